#pragma once
// The appliance's main thread while it runs: waits for SIGTERM/SIGINT (or the duration), logs
// mode changes, moves, faults and a periodic status line, keeps the fault history, has the gate
// log and audit the commands the loop refused after acceptance, and talks to systemd
// (Type=notify: READY, WATCHDOG only while the loop advances so a stuck loop gets the unit
// restarted, STOPPING).
#include <csignal>
#include <string>

#include "appliance/axis.hpp"
#include "config/appliance_config.hpp"
#include "core/log_throttle.hpp"
#include "runtime/snapshot.hpp"

namespace epa::appliance {

enum class StopCause { kSignal, kDuration };

// SIGTERM/SIGINT, blocked in the calling thread to be taken synchronously by supervise(). Call it
// before any other thread starts: they inherit the mask.
sigset_t block_stop_signals();

// `duration_s` > 0: stops by itself after this long.
StopCause supervise(const config::ApplianceConfig& c, double duration_s, Axis& axis, const sigset_t& signals,
                    core::LogThrottle& throttle);

// The status line: mode, controller, setpoint, position, valve, moves, loop timing.
std::string describe_snapshot(const runtime::Snapshot& s);

}  // namespace epa::appliance
