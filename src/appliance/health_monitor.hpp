#pragma once
// The model-health monitor of one axis: each move the recorder writes is judged, on a thread of
// its own at the lowest priority (nice 19: the loop, the interfaces and the store come first),
// against the running tuning set's stick-slip model by diag::ModelHealth. Its verdict is what the
// health points, /api/status, /metrics and the page show; each change of state goes to the audit
// trail and the log, and each warning's start, change and end to the fault history. It never
// commands the axis: a drift warns, it does not fault.
//
// The model follows the running set: when another set runs (commissioning deployed one, or rolled
// back), the monitor starts learning again on that set's model. A set whose model has no
// stick-slip table (the paper's, or one identified before stick-slip models existed) is not
// monitored: the state is off, and the reason says so.
#include <array>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "config/appliance_config.hpp"
#include "core/audit.hpp"
#include "core/result.hpp"
#include "core/run.hpp"
#include "core/stick_slip_params.hpp"
#include "diag/model_health.hpp"
#include "points/health_control.hpp"
#include "runtime/seqlock.hpp"

namespace epa::appliance {

// The running set's model as the monitor needs it.
struct MonitoredModel {
  std::string set_name;
  std::optional<core::StickSlipParams> stick_slip;  // none: not monitored
  double Ts = 0.005;
};

class HealthMonitor final : public points::HealthControl {
 public:
  using Log = std::function<void(bool warning, const std::string& line)>;
  // An entry for the fault history: a warning began, changed or ended (never a fault: the axis runs on).
  using HistoryNote = std::function<void(const std::string& text)>;
  // The running set's id (cheap: asked for every move) and its model (read when the id changes).
  // Both are called on the monitor's thread.
  using RunningSetId = std::function<std::int64_t()>;
  using ModelOf = std::function<core::Result<MonitoredModel>(std::int64_t set_id)>;

  // `audit` and `history` may be null. Starts its thread (unless disabled).
  HealthMonitor(config::HealthSettings config, RunningSetId running_set, ModelOf model_of, core::AuditSink* audit, Log log,
                HistoryNote history = nullptr);
  ~HealthMonitor() override;  // stops the thread; moves still queued are not judged
  HealthMonitor(const HealthMonitor&) = delete;
  HealthMonitor& operator=(const HealthMonitor&) = delete;

  // A run the recorder wrote: a whole move's file is queued for judging (at most kQueued wait; more
  // are dropped and counted), unless the move before it was cut short (or not seen: the piston may
  // have been sliding); any other run is ignored. `hunting`: the loop's hunting watch holds the
  // law as it is written. Never blocks on a judgement.
  void add_run(const core::Run& run, bool hunting);

  points::HealthView view() const override;
  points::HealthReport report(bool with_trend) const override;
  void retake_baseline(const std::string& source) override;

  // Waits (at most `timeout_ms`) until every run queued so far has been judged; for tests.
  bool wait_idle(int timeout_ms) const;

  static constexpr std::size_t kQueued = 8;
  static constexpr std::size_t kTrendKept = 120;  // judgements the page's trend shows
  static constexpr double kSetPollS = 0.5;         // how often the running set is looked at between moves

 private:
  struct Queued {
    core::Run run;
    bool hunting = false;
  };
  void run_thread();
  void follow_running_set();                     // the model of the set that runs now
  void judge(Queued item);
  // The estimator's verdict into report_, logged and audited when its state or effect changed.
  void publish(const std::string& source, bool always_audit = false);
  void set_off(const std::string& reason, const std::string& source);

  const config::HealthSettings config_;
  RunningSetId running_set_;
  ModelOf model_of_;
  core::AuditSink* audit_;
  Log log_;
  HistoryNote history_;

  // Hands the report over: readers copy a pointer, never wait for a judgement.
  void put(points::HealthReport report);

  // The thread's own: the estimator, the set it was made for, the verdict it last published.
  std::optional<diag::ModelHealth> health_;
  std::optional<std::int64_t> set_id_;
  points::HealthReport current_;

  // What the interfaces read. The thread runs at the lowest priority, so nothing it shares with
  // them is held while it works: the numbers through a seqlock (a Modbus request reads them), the
  // report as a pointer swapped under report_mutex_.
  runtime::SeqlockCell<points::HealthView> view_;
  mutable std::mutex report_mutex_;
  std::shared_ptr<const points::HealthReport> report_;
  std::atomic<std::uint64_t> dropped_{0};

  mutable std::mutex mutex_;  // the queue and the commands
  mutable std::condition_variable changed_;
  std::deque<Queued> queue_;
  std::string previous_move_, previous_end_;  // the last move's number and end, as its run file says
  bool busy_ = false;  // a run is being judged
  std::optional<std::string> retake_source_;  // a baseline retake asked for, by whom
  bool stop_ = false;
  std::thread thread_;
};

// diag's vocabulary in the interface's codes.
points::HealthStateCode health_state_code(diag::HealthState state);
points::HealthEffectCode health_effect_code(plant::EffectKind effect);

}  // namespace epa::appliance
