#include "appliance/commissioning_axis.hpp"

#include <chrono>
#include <thread>
#include <vector>

#include "appliance/store_save.hpp"
#include "core/format.hpp"
#include "core/units.hpp"
#include "runtime/excitation_settings.hpp"
#include "store/set_activation.hpp"
#include "store/store_file.hpp"

namespace epa::appliance {

namespace {

using Clock = std::chrono::steady_clock;
using points::PointId;
constexpr auto kPoll = std::chrono::milliseconds(1);        // a fifth of the loop's period: every cycle is seen
constexpr auto kRunWritten = std::chrono::seconds(10);      // the recorder writes within a few of its 20 ms polls
constexpr double kModeChangeS = 1.0;                        // a queued command is applied at the next cycle
constexpr double kPlaceHoldS = 3.0;                         // a move to the middle of the stroke, held

double mode_value(runtime::Mode m) { return static_cast<double>(static_cast<int>(m)); }

std::string fault_text(const runtime::Snapshot& s) {
  return "FAULT " + std::string(runtime::to_string(s.fault)) + ": " + std::string(runtime::describe(s.fault));
}

}  // namespace

core::Status CommissioningAxis::write(std::initializer_list<points::PointWrite> writes) {
  const std::vector<points::PointWrite> w(writes);
  const auto r = gate_.submit(w, who_);
  if (!r.accepted()) return core::invalid_argument(r.reason);
  return core::ok();
}

core::Result<core::Run> CommissioningAxis::excite(const commission::ExcitationRequest& request, const std::atomic<bool>& abort) {
  // The experiment starts only between its guard lines (its ramps need room both ways): a piston
  // left elsewhere (a verification move to the end, an operator) is first brought to the middle of
  // the soft limits with the set that runs now.
  const auto settings = gate_.excitation_settings();
  if (!runtime::excitation_may_start_at(channels_.snapshot.read().position_mm, settings, rules_)) {
    const double middle_mm = 0.5 * (rules_.soft_min_mm + rules_.soft_max_mm);
    auto placed = move(middle_mm, kPlaceHoldS, abort);
    if (!placed) return core::invalid_argument("bringing the piston between the excitation's guard lines: " + placed.error().message);
    if (!runtime::excitation_may_start_at(channels_.snapshot.read().position_mm, settings, rules_))
      return core::invalid_argument("the piston did not reach the excitation's guard lines (it stands at " +
                                    core::format_number(channels_.snapshot.read().position_mm) + " mm)");
  }
  if (channels_.snapshot.read().mode != runtime::Mode::kStop)
    if (auto s = write({{PointId::kMode, mode_value(runtime::Mode::kStop)}}); !s) return s.error();
  std::this_thread::sleep_for(std::chrono::duration<double>(2 * rules_.period_s));
  const std::uint64_t seen = runs_.count();
  if (auto s = write({{PointId::kExciteSeed, static_cast<double>(request.seed)},
                      {PointId::kExciteAmplitudeMax, request.amplitude_max_v},
                      {PointId::kExciteDuration, request.duration_s}});
      !s)
    return s.error();
  if (auto s = write({{PointId::kMode, mode_value(runtime::Mode::kExcite)}}); !s) return s.error();

  // Into EXCITE at the next cycle, out of it at its end (STOP), or FAULT.
  const auto started = Clock::now();
  bool entered = false;
  for (;;) {
    std::this_thread::sleep_for(kPoll * 10);
    const auto s = channels_.snapshot.read();
    const double waited_s = std::chrono::duration<double>(Clock::now() - started).count();
    if (abort) {
      stop();
      return core::invalid_argument("aborted during the excitation");
    }
    if (s.mode == runtime::Mode::kExcite) entered = true;
    if (s.mode == runtime::Mode::kFault) return core::invalid_argument("the excitation ended in " + fault_text(s));
    if (entered && s.mode != runtime::Mode::kExcite) break;
    if (!entered && waited_s > kModeChangeS) return core::invalid_argument("the loop did not enter EXCITE");
    if (waited_s > request.duration_s + 10.0) {
      stop();
      return core::invalid_argument("the excitation did not end within its duration");
    }
  }
  // The experiment's own file: a move that ended before it writes one too.
  const std::string seed = std::to_string(request.seed);
  auto run = runs_.wait_for(
      seen, [&seed](const core::Run& r) { return !r.meta("excitation_end").empty() && r.meta("excitation_seed") == seed; }, kRunWritten);
  if (!run) return core::io_error("the excitation's run file was not written within 10 s");
  if (run->meta("excitation_end") != "complete")
    return core::invalid_argument("the excitation ended early (" + run->meta("excitation_end") + ")");
  return *run;
}

core::Result<commission::RunningTuning> CommissioningAxis::running() {
  const auto set = store_.running_set();
  auto db = store::open_existing_store(db_path_);
  if (!db) return db.error();
  auto loaded = store::find_set_with_model(*db, std::to_string(set.id));
  if (!loaded) return loaded.error();
  loaded->set = set;  // with the tuning points written since it was loaded
  return commission::RunningTuning{loaded->set, loaded->model};
}

core::Result<std::int64_t> CommissioningAxis::save(const store::ModelRecord& model, const store::TuningSet& set) {
  return save_tuning_set(db_path_, model, set, who_.source);
}

core::Status CommissioningAxis::use_set(std::int64_t set_id, bool persist, const std::string& reason) {
  auto db = store::open_existing_store(db_path_);
  if (!db) return db.error();
  auto loaded = store::find_set_with_model(*db, std::to_string(set_id));
  if (!loaded) return loaded.error();
  const auto& model = loaded->model.model;
  if (!core::same_sample_time(model.Ts, rules_.period_s) || std::abs(model.mm_per_volt - rules_.mm_per_volt) > 1e-9)
    return core::invalid_argument("tuning set '" + loaded->set.name + "': its model's Ts " + core::format_number(model.Ts) +
                                  " s and sensor scale " + core::format_number(model.mm_per_volt) + " mm/V differ from the loop's");
  const auto old = store_.running_set();
  const core::AuditEntry entry{core::unix_time_ms(), who_.source + ": " + reason, "running_tuning_set", static_cast<double>(old.id),
                               static_cast<double>(set_id)};
  const auto r = gate_.replace_tuning(store::controller_config(loaded->set, model, rules_.safe_valve_v), who_, entry);
  if (!r.accepted()) return core::invalid_argument(r.reason);
  store_.switch_running_set(loaded->set, persist, who_.source);
  return core::ok();
}

core::Result<core::Run> CommissioningAxis::move(double target_mm, double hold_s, const std::atomic<bool>& abort) {
  if (auto s = write({{PointId::kSetpoint, target_mm}, {PointId::kMode, mode_value(runtime::Mode::kRun)}}); !s) return s.error();
  core::Run run;
  runtime::Snapshot s = channels_.snapshot.read();
  run.Ts = s.Ts > 0 ? s.Ts : rules_.period_s;
  run.set_meta("source", "commissioning verification move");
  const auto n = static_cast<std::size_t>(hold_s / run.Ts);
  std::uint64_t last_cycle = s.cycle;
  const auto deadline = Clock::now() + std::chrono::duration<double>(hold_s + 2.0);
  while (run.y_mm.size() < n) {
    std::this_thread::sleep_for(kPoll);
    s = channels_.snapshot.read();
    if (abort) {
      stop();
      return core::invalid_argument("aborted during the move");
    }
    if (s.mode == runtime::Mode::kFault) return core::invalid_argument("the move ended in " + fault_text(s));
    if (Clock::now() > deadline) return core::invalid_argument("the loop did not advance during the move");
    // One sample per cycle; a cycle this thread missed repeats the one after it (it is rare and
    // only blurs the figures by a sample).
    for (; last_cycle < s.cycle && run.y_mm.size() < n; ++last_cycle) {
      run.t_s.push_back(static_cast<double>(run.y_mm.size()) * run.Ts);
      run.r_mm.push_back(target_mm);
      run.y_mm.push_back(s.position_mm);
      run.u_V.push_back(s.valve_v);
      run.uc_V.push_back(s.controller_v);
    }
  }
  return run;
}

void CommissioningAxis::stop() { (void)write({{PointId::kMode, mode_value(runtime::Mode::kStop)}}); }

}  // namespace epa::appliance
