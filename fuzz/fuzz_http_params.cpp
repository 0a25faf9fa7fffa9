// HTTP API parameters: a POST body into the command validation of each endpoint (setpoint, mode,
// reset), in a running and a faulted state; then the same bytes as an epa-tuning/1 TOML file
// (`epa tuning import`). Validation must answer with a status or the commands, never crash, and
// an accepted setpoint must be within the configured limits.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "store/tuning_file.hpp"
#include "web/command_validation.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace epa;
  const std::string body(reinterpret_cast<const char*>(data), size);
  const runtime::RuntimeConfig limits;
  runtime::Snapshot snap;
  snap.mode = runtime::Mode::kRun;
  for (int faulted = 0; faulted < 2; ++faulted) {
    if (faulted) snap.mode = runtime::Mode::kFault;
    for (auto endpoint : {web::CommandEndpoint::kSetpoint, web::CommandEndpoint::kMode, web::CommandEndpoint::kReset}) {
      const auto d = web::validate_command(endpoint, body, snap, limits);
      if (d.status == 200 && !d.error.empty()) __builtin_trap();
      if (d.status != 200 && !d.commands.empty()) __builtin_trap();
      for (const auto& c : d.commands)
        if (c.kind == runtime::CommandKind::kSetpoint &&
            !(c.value >= limits.setpoint_min_mm && c.value <= limits.setpoint_max_mm))
          __builtin_trap();
    }
  }
  (void)store::parse_tuning_toml(body, "fuzz.toml");
  return 0;
}
