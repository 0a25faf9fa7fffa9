#include "store/axis_json.hpp"

#include <cstdint>
#include <nlohmann/json.hpp>
#include <span>
#include <string_view>
#include <vector>

namespace epa::store {

namespace {

constexpr std::string_view kAxisJsonKeys[] = {"axis_model", "identified_drive_v", "stick_slip", "stick_slip_spread"};

core::Error axis_json_error(const std::string& what, const std::string& field, const std::string& why) {
  return core::parse_error(what + ": axis_json: " + field + " " + why);
}

// Every key of `object` must be one of `allowed`; the first that is not is named.
core::Status axis_json_keys_known(const nlohmann::json& object, std::span<const std::string_view> allowed, const std::string& what,
                        const std::string& table) {
  for (const auto& [key, value] : object.items()) {
    bool known = false;
    for (const std::string_view a : allowed) known = known || key == a;
    if (known) continue;
    std::string names;
    for (const std::string_view a : allowed) names += (names.empty() ? "" : ", ") + std::string(a);
    return core::parse_error(what + ": axis_json: unknown key '" + table + key + "' (expected one of: " + names + ")");
  }
  return core::ok();
}

core::Result<double> axis_json_number(const nlohmann::json& object, std::string_view key, const std::string& what, const std::string& table) {
  const std::string field = table + std::string(key);
  const auto it = object.find(std::string(key));
  if (it == object.end()) return axis_json_error(what, field, "is missing");
  if (!it->is_number()) return axis_json_error(what, field, "must be a number");
  return it->get<double>();
}

core::Result<core::StickSlipParams> stick_slip_of_json(const nlohmann::json& j, const std::string& what) {
  if (!j.is_object()) return axis_json_error(what, "stick_slip", "must be an object");
  std::vector<std::string_view> keys{"delay_samples"};
  for (const auto& [key, member] : core::kStickSlipFields) keys.push_back(key);
  if (auto s = axis_json_keys_known(j, keys, what, "stick_slip."); !s) return s.error();
  core::StickSlipParams p;
  for (const auto& [key, member] : core::kStickSlipFields) {
    auto v = axis_json_number(j, key, what, "stick_slip.");
    if (!v) return v.error();
    p.*member = *v;
  }
  const auto delay = j.find("delay_samples");
  if (delay == j.end()) return axis_json_error(what, "stick_slip.delay_samples", "is missing");
  if (!delay->is_number_integer()) return axis_json_error(what, "stick_slip.delay_samples", "must be a whole number of samples");
  const auto samples = delay->get<std::int64_t>();
  if (samples < 0 || samples > core::StickSlipParams::kMaxDelay)
    return axis_json_error(what, "stick_slip.delay_samples", "is outside 0.." + std::to_string(core::StickSlipParams::kMaxDelay));
  p.delay_samples = static_cast<int>(samples);
  return p;
}

core::Result<core::StickSlipSpread> spread_of_json(const nlohmann::json& j, const std::string& what) {
  if (!j.is_object()) return axis_json_error(what, "stick_slip_spread", "must be an object");
  std::vector<std::string_view> keys;
  for (const auto& [key, member] : core::kStickSlipSpreadFields) keys.push_back(key);
  if (auto s = axis_json_keys_known(j, keys, what, "stick_slip_spread."); !s) return s.error();
  core::StickSlipSpread spread;
  for (const auto& [key, member] : core::kStickSlipSpreadFields) {
    auto v = axis_json_number(j, key, what, "stick_slip_spread.");
    if (!v) return v.error();
    spread.*member = *v;
  }
  return spread;
}

core::Result<std::array<double, 2>> drive_of_json(const nlohmann::json& j, const std::string& what) {
  if (!j.is_array() || j.size() != 2 || !j[0].is_number() || !j[1].is_number())
    return axis_json_error(what, "identified_drive_v", "must be [lowest, highest], two numbers");
  return std::array<double, 2>{j[0].get<double>(), j[1].get<double>()};
}

}  // namespace

std::string axis_json_text(const ModelRecord& r) {
  nlohmann::json j = nlohmann::json::object();
  // The verdict is written whenever there is a stick-slip model to judge: '{}' stays "nothing known".
  if (r.stick_slip || r.axis_model != core::AxisModel::kHammerstein) j["axis_model"] = std::string(core::to_string(r.axis_model));
  if (r.identified_drive_v) j["identified_drive_v"] = {(*r.identified_drive_v)[0], (*r.identified_drive_v)[1]};
  if (r.stick_slip) {
    nlohmann::json& t = j["stick_slip"] = nlohmann::json::object();
    for (const auto& [key, member] : core::kStickSlipFields) t[std::string(key)] = (*r.stick_slip).*member;
    t["delay_samples"] = r.stick_slip->delay_samples;
  }
  if (r.stick_slip_spread) {
    nlohmann::json& t = j["stick_slip_spread"] = nlohmann::json::object();
    for (const auto& [key, member] : core::kStickSlipSpreadFields) t[std::string(key)] = (*r.stick_slip_spread).*member;
  }
  return j.dump();
}

core::Status read_axis_json(const std::string& text, const std::string& what, ModelRecord& r) {
  const auto j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return core::parse_error(what + ": axis_json is not a JSON object: " + text);
  if (auto s = axis_json_keys_known(j, kAxisJsonKeys, what, ""); !s) return s;
  ModelRecord read;  // the four fields, kept apart until all of them are good
  if (const auto it = j.find("axis_model"); it != j.end()) {
    const auto axis = it->is_string() ? core::parse_axis_model(it->get<std::string>()) : std::nullopt;
    if (!axis) return axis_json_error(what, "axis_model", "must be \"hammerstein\" or \"stick-slip\"");
    read.axis_model = *axis;
  }
  if (const auto it = j.find("identified_drive_v"); it != j.end()) {
    auto drive = drive_of_json(*it, what);
    if (!drive) return drive.error();
    read.identified_drive_v = *drive;
  }
  if (const auto it = j.find("stick_slip"); it != j.end()) {
    auto params = stick_slip_of_json(*it, what);
    if (!params) return params.error();
    read.stick_slip = *params;
  }
  if (const auto it = j.find("stick_slip_spread"); it != j.end()) {
    auto spread = spread_of_json(*it, what);
    if (!spread) return spread.error();
    read.stick_slip_spread = *spread;
  }
  if (auto s = check_axis_fields(read); !s) return core::parse_error(what + ": axis_json: " + s.error().message);
  r.axis_model = read.axis_model;
  r.identified_drive_v = read.identified_drive_v;
  r.stick_slip = read.stick_slip;
  r.stick_slip_spread = read.stick_slip_spread;
  return core::ok();
}

core::Status check_axis_fields(const ModelRecord& r) {
  if (r.identified_drive_v && !core::identified_drive_v_valid(*r.identified_drive_v))
    return core::invalid_argument("identified_drive_v must be [lowest, highest] valve command in V, within [-10, 0] and [0, 10]");
  if (r.stick_slip)
    if (auto s = r.stick_slip->validate(); !s) return core::invalid_argument("stick_slip: " + s.error().message);
  if (r.stick_slip_spread) {
    if (!r.stick_slip) return core::invalid_argument("stick_slip_spread needs a stick_slip model");
    if (auto s = r.stick_slip_spread->validate(); !s) return core::invalid_argument("stick_slip_spread: " + s.error().message);
  }
  if (r.axis_model == core::AxisModel::kStickSlip && !r.stick_slip)
    return core::invalid_argument("axis_model \"stick-slip\" needs a stick_slip model");
  return core::ok();
}

}  // namespace epa::store
