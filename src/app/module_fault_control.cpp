#include "app/module_fault_control.hpp"

#include <poll.h>
#include <unistd.h>

#include <sstream>

#include "core/format.hpp"

namespace epa::app {

std::string apply_module_command(const std::string& line, rig::RemoteIoSimulator& sim, rig::ModuleFaults& f) {
  std::istringstream in(line);
  std::string what, how;
  in >> what >> how;
  using A = rig::ModuleFaults::Answers;
  using S = rig::ModuleFaults::Sensor;
  if (what == "status")
    return "valve " + core::format_number(sim.valve_v()) + " position " + core::format_number(sim.position_mm()) +
           " steps_to_safe " + std::to_string(sim.steps_to_safe_valve()) + " watchdog " + (sim.watchdog_tripped() ? "tripped" : "ok");
  if (what == "answers") {
    if (how == "normal") f.answers = A::kNormal;
    else if (how == "silent") f.answers = A::kSilent;
    else if (how == "garbage") f.answers = A::kGarbage;
    else if (how == "late" && (in >> f.late_ms) && f.late_ms >= 0 && f.late_ms <= 10000) f.answers = A::kLate;
    else return "error: answers takes normal, silent, garbage or late MS (0..10000), not '" + line + "'";
  } else if (what == "sensor") {
    if (how == "normal") f.sensor = S::kNormal;
    else if (how == "nan") f.sensor = S::kNotANumber;
    else if (how == "frozen") f.sensor = S::kFrozen;
    else if (how == "fixed" && (in >> f.sensor_v)) f.sensor = S::kFixed;
    else return "error: sensor takes normal, nan, frozen or fixed VOLTS, not '" + line + "'";
  } else if (what == "physics") {
    double value = 0.0;
    std::string rest;
    if (how.empty() || !(in >> value) || (in >> rest)) return "error: physics takes KEY VALUE (an epa-pneumatic/1 key and a number), not '" + line + "'";
    if (auto s = sim.change_physics(how, value); !s) return "error: " + s.error().message;
    return "ok " + line;
  } else {
    return "error: unknown command '" + line + "' (answers, sensor, physics, status)";
  }
  sim.inject(f);
  return "ok " + line;
}

ModuleFaultControl::ModuleFaultControl(rig::RemoteIoSimulator& sim, std::ostream& out) : sim_(sim), out_(out) {
  thread_ = std::thread([this] { run(); });
}

void ModuleFaultControl::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void ModuleFaultControl::run() {
  rig::ModuleFaults faults;
  std::string pending;
  char buf[256];
  while (!stop_) {
    pollfd p{STDIN_FILENO, POLLIN, 0};
    if (poll(&p, 1, 100) <= 0) continue;
    const ssize_t n = ::read(STDIN_FILENO, buf, sizeof buf);
    if (n <= 0) return;  // EOF: no more commands
    pending.append(buf, static_cast<std::size_t>(n));
    for (std::size_t eol; (eol = pending.find('\n')) != std::string::npos;) {
      const std::string line = pending.substr(0, eol);
      pending.erase(0, eol + 1);
      if (!line.empty()) out_ << apply_module_command(line, sim_, faults) << std::endl;
    }
  }
}

}  // namespace epa::app
