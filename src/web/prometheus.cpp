#include "web/prometheus.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "core/version.hpp"
#include "points/point_catalog.hpp"

namespace epa::web {

namespace {

// Prometheus wants base units in the name (promtool check metrics refuses microseconds): the
// catalog's unit, the name's suffix instead of it, and the factor to it.
struct BaseUnit {
  std::string_view catalog, suffix;
  double scale;
};
constexpr BaseUnit kBaseUnits[] = {{"mm", "meters", 1e-3}, {"V", "volts", 1.0}, {"s", "seconds", 1.0}, {"us", "seconds", 1e-6}};

class Writer {
 public:
  explicit Writer(const points::PointContext& ctx) : ctx_(ctx) {}

  // A point as the catalog defines it: its value, its description as help, its name with the
  // unit in base units (position_mm -> epa_position_meters, loop_wake_p99_us ->
  // epa_loop_wake_p99_seconds), and _total when it is a counter.
  void point(points::PointId id, const char* type = "gauge") {
    const auto& p = points::point(id);
    std::string name(p.name);
    double value = p.value(ctx_);
    for (const auto& u : kBaseUnits) {
      if (p.unit != u.catalog) continue;
      std::string tail = "_" + std::string(u.catalog);
      for (auto& c : tail) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      if (name.ends_with(tail)) name.erase(name.size() - tail.size());
      name += "_" + std::string(u.suffix);
      value *= u.scale;
    }
    if (std::string_view(type) == "counter") name += "_total";
    std::string help(p.description);
    help += ".";
    metric(("epa_" + name).c_str(), type, help.c_str(), value);
  }
  void metric(const char* name, const char* type, const char* help, double value, const std::string& labels = "") {
    out_ += "# HELP ";
    out_ += name;
    out_ += ' ';
    out_ += help;
    out_ += "\n# TYPE ";
    out_ += name;
    out_ += ' ';
    out_ += type;
    out_ += '\n';
    out_ += name;
    out_ += labels;
    out_ += ' ';
    out_ += number(value);
    out_ += '\n';
  }
  std::string take() { return std::move(out_); }

 private:
  static std::string number(double v) {
    if (std::isnan(v)) return "NaN";
    if (std::isinf(v)) return v > 0 ? "+Inf" : "-Inf";
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.15g", v);  // 2.485, not 2.4849999999999999
    if (std::strtod(buf, nullptr) != v) std::snprintf(buf, sizeof buf, "%.17g", v);  // unless it loses the value
    return buf;
  }
  const points::PointContext& ctx_;
  std::string out_;
};

}  // namespace

std::string prometheus_text(const runtime::Snapshot& s, const ModbusStats& modbus, std::uint64_t web_requests,
                            const points::HealthView& health) {
  points::InterfaceStatus server;  // what the points of the Modbus interface read
  server.requests = modbus.requests;
  server.clients = modbus.clients;
  server.health = health;
  const points::PointContext ctx{s, server};
  Writer w(ctx);
  using Id = points::PointId;  // not P: json_api.cpp has that at file scope, and a unity batch holds both
  w.metric("epa_build_info", "gauge", "The running epa's version (project VERSION in CMakeLists.txt), in the label; always 1.", 1.0,
           "{version=\"" + std::string(core::kVersion) + "\"}");
  for (const Id id : {Id::kPosition, Id::kSetpoint, Id::kError, Id::kValve, Id::kSensor, Id::kMode, Id::kFaultCode, Id::kController,
                      Id::kUptime, Id::kLoopJitterP99, Id::kLoopWakeP50, Id::kLoopWakeP99, Id::kLoopWakeMax, Id::kLoopComputeP99})
    w.point(id);
  w.metric("epa_loop_jitter_max_seconds", "gauge", "scan period jitter, maximum.", s.loop.jitter_max_us * 1e-6);
  for (const Id id : {Id::kCycles, Id::kLoopOverruns, Id::kFaults, Id::kIoErrors, Id::kMoves, Id::kCommandsApplied, Id::kCommandsRejected,
                      Id::kModbusRequests})
    w.point(id, "counter");
  w.metric("epa_modbus_exceptions_total", "counter", "Modbus requests answered with an exception since start.",
           static_cast<double>(modbus.exceptions));
  w.point(Id::kModbusClients);
  w.metric("epa_web_requests_total", "counter", "HTTP requests served since start.", static_cast<double>(web_requests));
  for (const Id id : {Id::kHealthState, Id::kHealthEffect, Id::kHealthRatio, Id::kHealthMovesSinceOnset, Id::kHealthMovesSeen}) w.point(id);
  return w.take();
}

}  // namespace epa::web
