#include "web/prometheus.hpp"

#include <cmath>
#include <cstdio>
#include <string>

#include "points/point_catalog.hpp"

namespace epa::web {

namespace {

class Writer {
 public:
  // A point's value under its catalog name: epa_<point>, the catalog's description as help.
  void point(points::PointId id, double value) {
    const auto& p = points::point(id);
    metric(("epa_" + std::string(p.name)).c_str(), "gauge", (std::string(p.description) + ".").c_str(), value);
  }
  void metric(const char* name, const char* type, const char* help, double value) {
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
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
  }
  std::string out_;
};

}  // namespace

std::string prometheus_text(const runtime::Snapshot& s, const ModbusStats& modbus, std::uint64_t web_requests) {
  Writer w;
  const auto d = [](std::uint64_t v) { return static_cast<double>(v); };
  using P = points::PointId;
  w.point(P::kPosition, s.position_mm);
  w.point(P::kSetpoint, s.setpoint_mm);
  w.point(P::kError, s.error_mm);
  w.metric("epa_valve_volts", "gauge", "Valve command written to the DAQ, V.", s.valve_v);
  w.metric("epa_sensor_volts", "gauge", "Position sensor reading, V.", s.sensor_v);
  w.point(P::kMode, static_cast<double>(s.mode));
  w.point(P::kFaultCode, static_cast<double>(s.fault));
  w.point(P::kController, static_cast<double>(s.controller));
  w.metric("epa_uptime_seconds", "gauge", "Time since the scan cycle started, s.", s.time_s);
  w.metric("epa_loop_cycles_total", "counter", "Scan cycles run.", d(s.loop.cycles));
  w.metric("epa_loop_overruns_total", "counter", "Scan cycles that missed their deadline.", d(s.loop.overruns));
  w.metric("epa_loop_jitter_p99_microseconds", "gauge", "99th percentile of |period - Ts|, us.", s.loop.jitter_p99_us);
  w.metric("epa_loop_jitter_max_microseconds", "gauge", "Largest |period - Ts|, us.", s.loop.jitter_max_us);
  w.metric("epa_loop_wake_p99_microseconds", "gauge", "99th percentile of the wake-up latency, us.", s.loop.wake_p99_us);
  w.metric("epa_loop_compute_p99_microseconds", "gauge", "99th percentile of the compute time, us.", s.loop.compute_p99_us);
  w.metric("epa_faults_total", "counter", "Faults latched since start.", d(s.faults));
  w.metric("epa_io_errors_total", "counter", "DAQ read or write failures.", d(s.io_errors));
  w.metric("epa_moves_total", "counter", "Moves started.", d(s.moves));
  w.metric("epa_commands_applied_total", "counter", "Commands applied by the scan cycle.", d(s.commands_applied));
  w.metric("epa_commands_rejected_total", "counter", "Commands refused by the scan cycle.", d(s.commands_rejected));
  w.metric("epa_modbus_requests_total", "counter", "Modbus requests served.", d(modbus.requests));
  w.metric("epa_modbus_exceptions_total", "counter", "Modbus requests answered with an exception.", d(modbus.exceptions));
  w.metric("epa_modbus_clients", "gauge", "Connected Modbus clients.", modbus.clients);
  w.metric("epa_web_requests_total", "counter", "HTTP requests served.", d(web_requests));
  return w.take();
}

}  // namespace epa::web
