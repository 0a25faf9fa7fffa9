#include "appliance/health_monitor.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>

#include "core/move_metrics.hpp"
#include "core/utc_stamp.hpp"
#include "points/point_catalog.hpp"

namespace epa::appliance {

namespace {

using points::HealthStateCode;

// A move ended as a move (not cut short, halted, stopped or faulted), closed-loop and recorded
// whole: what the estimator compares with its model (diag/model_health.hpp).
bool whole_move(const core::Run& run) {
  if (run.meta("move").empty() || run.meta("controller") == "open-loop" || !run.meta("samples_lost").empty()) return false;
  const auto end = core::parse_move_end(run.meta("move_end"));
  return end && (*end == core::MoveEnd::kInPosition || *end == core::MoveEnd::kOffTarget || *end == core::MoveEnd::kTimeout);
}

// The move that follows a cut one starts with the piston at speed, not from rest as the estimator
// assumes. (Its first readings cannot tell: from rest, a wound-up air spring moves the piston in the
// first sample.)
bool follows_a_cut_move(const core::Run& run, const std::string& previous_move, const std::string& previous_end) {
  std::uint64_t previous = 0;
  const auto [end, error] = std::from_chars(previous_move.data(), previous_move.data() + previous_move.size(), previous);
  const bool previous_is_the_one_before = error == std::errc() && std::to_string(previous + 1) == run.meta("move");
  return !previous_is_the_one_before || previous_end == core::to_string(core::MoveEnd::kCutShort);
}

// The lowest nice value: the monitor takes what the loop, the interfaces and the store leave. Not
// SCHED_IDLE: a thread of that class can wait for the CPU for seconds on a busy machine, and it
// still takes short locks. An unprivileged process may always lower its own threads.
void lower_priority() { (void)setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), 19); }

std::string state_reason(HealthStateCode s, const diag::HealthConfig& c) {
  switch (s) {
    case HealthStateCode::kLearning:
      return "learning the axis's normal: the first " + std::to_string(c.baseline_moves) + " moves after the model was set are the baseline";
    case HealthStateCode::kOk: return "the axis follows its baseline model";
    case HealthStateCode::kDrifting: return "one effect of the model has changed beyond its tolerance and explains the axis's recent moves";
    case HealthStateCode::kUnexplained: return "the axis has left its model and no single effect explains it: run epa diagnose on its run files";
    case HealthStateCode::kHunting: return "the law hunted about a standing target (a limit cycle): see the hunting status bit";
    case HealthStateCode::kOff: break;
  }
  return "";
}

}  // namespace

points::HealthStateCode health_state_code(diag::HealthState state) {
  switch (state) {
    case diag::HealthState::kOff: return HealthStateCode::kOff;
    case diag::HealthState::kLearning: return HealthStateCode::kLearning;
    case diag::HealthState::kOk: return HealthStateCode::kOk;
    case diag::HealthState::kDrifting: return HealthStateCode::kDrifting;
    case diag::HealthState::kUnexplained: return HealthStateCode::kUnexplained;
    case diag::HealthState::kHunting: return HealthStateCode::kHunting;
  }
  return HealthStateCode::kOff;
}

points::HealthEffectCode health_effect_code(plant::EffectKind effect) {
  using E = points::HealthEffectCode;
  switch (effect) {
    case plant::EffectKind::kStaticFriction: return E::kStaticFriction;
    case plant::EffectKind::kGainChange: return E::kGainChange;
    case plant::EffectKind::kDeadzoneShift: return E::kDeadzoneShift;
    case plant::EffectKind::kValveLag: return E::kValveLag;
    case plant::EffectKind::kInputDelay: return E::kInputDelay;
    default: return E::kNone;
  }
}

HealthMonitor::HealthMonitor(config::HealthSettings config, RunningSetId running_set, ModelOf model_of, core::AuditSink* audit, Log log,
                             HistoryNote history)
    : config_(std::move(config)),
      running_set_(std::move(running_set)),
      model_of_(std::move(model_of)),
      audit_(audit),
      log_(std::move(log)),
      history_(std::move(history)) {
  if (!config_.enabled) {
    current_.reason = "the model-health monitor is switched off ([health] enabled = false)";
    put(current_);
    return;
  }
  put(current_);
  busy_ = true;  // until the thread has looked at the running set
  thread_ = std::thread([this] { run_thread(); });
}

HealthMonitor::~HealthMonitor() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void HealthMonitor::add_run(const core::Run& run, bool hunting) {
  if (!config_.enabled || run.meta("move").empty()) return;
  {
    std::lock_guard lock(mutex_);
    const bool after_cut = follows_a_cut_move(run, previous_move_, previous_end_);
    previous_move_ = run.meta("move");
    previous_end_ = run.meta("move_end");
    if (after_cut || !whole_move(run)) return;
    if (queue_.size() >= kQueued) {
      ++dropped_;
      return;
    }
    queue_.push_back({run, hunting});
  }
  changed_.notify_all();
}

points::HealthView HealthMonitor::view() const { return view_.read(); }

points::HealthReport HealthMonitor::report(bool with_trend) const {
  std::shared_ptr<const points::HealthReport> published;
  {
    std::lock_guard lock(report_mutex_);
    published = report_;
  }
  points::HealthReport r;
  r.view = published->view;
  r.size = published->size, r.unit = published->unit, r.reason = published->reason;
  r.window_gap_mm = published->window_gap_mm, r.baseline_gap_mm = published->baseline_gap_mm;
  if (with_trend) r.trend = published->trend;
  r.moves_dropped = dropped_.load();
  return r;
}

void HealthMonitor::put(points::HealthReport report) {
  view_.publish(report.view);
  auto shared = std::make_shared<const points::HealthReport>(std::move(report));
  std::lock_guard lock(report_mutex_);
  report_.swap(shared);  // the old one is freed outside the lock, when `shared` goes
}

void HealthMonitor::retake_baseline(const std::string& source) {
  {
    std::lock_guard lock(mutex_);
    retake_source_ = source;
  }
  changed_.notify_all();
}

bool HealthMonitor::wait_idle(int timeout_ms) const {
  std::unique_lock lock(mutex_);
  return changed_.wait_for(lock, std::chrono::milliseconds(timeout_ms), [&] { return queue_.empty() && !busy_ && !retake_source_; });
}

void HealthMonitor::run_thread() {
  lower_priority();
  follow_running_set();  // learning (or off, and why) from the start, not from the first move
  std::unique_lock lock(mutex_);
  busy_ = false;
  changed_.notify_all();
  while (true) {
    // Woken by a move or a command, and every kSetPollS to see whether another set runs (one is
    // deployed by commissioning, or rolled back, between moves).
    changed_.wait_for(lock, std::chrono::duration<double>(kSetPollS), [&] { return stop_ || !queue_.empty() || retake_source_; });
    if (stop_) return;
    busy_ = true;
    std::optional<std::string> retake = std::exchange(retake_source_, std::nullopt);
    std::optional<Queued> item;
    if (!retake && !queue_.empty()) item = std::move(queue_.front()), queue_.pop_front();
    lock.unlock();
    follow_running_set();
    if (retake && health_) {
      health_->retake_baseline();
      publish(*retake + ": retake the baseline", /*always_audit=*/true);
    }
    if (item) judge(std::move(*item));
    lock.lock();
    busy_ = false;
    changed_.notify_all();
  }
}

void HealthMonitor::follow_running_set() {
  const std::int64_t id = running_set_();
  if (set_id_ == id) return;
  set_id_ = id;
  health_.reset();
  auto model = model_of_(id);
  if (!model) {
    set_id_.reset();  // read it again at the next look: the store may have been busy
    return set_off("the running tuning set's model could not be read: " + model.error().message, "health monitor");
  }
  if (!model->stick_slip)
    return set_off("the running tuning set '" + model->set_name +
                       "' has no stick-slip model: commission the axis (epa commission) to give it one",
                   "health monitor");
  auto health = diag::ModelHealth::make(*model->stick_slip, model->Ts, config_.stroke_mm, config_.estimator);
  if (!health) return set_off(health.error().message, "health monitor");
  health_.emplace(std::move(*health));
  publish("health monitor: tuning set '" + model->set_name + "' runs");
}

void HealthMonitor::judge(Queued item) {
  if (!health_) return;
  health_->add_move(std::move(item.run), item.hunting);
  publish("health monitor");
}

void HealthMonitor::set_off(const std::string& reason, const std::string& source) {
  const HealthStateCode before = current_.view.state;
  const bool same_reason = current_.reason == reason;
  current_ = points::HealthReport{};
  current_.reason = reason;
  put(current_);
  if (!same_reason) log_(false, "model health: off: " + reason);
  if (history_ && points::health_warns(before)) history_("model health: " + std::string(points::to_string(before)) + " -> off: " + reason);
  if (audit_ && before != HealthStateCode::kOff)
    audit_->record({{core::unix_time_ms(), source, std::string(points::name(points::PointId::kHealthState)), double(static_cast<int>(before)),
                     double(static_cast<int>(HealthStateCode::kOff))}});
}

void HealthMonitor::publish(const std::string& source, bool always_audit) {
  const diag::HealthVerdict& v = health_->verdict();
  points::HealthReport r;
  r.view.state = health_state_code(v.state);
  r.view.moves_seen = static_cast<std::uint32_t>(v.moves_seen);
  r.view.moves_since_onset = static_cast<std::uint32_t>(v.moves_since_onset);
  if (v.effect) {
    r.view.effect = health_effect_code(*v.effect);
    r.view.value = v.value;
    r.view.commissioned = v.commissioned;
    r.view.ratio = v.ratio;
    r.unit = v.unit;
    r.size = v.size;
  }
  r.reason = state_reason(r.view.state, config_.estimator);
  r.window_gap_mm = v.estimates.empty() ? std::nan("") : v.window_gap_mm;
  r.baseline_gap_mm = v.state == diag::HealthState::kLearning ? std::nan("") : v.baseline_gap_mm;

  const HealthStateCode before = current_.view.state;
  const points::HealthEffectCode effect_before = current_.view.effect;
  r.trend = std::move(current_.trend);
  const bool new_judgement = !v.estimates.empty() && (r.trend.empty() || r.trend.back().move != r.view.moves_seen);
  if (r.view.state == HealthStateCode::kLearning) {
    r.trend.clear();
  } else if (new_judgement) {
    points::HealthJudgement j{r.view.moves_seen, {}};
    for (const auto& e : v.estimates) j.estimates.push_back({health_effect_code(e.effect), e.ratio, e.reduction});
    r.trend.push_back(std::move(j));
    if (r.trend.size() > kTrendKept) r.trend.erase(r.trend.begin());
  }
  current_ = r;
  put(std::move(r));
  const points::HealthReport& now = current_;
  if (before == now.view.state && effect_before == now.view.effect && !always_audit) return;
  const bool warns = points::health_warns(now.view.state);
  const std::string line = "model health: " + std::string(points::to_string(before)) + " -> " + std::string(points::to_string(now.view.state)) +
                           (now.size.empty() ? "" : " (" + now.size + ", " + std::to_string(now.view.moves_since_onset) + " moves since its onset)") +
                           " after " + std::to_string(now.view.moves_seen) + " moves";
  log_(warns, line);
  if (history_ && (warns || points::health_warns(before))) history_(line);
  if (audit_)
    audit_->record({{core::unix_time_ms(), source + (now.size.empty() ? "" : ": " + now.size),
                     std::string(points::name(points::PointId::kHealthState)), double(static_cast<int>(before)),
                     double(static_cast<int>(now.view.state))}});
}

}  // namespace epa::appliance
