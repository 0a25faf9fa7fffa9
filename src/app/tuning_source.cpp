#include "app/tuning_source.hpp"

#include <fstream>
#include <nlohmann/json.hpp>

#include "core/paper_reference.hpp"

namespace epa::app {

core::Result<core::ModelFile> load_model(const std::string& path) {
  if (path.empty()) return core::ModelFile{core::paper::model(), "paper eq 9-10"};
  return core::read_model_file(path);
}

core::Result<ControllerPolynomials> load_controller_polynomials(const std::string& path) {
  if (path.empty()) return ControllerPolynomials{core::paper::F(), core::paper::G(), core::paper::G(), "paper eq 12-13"};
  std::ifstream in(path);
  if (!in) return core::io_error(path + ": cannot open design file");
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) return core::parse_error(path + ": not valid JSON");
  if (j.value("schema", "") != "epa-design/1") return core::parse_error(path + ": schema is not \"epa-design/1\"");
  ControllerPolynomials p;
  p.source = path;
  core::Polynomial* targets[] = {&p.F, &p.G, &p.H};
  const char* keys[] = {"F", "G", "H"};
  for (int i = 0; i < 3; ++i) {
    const auto it = j.find(keys[i]);
    if (it == j.end() || !it->is_array() || it->empty())
      return core::parse_error(path + ": \"" + keys[i] + "\" must be a non-empty array of numbers");
    std::vector<double> c;
    for (const auto& v : *it) {
      if (!v.is_number()) return core::parse_error(path + ": \"" + keys[i] + "\" contains a value that is not a number");
      c.push_back(v.get<double>());
    }
    *targets[i] = core::Polynomial(std::move(c));
  }
  return p;
}

}  // namespace epa::app
