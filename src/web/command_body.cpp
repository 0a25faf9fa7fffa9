#include "web/command_body.hpp"

#include <cmath>
#include <nlohmann/json.hpp>
#include <utility>

#include "control/controller_kind.hpp"
#include "core/format.hpp"
#include "core/strict_json.hpp"
#include "core/tiny_number.hpp"
#include "points/point_catalog.hpp"
#include "points/record_controller.hpp"
#include "runtime/mode.hpp"
#include "web/json_api.hpp"

namespace epa::web {

namespace {

using nlohmann::json;
using P = points::PointId;
using points::RecordField;

CommandBody malformed(std::string message) { return {std::move(message), {}}; }

// One point's value from JSON: a number, a boolean (1/0), or for mode and controller their name.
std::optional<double> value_of(P id, const json& v, std::string& error) {
  const std::string point(points::name(id));
  if (v.is_number()) {
    // Refused as Modbus refuses them (core/tiny_number.hpp): no interface takes a value the other refuses.
    const double number = v.get<double>();
    if (std::isfinite(number) && !core::is_tiny_number(number)) return number;
    error = point + " " + core::format_number(number) + " is not a usable number (non-zero values below 1.2e-38 and non-finite ones are refused)";
    return std::nullopt;
  }
  if (v.is_boolean()) return v.get<bool>() ? 1.0 : 0.0;
  if (v.is_string() && id == P::kMode) {
    auto m = runtime::parse_mode(v.get<std::string>());
    if (m && *m != runtime::Mode::kFault) return static_cast<double>(*m);
    error = point + " must be one of \"stop\", \"run\", \"manual\", \"excite\"";
    return std::nullopt;
  }
  if (v.is_string() && id == P::kController) {
    auto c = control::parse_controller_kind(v.get<std::string>());
    if (c) return static_cast<double>(*c);
    error = point + ": " + c.error().message;
    return std::nullopt;
  }
  RecordField field;
  if (v.is_string() && record_field(id, field) && field.kind == RecordField::kController) {
    auto c = points::parse_record_controller(v.get<std::string>());
    if (c) return static_cast<double>(*c);
    error = point + ": " + c.error().message;
    return std::nullopt;
  }
  if (v.is_string() && record_field(id, field) && field.kind == RecordField::kApproach) {
    auto a = points::parse_record_approach(v.get<std::string>());
    if (a) return static_cast<double>(*a);
    error = point + ": " + a.error().message;
    return std::nullopt;
  }
  error = point + " must be a number";
  return std::nullopt;
}

// POST /api/records: the record's number, then its fields as the record<N>_* points.
CommandBody record_body(const json& j) {
  using K = RecordKeys;
  constexpr std::pair<const char*, P> kFields[] = {{K::kTarget, P::kRecordTarget0}, {K::kSpeed, P::kRecordSpeed0},
                                                   {K::kWindow, P::kRecordWindow0}, {K::kController, P::kRecordController0},
                                                   {K::kApproach, P::kRecordApproach0}};
  const std::string range = "1.." + std::to_string(points::kPositionRecords);
  const auto number = j.find(K::kRecord);
  if (number == j.end()) return malformed("name the record: {\"record\": " + range + ", \"target_mm\": ...}");
  if (!number->is_number_integer() || number->get<std::int64_t>() < 1 ||
      number->get<std::int64_t>() > static_cast<std::int64_t>(points::kPositionRecords))
    return malformed("record must be a whole number " + range + ", not " + number->dump());
  const auto i = static_cast<std::size_t>(number->get<std::int64_t>() - 1);
  CommandBody out;
  for (const auto& [k, v] : j.items()) {
    if (k == K::kRecord) continue;
    const std::pair<const char*, P>* f = nullptr;
    for (const auto& field : kFields)
      if (k == field.first) f = &field;
    if (!f) return malformed("unknown field '" + k + "' (a record has target_mm, speed_mm_s, window_mm, controller, approach)");
    const P id = points::indexed_id(f->second, i);
    std::string error;
    auto value = value_of(id, v, error);
    if (!value) return malformed(error);
    out.writes.push_back({id, *value});
  }
  if (out.writes.empty()) return malformed("give at least one of target_mm, speed_mm_s, window_mm, controller, approach for record " + std::to_string(i + 1));
  return out;
}

}  // namespace

CommandBody parse_command_body(CommandEndpoint endpoint, const std::string& body) {
  json j = json::object();
  if (!body.empty()) {
    // Strict: valid UTF-8, each key once, bounded depth (core/strict_json.hpp), in words of ours.
    auto parsed = core::parse_strict_json(body, "the request body");
    if (!parsed) return malformed(parsed.error().message);
    j = std::move(*parsed);
  }
  if (!j.is_object()) return malformed("the request body must be a JSON object");

  if (endpoint == CommandEndpoint::kReset) {
    if (!j.empty()) return malformed("unknown field '" + j.begin().key() + "' (reset takes {})");
    return {"", {{P::kReset, 1.0}}};
  }
  if (endpoint == CommandEndpoint::kSetpoint || endpoint == CommandEndpoint::kMode) {
    const P id = endpoint == CommandEndpoint::kSetpoint ? P::kSetpoint : P::kMode;
    const std::string key(points::name(id));
    for (const auto& [k, v] : j.items())
      if (k != key) return malformed("unknown field '" + k + "' (expected '" + key + "')");
    if (!j.contains(key))
      return malformed(id == P::kSetpoint ? key + " must be a number, e.g. {\"" + key + "\": 120}"
                                          : key + " must be one of \"stop\", \"run\", \"manual\", \"excite\"");
    std::string error;
    if (id == P::kMode && !j[key].is_string()) return malformed(key + " must be one of \"stop\", \"run\", \"manual\", \"excite\"");
    if (id == P::kSetpoint && !j[key].is_number()) return malformed(key + " must be a number, e.g. {\"" + key + "\": 120}");
    auto v = value_of(id, j[key], error);
    if (!v) return malformed(error);
    return {"", {{id, *v}}};
  }
  if (endpoint == CommandEndpoint::kRecord) return record_body(j);
  // /api/points: any writable points, one group.
  if (j.empty()) return malformed("name at least one point, e.g. {\"" + std::string(points::name(P::kSetpoint)) + "\": 120}");
  CommandBody out;
  for (const auto& [k, v] : j.items()) {
    const points::PointDef* p = points::find_point(k);
    if (!p) return malformed("unknown point '" + k + "' (GET /api/points lists them)");
    std::string error;
    auto value = value_of(p->id, v, error);
    if (!value) return malformed(error);
    out.writes.push_back({p->id, *value});
  }
  return out;
}

}  // namespace epa::web
