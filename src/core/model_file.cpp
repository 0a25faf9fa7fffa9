#include "core/model_file.hpp"

#include <charconv>
#include <cstdint>
#include <cmath>
#include <sstream>
#include <string_view>
#include <vector>
#include <toml++/toml.h>

#include "core/atomic_file.hpp"
#include "core/coefficient_cap.hpp"
#include "core/format.hpp"
#include "core/printable_name.hpp"
#include "core/text_file.hpp"
#include "core/toml_document.hpp"
#include "core/toml_keys.hpp"
#include "core/toml_number.hpp"

namespace epa::core {

namespace {

constexpr const char* kSchema = "epa-model/1";
// Every number of a model file is bounded: nothing physical in it comes near, and 1e300 or NaN
// would only overflow later (the model's own validation then checks each value's meaning).
constexpr double kMaxMagnitude = 1e6;
constexpr std::size_t kMaxModelSourceChars = 1024;  // a sentence: epa identify writes up to 640 characters

Result<double> number_at(const toml::table& t, const char* table_name, const char* key, const std::string& src) {
  const auto* node = t.get(key);
  const std::string where = src + ": " + (table_name[0] ? std::string("[") + table_name + "] " : std::string()) + key;
  if (!node) return parse_error(where + " is missing");
  if (auto v = node->value<double>()) {
    if (std::isfinite(*v) && std::abs(*v) <= kMaxMagnitude) return *v;
    return parse_error(where + " " + format_number(*v) + " is outside [-1e6, 1e6] (line " + std::to_string(node->source().begin.line) + ")");
  }
  return parse_error(where + " must be a number");
}

Result<Polynomial> array_at(const toml::table& t, const char* key, const std::string& src) {
  const auto* arr = t.get_as<toml::array>(key);
  if (!arr) return parse_error(src + ": [arx] " + key + " is missing or not an array of numbers");
  if (auto s = check_coefficient_count(arr->size(), src + ": [arx] " + key); !s) return s.error();
  std::vector<double> c;
  for (std::size_t i = 0; i < arr->size(); ++i) {
    auto v = arr->get(i)->value<double>();
    if (!v) return parse_error(src + ": [arx] " + key + "[" + std::to_string(i) + "] is not a number");
    if (!std::isfinite(*v) || std::abs(*v) > kMaxMagnitude)
      return parse_error(src + ": [arx] " + key + "[" + std::to_string(i) + "] " + format_number(*v) + " is outside [-1e6, 1e6] (line " +
                         std::to_string(arr->get(i)->source().begin.line) + ")");
    c.push_back(*v);
  }
  return Polynomial(std::move(c));
}

// The [stick_slip] table: every field, by its name (a reader that knows the table wants it whole).
Result<StickSlipParams> stick_slip_at(const toml::table& t, const std::string& src) {
  StickSlipParams p;
  std::vector<std::string_view> keys{"delay_samples"};  // the table's keys: the fields and the delay
  for (const auto& [key, member] : kStickSlipFields) keys.push_back(key);
  if (auto s = only_keys(t, keys, src, "stick_slip"); !s) return s.error();
  for (const auto& [key, member] : kStickSlipFields) {
    auto v = number_at(t, "stick_slip", key.data(), src);  // literals: terminated
    if (!v) return v.error();
    p.*member = *v;
  }
  const auto* delay = t.get("delay_samples");
  if (!delay) return parse_error(src + ": [stick_slip] delay_samples is missing");
  const auto whole = delay->value<std::int64_t>();
  if (!whole || !delay->is_integer())
    return parse_error(src + ": [stick_slip] delay_samples must be a whole number of samples");
  if (*whole < 0 || *whole > StickSlipParams::kMaxDelay)
    return parse_error(src + ": [stick_slip] delay_samples " + std::to_string(*whole) + " is outside 0.." +
                       std::to_string(StickSlipParams::kMaxDelay));
  p.delay_samples = static_cast<int>(*whole);
  if (auto s = p.validate(); !s) return invalid_argument(src + ": [stick_slip] " + s.error().message);
  return p;
}

// The [stick_slip_spread] table: every field, by its name.
Result<StickSlipSpread> stick_slip_spread_at(const toml::table& t, const std::string& src) {
  StickSlipSpread s;
  std::vector<std::string_view> keys;
  for (const auto& [key, member] : kStickSlipSpreadFields) keys.push_back(key);
  if (auto st = only_keys(t, keys, src, "stick_slip_spread"); !st) return st.error();
  for (const auto& [key, member] : kStickSlipSpreadFields) {
    auto v = number_at(t, "stick_slip_spread", key.data(), src);  // literals: terminated
    if (!v) return v.error();
    s.*member = *v;
  }
  if (auto st = s.validate(); !st) return invalid_argument(src + ": [stick_slip_spread] " + st.error().message);
  return s;
}

}  // namespace

Result<ModelFile> parse_model_toml(const std::string& text, const std::string& src) {
  auto document = parse_toml_with_schema(text, src, kSchema);
  if (!document) return document.error();
  const toml::table& root = *document;

  if (auto s = only_keys(root, {"schema", "Ts", "mm_per_volt", "source", "axis_model", "identified_drive_v", "arx", "dead_zone", "stick_slip",
                          "stick_slip_spread"},
                         src);
      !s)
    return s.error();
  ModelFile f;
  auto Ts = number_at(root, "", "Ts", src);
  if (!Ts) return Ts.error();
  f.model.Ts = *Ts;
  if (root.contains("mm_per_volt")) {
    auto s = number_at(root, "", "mm_per_volt", src);
    if (!s) return s.error();
    f.model.mm_per_volt = *s;
  }
  f.source = root["source"].value_or(std::string());
  // Free text that `epa design` prints and the store keeps: one printable line (core/printable_name.hpp).
  if (auto s = check_printable_text(f.source, src + ": source", kMaxModelSourceChars); !s) return s.error();

  const auto* arx = root["arx"].as_table();
  if (!arx) return parse_error(src + ": table [arx] is missing");
  if (auto s = only_keys(*arx, {"A", "B"}, src, "arx"); !s) return s.error();
  auto A = array_at(*arx, "A", src);
  if (!A) return A.error();
  auto B = array_at(*arx, "B", src);
  if (!B) return B.error();
  f.model.A = *A;
  f.model.B = *B;

  const auto* dz = root["dead_zone"].as_table();
  if (!dz) return parse_error(src + ": table [dead_zone] is missing");
  if (auto s = only_keys(*dz, kDeadZoneKeys, src, "dead_zone"); !s) return s.error();
  for (std::size_t i = 0; i < std::size(kDeadZoneKeys); ++i) {
    auto v = number_at(*dz, "dead_zone", kDeadZoneKeys[i].data(), src);  // literals: terminated
    if (!v) return v.error();
    f.model.dead_zone.*kDeadZoneMembers[i] = *v;
  }
  if (auto s = f.model.validate(); !s) return invalid_argument(src + ": " + s.error().message);
  if (root.contains("stick_slip")) {
    const auto* ss = root["stick_slip"].as_table();
    if (!ss) return parse_error(src + ": stick_slip must be a table");
    auto params = stick_slip_at(*ss, src);
    if (!params) return params.error();
    f.stick_slip = *params;
  }
  if (root.contains("stick_slip_spread")) {
    const auto* t = root["stick_slip_spread"].as_table();
    if (!t) return parse_error(src + ": stick_slip_spread must be a table");
    if (!f.stick_slip) return parse_error(src + ": [stick_slip_spread] needs a [stick_slip] table");
    auto spread = stick_slip_spread_at(*t, src);
    if (!spread) return spread.error();
    f.stick_slip_spread = *spread;
  }
  if (root.contains("identified_drive_v")) {
    auto range = array_at(root, "identified_drive_v", src);
    if (!range) return range.error();
    const auto& v = range->coefficients();
    if (v.size() != 2 || !identified_drive_v_valid({v[0], v[1]}))
      return parse_error(src + ": identified_drive_v must be [lowest, highest] valve command in V, within [-10, 0] and [0, 10]");
    f.identified_drive_v = std::array<double, 2>{v[0], v[1]};
  }
  if (root.contains("axis_model")) {
    const auto axis = parse_axis_model(root["axis_model"].value<std::string>().value_or(""));
    if (!axis) return parse_error(src + ": axis_model must be \"hammerstein\" or \"stick-slip\"");
    if (*axis == AxisModel::kStickSlip && !f.stick_slip)
      return parse_error(src + ": axis_model = \"stick-slip\" needs a [stick_slip] table");
    f.axis_model = *axis;
  }
  return f;
}

std::string_view to_string(AxisModel axis_model) { return axis_model == AxisModel::kStickSlip ? "stick-slip" : "hammerstein"; }

std::optional<AxisModel> parse_axis_model(std::string_view name) {
  if (name == "hammerstein") return AxisModel::kHammerstein;
  if (name == "stick-slip") return AxisModel::kStickSlip;
  return std::nullopt;
}

Result<ModelFile> read_model_file(const std::string& path) {
  auto text = read_text_file(path, "model file", kSmallFileCapBytes);
  if (!text) return text.error();
  return parse_model_toml(*text, path);
}

namespace {

std::string format_stick_slip(const StickSlipParams& p) {
  std::string table = "\n[stick_slip]\n";
  for (const auto& [key, member] : kStickSlipFields) table += std::string(key) + " = " + toml_float(p.*member) + "\n";
  return table + "delay_samples = " + std::to_string(p.delay_samples) + "\n";
}

std::string format_stick_slip_spread(const StickSlipSpread& s) {
  std::string table = "\n[stick_slip_spread]\n";
  for (const auto& [key, member] : kStickSlipSpreadFields) table += std::string(key) + " = " + toml_float(s.*member) + "\n";
  return table;
}

}  // namespace

std::string format_dead_zone_table(const DeadZone& dead_zone) {
  std::string table = "[dead_zone]\n";
  for (std::size_t i = 0; i < std::size(kDeadZoneKeys); ++i)
    table += std::string(kDeadZoneKeys[i]) + " = " + toml_float(dead_zone.*kDeadZoneMembers[i]) + "\n";
  return table;
}

std::string format_model_toml(const ModelFile& f) {
  auto num = [](double v) { return toml_float(v); };
  auto list = [](const Polynomial& p) { return toml_float_array(p.coefficients()); };
  const auto& m = f.model;
  std::ostringstream source;
  source << toml::value<std::string>(f.source);  // TOML string escaping by the library
  return "schema = \"" + std::string(kSchema) + "\"\nTs = " + num(m.Ts) + "\nmm_per_volt = " + num(m.mm_per_volt) +
         "\nsource = " + source.str() + "\n" +
         (f.axis_model == AxisModel::kStickSlip ? "axis_model = \"stick-slip\"\n" : "") +
         (f.identified_drive_v ? "identified_drive_v = " + toml_float_array(std::vector<double>(f.identified_drive_v->begin(), f.identified_drive_v->end())) + "\n"
                               : std::string()) +
         "\n[arx]\nA = " + list(m.A) + "\nB = " + list(m.B) +
         "\n\n" + format_dead_zone_table(m.dead_zone) + (f.stick_slip ? format_stick_slip(*f.stick_slip) : std::string()) +
         (f.stick_slip && f.stick_slip_spread ? format_stick_slip_spread(*f.stick_slip_spread) : std::string());
}

Status write_model_file(const std::string& path, const ModelFile& file) {
  if (auto s = write_file_atomically(path, format_model_toml(file)); !s)
    return io_error(path + ": cannot write the model file: " + s.error().message);
  return ok();
}

}  // namespace epa::core
