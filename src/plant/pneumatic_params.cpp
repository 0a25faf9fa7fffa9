#include "plant/pneumatic_params.hpp"

#include "core/text_file.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <string_view>
#include <toml++/toml.h>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/format.hpp"
#include "core/toml_at_line.hpp"
#include "core/toml_document.hpp"
#include "core/toml_keys.hpp"

namespace epa::plant {

namespace {

constexpr const char* kSchema = "epa-pneumatic/1";

// One row per field: where it lives in the file and its physical range. The validator, the
// reader and the writer all walk this table, so a field cannot be known to one and not another.
struct Field {
  const char* table;
  const char* key;
  double PneumaticParams::*member;
  double min, max;
  bool min_open;  // range is (min, max] rather than [min, max]
};

constexpr std::array kFields{
    Field{"supply", "supply_pressure_bar", &PneumaticParams::supply_pressure_bar, 0.5, 16.0, false},
    Field{"supply", "atmospheric_pressure_bar", &PneumaticParams::atmospheric_pressure_bar, 0.5, 1.2, false},
    Field{"supply", "temperature_k", &PneumaticParams::temperature_k, 200.0, 400.0, false},
    Field{"cylinder", "bore_mm", &PneumaticParams::bore_mm, 5.0, 500.0, false},
    Field{"cylinder", "rod_mm", &PneumaticParams::rod_mm, 0.0, 400.0, false},
    Field{"cylinder", "stroke_mm", &PneumaticParams::stroke_mm, 10.0, 5000.0, false},
    Field{"cylinder", "dead_volume_a_cm3", &PneumaticParams::dead_volume_a_cm3, 0.1, 1e4, false},
    Field{"cylinder", "dead_volume_b_cm3", &PneumaticParams::dead_volume_b_cm3, 0.1, 1e4, false},
    Field{"cylinder", "piston_mass_kg", &PneumaticParams::piston_mass_kg, 0.01, 1000.0, false},
    Field{"cylinder", "polytropic_index", &PneumaticParams::polytropic_index, 1.0, 1.67, false},
    Field{"cylinder", "leak_a_mm2", &PneumaticParams::leak_a_mm2, 0.0, 100.0, false},
    Field{"cylinder", "leak_b_mm2", &PneumaticParams::leak_b_mm2, 0.0, 100.0, false},
    Field{"friction", "static_friction_n", &PneumaticParams::static_friction_n, 0.0, 1e5, false},
    Field{"friction", "coulomb_friction_n", &PneumaticParams::coulomb_friction_n, 0.0, 1e5, false},
    Field{"friction", "stribeck_velocity_mps", &PneumaticParams::stribeck_velocity_mps, 1e-4, 10.0, false},
    Field{"friction", "viscous_friction_n_per_mps", &PneumaticParams::viscous_friction_n_per_mps, 0.0, 1e5, false},
    Field{"friction", "lugre_stiffness_n_per_m", &PneumaticParams::lugre_stiffness_n_per_m, 0.0, 1e9, false},
    Field{"friction", "lugre_damping_n_s_per_m", &PneumaticParams::lugre_damping_n_s_per_m, 0.0, 1e6, false},
    Field{"valve", "orifice_area_mm2", &PneumaticParams::orifice_area_mm2, 0.0, 1000.0, true},
    Field{"valve", "discharge_coefficient", &PneumaticParams::discharge_coefficient, 0.0, 1.0, true},
    Field{"valve", "spool_time_constant_s", &PneumaticParams::spool_time_constant_s, 1e-4, 1.0, false},
    Field{"valve", "overlap_pos_v", &PneumaticParams::overlap_pos_v, 0.0, 9.0, false},
    Field{"valve", "overlap_neg_v", &PneumaticParams::overlap_neg_v, -9.0, 0.0, false},
};
constexpr std::array<const char*, 4> kTables{"supply", "cylinder", "friction", "valve"};

std::string name_of(const Field& f) { return std::string("[") + f.table + "] " + f.key; }

std::string range_of(const Field& f) {
  return std::string(f.min_open ? "(" : "[") + core::format_number(f.min) + ", " + core::format_number(f.max) + "]";
}

const Field* find_field(std::string_view table, std::string_view key) {
  for (const Field& f : kFields)
    if (table == f.table && key == f.key) return &f;
  return nullptr;
}

// Shortest text that reads back to the same double, always a TOML float.
std::string number_text(double v) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, res.ptr);
  if (s.find_first_of(".en") == std::string::npos) s += ".0";
  return s;
}

}  // namespace

core::Status PneumaticParams::validate() const {
  for (const Field& f : kFields) {
    const double v = this->*f.member;
    const bool above_min = f.min_open ? v > f.min : v >= f.min;
    if (!std::isfinite(v) || !above_min || !(v <= f.max))
      return core::invalid_argument("pneumatic plant: " + name_of(f) + " = " + core::format_number(v) +
                                    " is outside its range " + range_of(f));
  }
  if (!(rod_mm < bore_mm))
    return core::invalid_argument("pneumatic plant: [cylinder] rod_mm = " + core::format_number(rod_mm) +
                                  " must be smaller than bore_mm = " + core::format_number(bore_mm));
  if (!(coulomb_friction_n <= static_friction_n))
    return core::invalid_argument("pneumatic plant: [friction] coulomb_friction_n = " +
                                  core::format_number(coulomb_friction_n) + " must not exceed static_friction_n = " +
                                  core::format_number(static_friction_n));
  return core::ok();
}

core::Result<PneumaticParams> parse_pneumatic_toml(const std::string& text, const std::string& src) {
  auto document = core::parse_toml_with_schema(text, src, kSchema);
  if (!document) return document.error();
  const toml::table& root = *document;

  PneumaticParams p;
  for (const auto& [key, node] : root) {
    const std::string_view k = key.str();
    if (k == "schema" || k == "source") continue;
    const bool known_table = std::find(kTables.begin(), kTables.end(), k) != kTables.end();
    if (!known_table) {
      std::vector<std::string_view> expected{"schema", "source"};
      expected.insert(expected.end(), kTables.begin(), kTables.end());
      return core::unknown_key(src, key.source(), k, "", expected);
    }
    const toml::table* table = node.as_table();
    if (table == nullptr) return core::parse_error(core::at_line(src, key.source()) + "'" + std::string(k) + "' must be a table");
    for (const auto& [inner_key, value] : *table) {
      const Field* f = find_field(k, inner_key.str());
      if (f == nullptr) {
        std::vector<std::string_view> expected;
        for (const Field& field : kFields)
          if (k == field.table) expected.emplace_back(field.key);
        return core::unknown_key(src, inner_key.source(), inner_key.str(), k, expected);
      }
      const auto v = value.value<double>();  // integers are accepted as numbers too
      if (!v) return core::parse_error(core::at_line(src, value.source()) + name_of(*f) + " must be a number");
      p.*f->member = *v;
    }
  }
  if (auto s = p.validate(); !s) {
    // Point at the line of the offending key when the value came from the file.
    for (const Field& f : kFields) {
      if (s.error().message.find(name_of(f) + " ") == std::string::npos) continue;
      if (const toml::node* n = root.at_path(std::string(f.table) + "." + f.key).node())
        return core::invalid_argument(core::at_line(src, n->source()) + s.error().message);
    }
    return core::invalid_argument(src + ": " + s.error().message);
  }
  return p;
}

core::Status set_pneumatic_key(PneumaticParams& params, std::string_view key, double value) {
  const std::size_t dot = key.find('.');
  const std::string_view table = dot == std::string_view::npos ? std::string_view() : key.substr(0, dot);
  const std::string_view name = dot == std::string_view::npos ? key : key.substr(dot + 1);
  const Field* field = nullptr;
  for (const Field& f : kFields)
    if (name == f.key && (table.empty() || table == f.table)) field = &f;
  if (field == nullptr) {
    std::string known;
    for (const Field& f : kFields) known += (known.empty() ? "" : ", ") + std::string(f.key);
    return core::invalid_argument("pneumatic plant: unknown key '" + std::string(key) + "' (known: " + known + ")");
  }
  PneumaticParams next = params;
  next.*field->member = value;
  if (auto s = next.validate(); !s) return s;
  params = next;
  return core::ok();
}

core::Result<PneumaticParams> read_pneumatic_file(const std::string& path) {
  auto text = core::read_text_file(path, "pneumatic plant file", core::kSmallFileCapBytes);
  if (!text) return text.error();
  return parse_pneumatic_toml(*text, path);
}

std::string format_pneumatic_toml(const PneumaticParams& p) {
  std::string out = "schema = \"" + std::string(kSchema) + "\"\n";
  for (const char* table : kTables) {
    out += std::string("\n[") + table + "]\n";
    for (const Field& f : kFields)
      if (std::string_view(f.table) == table) out += std::string(f.key) + " = " + number_text(p.*f.member) + "\n";
  }
  return out;
}

core::Status write_pneumatic_file(const std::string& path, const PneumaticParams& p) {
  if (auto s = core::write_file_atomically(path, format_pneumatic_toml(p)); !s)
    return core::io_error(path + ": cannot write the pneumatic plant file: " + s.error().message);
  return core::ok();
}

}  // namespace epa::plant
