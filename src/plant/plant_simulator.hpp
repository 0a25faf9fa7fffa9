#pragma once
// What the `sim` DAQ backend and the remote I/O simulator need from a plant, so that either the
// paper's Hammerstein model or the physics model (PneumaticPlant) can stand behind them.
// Timing as in both plants: step(u) holds valve command u(k) over one sample period and advances
// to k+1; measured_v() is the sensor reading at k.
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "core/result.hpp"
#include "plant/pneumatic_params.hpp"

namespace epa::plant {

class PlantSimulator {
 public:
  virtual ~PlantSimulator() = default;

  // Valve command in V (-10..10); non-finite is taken as 0 V, the centred valve. Never allocates.
  virtual void step(double valve_v) noexcept = 0;
  virtual double measured_v() const noexcept = 0;       // sensor reading at k, V (0-10 V over the stroke)
  virtual double position_mm() const noexcept = 0;      // true piston position at k
  virtual double sample_period_s() const noexcept = 0;  // Ts that one step() covers
  virtual std::string_view kind() const noexcept = 0;   // "Hammerstein" or "physics", for logs
  // A copy with the same state (noise generator included), so holders keep value semantics.
  virtual std::unique_ptr<PlantSimulator> clone() const = 0;

  // The physics plant's parameters (epa-pneumatic/1), so a test rig can change them while it runs
  // (`epa plant-server`'s `physics KEY VALUE`); none for a plant without them.
  virtual std::optional<PneumaticParams> physics_params() const { return std::nullopt; }
  // Checks `next` for this plant without changing it; a plant without physics parameters refuses.
  virtual core::Status check_physics_params(const PneumaticParams& next) const;
  // Takes checked parameters from the next step on; the state carries over.
  virtual core::Status set_physics_params(const PneumaticParams& next) { return check_physics_params(next); }
};

inline core::Status PlantSimulator::check_physics_params(const PneumaticParams&) const {
  return core::invalid_argument("the " + std::string(kind()) +
                                " plant has no physical parameters to change: 'physics' lines need the physics plant (--plant physics)");
}

}  // namespace epa::plant
