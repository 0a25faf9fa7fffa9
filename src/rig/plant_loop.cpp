#include "rig/plant_loop.hpp"

#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>

#include "rig/monotonic_clock.hpp"

namespace epa::rig {

namespace {
constexpr long kMaxLagPeriods = 10;  // start a fresh schedule beyond this lag
}  // namespace

PlantLoop::PlantLoop(const Setup& setup, std::unique_ptr<plant::PlantSimulator> plant, ModuleRegisters& registers,
                     InjectedFaults& faults, const MasterActivity& activity)
    : setup_(setup),
      plant_(std::move(plant)),
      period_ns_(static_cast<std::int64_t>(std::llround(plant_->sample_period_s() * 1e9))),
      registers_(registers),
      faults_(faults),
      activity_(activity) {
  position_mm_.store(plant_->position_mm());
  physics_ = plant_->physics_params();
}

core::Status PlantLoop::change_physics(std::string_view key, double value) {
  std::lock_guard lock(physics_mutex_);
  if (!physics_) return plant_->check_physics_params(plant::PneumaticParams{});  // refuses, naming the plant
  plant::PneumaticParams next = *physics_;
  if (auto s = plant::set_pneumatic_key(next, key, value); !s) return s;
  // The check reads only the plant's options, which never change once it runs.
  if (auto s = plant_->check_physics_params(next); !s) return s;
  physics_ = next;
  physics_pending_.store(true);
  return core::ok();
}

void PlantLoop::take_physics_change() noexcept {
  if (!physics_pending_.load()) return;
  std::unique_lock lock(physics_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;  // being changed right now: taken a step later
  (void)plant_->set_physics_params(*physics_);  // checked in change_physics
  physics_pending_.store(false);
}

void PlantLoop::run(const std::atomic<bool>& running) noexcept {
  std::int64_t next_ns = monotonic_ns();
  std::int64_t step_before_ns = next_ns - period_ns_;
  while (running.load()) {
    next_ns = next_step_ns(next_ns, step_before_ns);
    next_step_due_ns_.store(next_ns);
    const timespec deadline = from_ns(next_ns);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) == EINTR) {
    }
    if (!running.load()) break;
    step(valve_command(next_ns));
    if (const std::int64_t now_ns = monotonic_ns(); now_ns - next_ns > kMaxLagPeriods * period_ns_) {
      next_ns = now_ns;
      overruns_.fetch_add(1);
    }
  }
}

// `last_step_ns` is when the last step was due. Synchronised: the master wrote the valve since the
// step before it, so its next write comes a period after that one; step half a period after it,
// within half a period of the free schedule. Locked after one write; without writes the schedule
// runs free.
std::int64_t PlantLoop::next_step_ns(std::int64_t last_step_ns, std::int64_t& step_before_ns) const noexcept {
  const std::int64_t write_ns = activity_.last_valve_write_ns.load();
  std::int64_t next_ns = last_step_ns + period_ns_;
  if (setup_.sync_to_valve_writes && write_ns > step_before_ns)
    next_ns = std::clamp(write_ns + period_ns_ + period_ns_ / 2, last_step_ns + period_ns_ / 2, last_step_ns + period_ns_ * 3 / 2);
  step_before_ns = last_step_ns;
  return next_ns;
}

double PlantLoop::valve_command(std::int64_t step_ns) noexcept {
  const double valve_v = registers_.valve_v();
  if (setup_.watchdog_ms <= 0) return valve_v;
  const std::int64_t last = activity_.last_request_ns.load();
  const bool tripped = last != 0 && step_ns - last > static_cast<std::int64_t>(setup_.watchdog_ms) * 1'000'000;
  watchdog_tripped_.store(tripped);
  return tripped ? 0.0 : valve_v;  // the module's own safe output: the valve centred
}

void PlantLoop::step(double valve_v) noexcept {
  take_physics_change();
  plant_->step(valve_v);
  last_valve_v_.store(valve_v);
  faults_.count_step(steps_.load(), valve_v);
  if (const auto words = faults_.sensor_words(setup_.sensor, plant_->measured_v())) registers_.write_sensor(*words);
  position_mm_.store(plant_->position_mm());
  steps_.fetch_add(1);
}

}  // namespace epa::rig
