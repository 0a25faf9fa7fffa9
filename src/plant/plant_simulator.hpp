#pragma once
// What the `sim` DAQ backend and the remote I/O simulator need from a plant, so that either the
// paper's Hammerstein model or the physics model (PneumaticPlant) can stand behind them.
// Timing as in both plants: step(u) holds valve command u(k) over one sample period and advances
// to k+1; measured_v() is the sensor reading at k.
#include <memory>
#include <string_view>

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
};

}  // namespace epa::plant
