#include "appliance/tuning_source.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "core/coefficient_cap.hpp"
#include "core/paper_reference.hpp"
#include "core/strict_json.hpp"
#include "core/text_file.hpp"

namespace epa::appliance {

core::Result<core::ModelFile> load_model(const std::string& path) {
  if (path.empty()) return core::ModelFile{core::paper::model(), "paper eq 9-10"};
  return core::read_model_file(path);
}

core::Result<ControllerPolynomials> load_controller_polynomials(const std::string& path) {
  if (path.empty()) return ControllerPolynomials{core::paper::F(), core::paper::G(), core::paper::G(), "paper eq 12-13"};
  auto text = core::read_text_file(path, "design file", core::kSmallFileCapBytes);
  if (!text) return text.error();
  auto parsed = core::parse_strict_json(*text, path);
  if (!parsed) return parsed.error();
  const nlohmann::json& j = *parsed;
  if (const auto schema = j.find("schema"); schema == j.end() || *schema != "epa-design/1") return core::parse_error(path + ": schema is not \"epa-design/1\"");
  ControllerPolynomials p;
  p.source = path;
  core::Polynomial* targets[] = {&p.F, &p.G, &p.H};
  const char* keys[] = {"F", "G", "H"};
  for (int i = 0; i < 3; ++i) {
    const auto it = j.find(keys[i]);
    if (it == j.end() || !it->is_array() || it->empty())
      return core::parse_error(path + ": \"" + keys[i] + "\" must be a non-empty array of numbers");
    if (auto s = core::check_coefficient_count(it->size(), path + ": \"" + keys[i] + "\""); !s) return s.error();
    std::vector<double> c;
    for (const auto& v : *it) {
      if (!v.is_number() || !std::isfinite(v.get<double>()))
        return core::parse_error(path + ": \"" + keys[i] + "\" contains a value that is not a finite number");
      c.push_back(v.get<double>());
    }
    *targets[i] = core::Polynomial(std::move(c));
  }
  return p;
}

}  // namespace epa::appliance
