#include "store/tuning_file.hpp"

#include <cmath>
#include <sstream>
#include <string_view>
#include <toml++/toml.h>

#include "core/coefficient_cap.hpp"
#include "core/format.hpp"
#include "core/model_file.hpp"
#include "core/printable_name.hpp"
#include "core/toml_document.hpp"
#include "core/toml_keys.hpp"
#include "core/toml_number.hpp"

namespace epa::store {

namespace {

// Every number of a tuning file is bounded (the set's own validation then checks each meaning).
constexpr double kMaxMagnitude = 1e6;

constexpr const char* kSchema = "epa-tuning/1";
// Free text bounds: a source is a sentence (epa identify writes up to 640 characters), design and
// fit a one-line JSON object of a few figures and at most 64 coefficients per polynomial.
constexpr std::size_t kMaxSourceChars = 1024;
constexpr std::size_t kMaxJsonTextChars = 16384;

std::string quoted(const std::string& s) {
  std::ostringstream out;
  out << toml::value<std::string>(s);  // TOML string escaping by the library
  return out.str();
}

core::Result<double> number(const toml::table& t, const char* key, const std::string& where) {
  const auto* node = t.get(key);
  if (!node) return core::parse_error(where + " " + key + " is missing");
  if (auto v = node->value<double>()) {
    if (std::isfinite(*v) && std::abs(*v) <= kMaxMagnitude) return *v;
    return core::parse_error(where + " " + key + " " + core::format_number(*v) + " is outside [-1e6, 1e6] (line " +
                             std::to_string(node->source().begin.line) + ")");
  }
  return core::parse_error(where + " " + key + " must be a number");
}

core::Result<core::Polynomial> polynomial(const toml::table& t, const char* key, const std::string& where) {
  const auto* arr = t.get_as<toml::array>(key);
  if (!arr) return core::parse_error(where + " " + key + " is missing or not an array of numbers");
  if (auto s = core::check_coefficient_count(arr->size(), where + " " + key); !s) return s.error();
  std::vector<double> c;
  for (std::size_t i = 0; i < arr->size(); ++i) {
    auto v = arr->get(i)->value<double>();
    if (!v) return core::parse_error(where + " " + key + "[" + std::to_string(i) + "] is not a number");
    if (!std::isfinite(*v) || std::abs(*v) > kMaxMagnitude)
      return core::parse_error(where + " " + key + "[" + std::to_string(i) + "] " + core::format_number(*v) + " is outside [-1e6, 1e6]");
    c.push_back(*v);
  }
  return core::Polynomial(std::move(c));
}

// The free text of a file reaches the log, the store and `epa tuning list`: one printable line
// each (core/printable_name.hpp), so a name cannot forge a line there. `table` prefixes the keys.
core::Status free_text_fits(const std::string& src, const std::string& name, const std::string& source,
                            const std::string& json_text, const std::string& table) {
  const std::string where = src + ": " + table;
  if (auto s = core::check_printable_name(name, where + "name"); !s) return s;
  if (auto s = core::check_printable_text(source, where + "source", kMaxSourceChars); !s) return s;
  return core::check_printable_text(json_text, where + (table.empty() ? "design" : "fit"), kMaxJsonTextChars);
}

}  // namespace

std::string format_tuning_toml(const TuningSet& t, const ModelRecord& m) {
  using core::toml_float;
  using core::toml_float_array;
  std::string s = "schema = \"" + std::string(kSchema) + "\"\n";
  s += "name = " + quoted(t.name) + "\nsource = " + quoted(t.source) + "\n";
  s += "controller = \"" + std::string(control::to_string(t.controller)) + "\"\n";
  s += "lc_mm = " + toml_float(t.lc_mm) + "\nvalve_limit_v = " + toml_float(t.valve_limit_v) + "\n";
  s += "design = " + quoted(t.design_json) + "\n";
  s += "\n[rst]\nF = " + toml_float_array(t.F.coefficients()) + "\nG = " + toml_float_array(t.G.coefficients()) +
       "\nH = " + toml_float_array(t.H.coefficients()) + "\n";
  s += "\n" + core::format_dead_zone_table(t.dead_zone);
  s += "\n[trajectory]  # pp-traj's parameters (docs/paper.md, \"Beyond the paper: pp-traj\")\n";
  for (const auto& [key, value] : trajectory_setting_values(t.trajectory)) s += key + " = " + toml_float(value) + "\n";
  // The model section is the model file's own text, moved under [model].
  std::string model_text = core::format_model_toml(model_file_of(m));
  model_text = model_text.substr(model_text.find('\n') + 1);  // drop its schema line
  std::string nested;
  std::istringstream lines(model_text);
  for (std::string line; std::getline(lines, line);)
    nested += (line.size() > 1 && line.front() == '[' ? "[model." + line.substr(1) : line) + "\n";
  s += "\n[model]\nname = " + quoted(m.name) + "\nfit = " + quoted(m.fit_json) + "\n" + nested;
  return s;
}

core::Result<TuningFile> parse_tuning_toml(const std::string& text, const std::string& src) {
  auto document = core::parse_toml_with_schema(text, src, kSchema);
  if (!document) return document.error();
  const toml::table& root = *document;
  if (auto s = core::only_keys(root, {"schema", "name", "source", "controller", "lc_mm", "valve_limit_v", "design", "rst", "dead_zone", "trajectory", "model"}, src); !s)
    return s.error();

  TuningFile f;
  TuningSet& t = f.set;
  t.name = root["name"].value_or(std::string());
  if (t.name.empty()) return core::parse_error(src + ": name is missing");
  t.source = root["source"].value_or(std::string());
  t.design_json = root["design"].value_or(std::string("{}"));
  if (auto s = free_text_fits(src, t.name, t.source, t.design_json, ""); !s) return s.error();
  auto kind = control::parse_controller_kind(root["controller"].value_or(std::string()));
  if (!kind) return core::parse_error(src + ": controller: " + kind.error().message);
  t.controller = *kind;
  auto lc = number(root, "lc_mm", src + ":");
  if (!lc) return lc.error();
  t.lc_mm = *lc;
  auto limit = number(root, "valve_limit_v", src + ":");
  if (!limit) return limit.error();
  t.valve_limit_v = *limit;

  const auto* rst = root["rst"].as_table();
  if (!rst) return core::parse_error(src + ": table [rst] is missing");
  constexpr std::string_view rst_keys[] = {"F", "G", "H"};
  if (auto s = core::only_keys(*rst, rst_keys, src, "rst"); !s) return s.error();
  core::Polynomial* polys[] = {&t.F, &t.G, &t.H};
  for (int i = 0; i < 3; ++i) {
    auto p = polynomial(*rst, rst_keys[i].data(), src + ": [rst]");  // literals: terminated
    if (!p) return p.error();
    *polys[i] = *p;
  }
  const auto* dz = root["dead_zone"].as_table();
  if (!dz) return core::parse_error(src + ": table [dead_zone] is missing");
  if (auto s = core::only_keys(*dz, core::kDeadZoneKeys, src, "dead_zone"); !s) return s.error();
  for (std::size_t i = 0; i < std::size(core::kDeadZoneKeys); ++i) {
    auto v = number(*dz, core::kDeadZoneKeys[i].data(), src + ": [dead_zone]");  // literals: terminated
    if (!v) return v.error();
    t.dead_zone.*core::kDeadZoneMembers[i] = *v;
  }

  if (const auto* trajectory = root["trajectory"].as_table()) {  // optional: files from before pp-traj have none
    for (const auto& [key, node] : *trajectory) {
      const std::string name(key.str());
      auto v = number(*trajectory, name.c_str(), src + ": [trajectory]");
      if (!v) return v.error();
      if (!set_trajectory_setting(t.trajectory, name, *v))
        return core::unknown_key(src, node.source(), name, "trajectory", trajectory_setting_keys());
    }
  }

  const auto* model = root["model"].as_table();
  if (!model) return core::parse_error(src + ": table [model] is missing");
  if (auto s = core::only_keys(*model, {"name", "fit", "source", "Ts", "mm_per_volt", "axis_model", "identified_drive_v", "arx", "dead_zone",
                                        "stick_slip", "stick_slip_spread"},
                               src, "model");
      !s)
    return s.error();
  f.model.name = (*model)["name"].value_or(std::string());
  if (f.model.name.empty()) return core::parse_error(src + ": [model] name is missing");
  f.model.fit_json = (*model)["fit"].value_or(std::string("{}"));
  if (auto s = free_text_fits(src, f.model.name, "", f.model.fit_json, "[model] "); !s) return s.error();
  // The rest of [model] is an epa-model/1 document: read it with the model file's own reader.
  toml::table model_doc = *model;
  model_doc.erase("name");
  model_doc.erase("fit");
  model_doc.insert_or_assign("schema", "epa-model/1");
  std::ostringstream doc;
  doc << model_doc;
  auto parsed = core::parse_model_toml(doc.str(), src + " [model]");
  if (!parsed) return parsed.error();
  f.model = model_record_of(*parsed, f.model.name, f.model.fit_json);

  if (auto s = validate(t, f.model.model); !s) return core::invalid_argument(src + ": " + s.error().message);
  return f;
}

}  // namespace epa::store
