#pragma once
// What the commissioning sequence needs of the axis it commissions: the appliance's loop, store
// and recorder behind one interface (appliance/commissioning_axis.*), or a simulated axis in the tests.
// Every call blocks until it is done or `abort` is set; none of them runs on the scan cycle.
#include <atomic>
#include <cstdint>
#include <string>

#include "core/result.hpp"
#include "core/run.hpp"
#include "store/model_record.hpp"
#include "store/tuning_set.hpp"

namespace epa::commission {

struct ExcitationRequest {
  double duration_s = 60.0;
  std::uint64_t seed = 1;
  double amplitude_max_v = 3.0;
};

struct RunningTuning {
  store::TuningSet set;
  store::ModelRecord model;
};

class Axis {
 public:
  virtual ~Axis() = default;

  virtual double position_mm() = 0;
  // The loop's stroke limits for targets: the setpoint range.
  virtual double setpoint_min_mm() const = 0;
  virtual double setpoint_max_mm() const = 0;
  // One open-loop excitation experiment, entered from STOP and back in STOP at its end: the run
  // as recorded (controller=open-loop).
  virtual core::Result<core::Run> excite(const ExcitationRequest& request, const std::atomic<bool>& abort) = 0;
  // The set the loop runs now, with its model.
  virtual core::Result<RunningTuning> running() = 0;
  // Stores the set with its model, not active; returns the set's id.
  virtual core::Result<std::int64_t> save(const store::ModelRecord& model, const store::TuningSet& set) = 0;
  // The loop runs set `set_id` from the next cycle (switched in STOP). `persist`: it is also the
  // store's active set, what a restart loads; until then a restart comes up on the old one.
  virtual core::Status use_set(std::int64_t set_id, bool persist, const std::string& reason) = 0;
  // RUN to `target_mm` and hold `hold_s`: the position from the command on, one sample per cycle.
  virtual core::Result<core::Run> move(double target_mm, double hold_s, const std::atomic<bool>& abort) = 0;
  // STOP: the valve at its safe command.
  virtual void stop() = 0;
};

}  // namespace epa::commission
