#include "appliance/supervisor.hpp"

#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>

#include <chrono>
#include <cstdio>
#include <ctime>

#include "appliance/throttled_log.hpp"
#include "core/move_metrics.hpp"

namespace epa::appliance {

namespace {

using SteadyClock = std::chrono::steady_clock;

// What the operator should read in the log between two snapshots: mode changes, moves. (Faults
// come from the loop's events: Axis::take_fault_events.)
void log_changes(const runtime::Snapshot& previous, const runtime::Snapshot& s, core::LogThrottle& throttle) {
  if (s.mode != previous.mode) spdlog::info("mode {} -> {}", runtime::to_string(previous.mode), runtime::to_string(s.mode));
  if (s.fault_events_dropped != previous.fault_events_dropped)
    spdlog::warn("{} fault(s) latched with the fault event ring full: counted in faults, missing from the fault history",
                 s.fault_events_dropped - previous.fault_events_dropped);
  if (s.moves != previous.moves)
    log_throttled(throttle, "move", spdlog::level::info,
                  fmt::format("move {} {:.1f} -> {:.1f} mm ({}, {}): rise {:.3f} s, settling {:.3f} s, e_ss {:.2f} mm, overshoot {:.1f} %",
                              s.last_move.number, s.last_move.from_mm, s.last_move.to_mm, control::to_string(s.last_move.controller),
                              core::to_string(static_cast<core::MoveEnd>(s.last_move.end)), s.last_move.rise_s,
                              s.last_move.settling_s, s.last_move.ess_mm, s.last_move.overshoot_pct));
}

// The systemd watchdog, pinged at half its interval only while the loop's cycle count advances.
class Watchdog {
 public:
  explicit Watchdog(std::uint64_t cycle) : enabled_(sd_watchdog_enabled(0, &interval_us_) > 0), cycle_at_last_ping_(cycle) {}
  void tick(SteadyClock::time_point now, std::uint64_t cycle) {
    if (!enabled_ || now - last_ping_ < std::chrono::microseconds(interval_us_ / 2)) return;
    if (cycle != cycle_at_last_ping_) sd_notify(0, "WATCHDOG=1");
    cycle_at_last_ping_ = cycle;
    last_ping_ = now;
  }

 private:
  std::uint64_t interval_us_ = 0;
  bool enabled_;
  std::uint64_t cycle_at_last_ping_;
  SteadyClock::time_point last_ping_ = SteadyClock::now();
};

// Waits one tick (50 ms: events are logged within that) for SIGTERM/SIGINT.
bool stop_signal_within_tick(const sigset_t& signals) {
  const timespec tick{0, 50'000'000};
  const int sig = sigtimedwait(&signals, nullptr, &tick);
  if (sig != SIGTERM && sig != SIGINT) return false;
  spdlog::info("signal {}: shutting down", sig == SIGTERM ? "SIGTERM" : "SIGINT");
  return true;
}

}  // namespace

sigset_t block_stop_signals() {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  return signals;
}

StopCause supervise(const config::ApplianceConfig& c, double duration_s, Axis& axis, const sigset_t& signals,
                    core::LogThrottle& throttle) {
  sd_notify(0, "READY=1");
  spdlog::info("running");
  const auto started = SteadyClock::now();
  auto last_status = started;
  runtime::Snapshot previous = axis.snapshot();
  Watchdog watchdog(previous.cycle);
  StopCause cause;
  for (;;) {
    if (stop_signal_within_tick(signals)) {
      cause = StopCause::kSignal;
      break;
    }
    const auto now = SteadyClock::now();
    const runtime::Snapshot s = axis.snapshot();
    axis.take_fault_events();
    log_changes(previous, s, throttle);
    axis.gate().take_refusals([&throttle](const std::string& line) { log_throttled(throttle, "refused", spdlog::level::warn, line); });
    for (const std::string& summary : throttle.due_summaries()) spdlog::info("{}", summary);
    previous = s;
    if (c.status_interval_s > 0 && now - last_status >= std::chrono::duration<double>(c.status_interval_s)) {
      spdlog::info("status: {}", describe_snapshot(s));
      last_status = now;
    }
    watchdog.tick(now, s.cycle);
    if (duration_s > 0 && now - started >= std::chrono::duration<double>(duration_s)) {
      spdlog::info("duration of {} s reached: shutting down", duration_s);
      cause = StopCause::kDuration;
      break;
    }
  }
  sd_notify(0, "STOPPING=1");
  return cause;
}

std::string describe_snapshot(const runtime::Snapshot& s) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "mode %s, %s, setpoint %.2f mm, position %.2f mm, valve %.3f V, moves %llu, loop p99 wake-up %.0f us, overruns %llu",
                std::string(runtime::to_string(s.mode)).c_str(), std::string(control::to_string(s.controller)).c_str(),
                s.setpoint_mm, s.position_mm, s.valve_v, static_cast<unsigned long long>(s.moves), s.loop.wake_p99_us,
                static_cast<unsigned long long>(s.loop.overruns));
  return buf;
}

}  // namespace epa::appliance
