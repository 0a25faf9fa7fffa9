// HTTP API parameters: a POST body read into point writes for each command endpoint (setpoint,
// mode, reset, points), then decided by the write gate in a running, a manual and a faulted
// state; then the same bytes as an epa-tuning/1 TOML file (`epa tuning import`). Nothing may
// crash; a malformed body carries no writes; whatever the gate accepts, the scan cycle's own rules
// accept in the same state, and an accepted setpoint is within the configured limits.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "control/paper_controller.hpp"
#include "points/write_gate.hpp"
#include "store/tuning_file.hpp"
#include "web/command_body.hpp"

namespace {

struct Rig {
  epa::runtime::RuntimeConfig config;
  epa::runtime::LoopChannels channels{16};
  epa::points::WriteGate gate;
  Rig()
      : gate(*epa::points::WriteLimits::from_config(config, "fuzz"), config,
             epa::control::paper_controller_config(epa::control::ControllerKind::kPpFfidz), channels, nullptr) {}
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace epa;
  static Rig rig;
  const std::string body(reinterpret_cast<const char*>(data), size);
  const points::Requester who{"web fuzz", true, "", true};
  for (auto mode : {runtime::Mode::kRun, runtime::Mode::kManual, runtime::Mode::kFault}) {
    runtime::Snapshot snap;
    snap.mode = mode;
    for (auto endpoint : {web::CommandEndpoint::kSetpoint, web::CommandEndpoint::kMode, web::CommandEndpoint::kReset,
                          web::CommandEndpoint::kPoints}) {
      const auto parsed = web::parse_command_body(endpoint, body);
      if (!parsed.error.empty() && !parsed.writes.empty()) __builtin_trap();
      if (!parsed.error.empty()) continue;
      std::vector<runtime::Command> commands;
      const auto r = rig.gate.decide(parsed.writes, who, snap, &commands);
      if (!r.accepted() && (r.reason.empty() || !commands.empty())) __builtin_trap();
      // Each command against the loop's rules in the state the group leaves it, as the gate promises.
      runtime::Mode m = mode;
      runtime::ExcitationSettings excitation = rig.gate.excitation_settings();
      std::uint16_t word = snap.axis.control_word;  // the gate's, as the loop last applied it (no write was queued)
      for (const auto& c : commands) {
        if (runtime::check_command(c, m, snap.position_mm, excitation, word, rig.config) != runtime::CommandRefusal::kNone)
          __builtin_trap();
        if (c.kind == runtime::CommandKind::kControl) word = c.control_word;
        if (c.kind == runtime::CommandKind::kMode) m = c.mode;
        if (c.kind == runtime::CommandKind::kExcitation) excitation = c.excitation;
        if (c.kind == runtime::CommandKind::kReset && m == runtime::Mode::kFault) m = runtime::Mode::kStop;
        if (c.kind == runtime::CommandKind::kSetpoint &&
            !(c.value >= rig.config.setpoint_min_mm && c.value <= rig.config.setpoint_max_mm))
          __builtin_trap();
      }
    }
  }
  (void)store::parse_tuning_toml(body, "fuzz.toml");
  return 0;
}
