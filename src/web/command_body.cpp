#include "web/command_body.hpp"

#include <nlohmann/json.hpp>

#include "control/controller_kind.hpp"
#include "points/point_catalog.hpp"
#include "runtime/mode.hpp"

namespace epa::web {

namespace {

using nlohmann::json;
using P = points::PointId;

CommandBody malformed(std::string message) { return {std::move(message), {}}; }

// One point's value from JSON: a number, a boolean (1/0), or for mode and controller their name.
std::optional<double> value_of(P id, const json& v, std::string& error) {
  const std::string point(points::name(id));
  if (v.is_number()) return v.get<double>();
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
  error = point + " must be a number";
  return std::nullopt;
}

}  // namespace

CommandBody parse_command_body(CommandEndpoint endpoint, const std::string& body) {
  json j = json::object();
  if (!body.empty()) {
    j = json::parse(body, nullptr, /*allow_exceptions=*/false);
    if (j.is_discarded()) return malformed("the request body is not valid JSON");
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
