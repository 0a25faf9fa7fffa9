#include "web/command_validation.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "runtime/mode.hpp"

namespace epa::web {

namespace {

CommandDecision refuse(int status, std::string message) {
  CommandDecision d;
  d.status = status;
  d.error = std::move(message);
  return d;
}

std::string number_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

}  // namespace

CommandDecision validate_command(CommandEndpoint endpoint, const std::string& body, const runtime::Snapshot& snap,
                                 const runtime::RuntimeConfig& limits) {
  nlohmann::json j = nlohmann::json::object();
  if (!body.empty()) {
    j = nlohmann::json::parse(body, nullptr, /*allow_exceptions=*/false);
    if (j.is_discarded()) return refuse(400, "the request body is not valid JSON");
  }
  if (!j.is_object()) return refuse(400, "the request body must be a JSON object");
  const char* key = endpoint == CommandEndpoint::kSetpoint ? "setpoint_mm" : endpoint == CommandEndpoint::kMode ? "mode" : "";
  for (const auto& [k, v] : j.items())
    if (k != key) return refuse(400, "unknown field '" + k + "'" + (*key ? std::string(" (expected '") + key + "')" : std::string(" (reset takes {})")));

  CommandDecision d;
  switch (endpoint) {
    case CommandEndpoint::kSetpoint: {
      if (!j.contains(key) || !j[key].is_number()) return refuse(400, "setpoint_mm must be a number, e.g. {\"setpoint_mm\": 120}");
      const double mm = j[key].get<double>();
      if (!std::isfinite(mm) || mm < limits.setpoint_min_mm || mm > limits.setpoint_max_mm)
        return refuse(400, "setpoint_mm " + number_text(mm) + " is outside [" + number_text(limits.setpoint_min_mm) + ", " +
                               number_text(limits.setpoint_max_mm) + "] mm");
      d.commands.push_back(runtime::setpoint_command(mm));
      d.changes.push_back({"setpoint_mm", snap.setpoint_mm, mm});
      break;
    }
    case CommandEndpoint::kMode: {
      if (!j.contains(key) || !j[key].is_string()) return refuse(400, "mode must be one of \"stop\", \"run\", \"manual\"");
      auto m = runtime::parse_mode(j[key].get<std::string>());
      if (!m || *m == runtime::Mode::kFault) return refuse(400, "mode must be one of \"stop\", \"run\", \"manual\"");
      if (snap.mode == runtime::Mode::kFault)
        return refuse(409, "a fault is latched (" + std::string(runtime::to_string(snap.fault)) + "): reset it before changing the mode");
      d.commands.push_back(runtime::mode_command(*m));
      d.changes.push_back({"mode", static_cast<double>(snap.mode), static_cast<double>(*m)});
      break;
    }
    case CommandEndpoint::kReset:
      d.commands.push_back(runtime::reset_command());
      d.changes.push_back({"reset", 0.0, 1.0});
      break;
  }
  return d;
}

}  // namespace epa::web
