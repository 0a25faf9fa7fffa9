#include "store/store_writer.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "core/free_space.hpp"

#include "store/audit_log.hpp"
#include "store/fault_table.hpp"
#include "store/retained_points.hpp"
#include "store/run_table.hpp"
#include "store/set_activation.hpp"
#include "store/transaction.hpp"
#include "points/point_catalog.hpp"
#include "store/tuning_points.hpp"
#include "store/tuning_set_table.hpp"

namespace epa::store {

namespace {
constexpr std::uint64_t kItemsBetweenRetention = 1000;
}  // namespace

StoreWriter::StoreWriter(Database db, TuningSet running, std::set<points::PointId> persisted, Log log)
    : db_(std::move(db)), running_(std::move(running)), persisted_(std::move(persisted)), log_(std::move(log)) {
  running_set_id_.store(running_.id, std::memory_order_release);
}

StoreWriter::~StoreWriter() { stop(0.0); }

void StoreWriter::start() {
  if (!thread_.joinable()) thread_ = std::thread([this] { loop(); });
}

void StoreWriter::stop(double drain_s) {
  {
    std::lock_guard lock(mutex_);
    if (stop_ && !thread_.joinable()) return;
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(drain_s);
  while (!flush() && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const StoreHealth h = health();
  if (h.pending > 0 && log_) log_("store: " + std::to_string(h.pending) + " accepted changes could not be saved: " + h.last_error);
}

void StoreWriter::record(const std::vector<core::AuditEntry>& change) {
  if (change.empty()) return;
  {
    std::lock_guard lock(mutex_);
    pending_.emplace_back(change);
    ++accepted_;
  }
  wake_.notify_one();
}

void StoreWriter::record_run(const RunRecord& run) {
  {
    std::lock_guard lock(mutex_);
    pending_.emplace_back(run);
  }
  wake_.notify_one();
}

void StoreWriter::record_fault(const runtime::FaultRecord& fault) {
  {
    std::lock_guard lock(mutex_);
    pending_.emplace_back(fault);
  }
  wake_.notify_one();
}

void StoreWriter::switch_running_set(const TuningSet& set, bool persist, const std::string& source) {
  {
    std::lock_guard lock(mutex_);
    pending_.emplace_back(SetSwitch{set, persist, source});
  }
  wake_.notify_one();
}

TuningSet StoreWriter::running_set() const {
  std::lock_guard lock(mutex_);
  return running_;
}

void StoreWriter::set_limits(const StoreLimits& limits) {
  std::lock_guard lock(mutex_);
  limits_ = limits;
}

core::ChangeCounters StoreWriter::counters() const {
  std::lock_guard lock(mutex_);
  return {accepted_, saved_.load(), health_.ok, disk_low_now()};
}

bool StoreWriter::disk_low_now() const {
  const std::int64_t now_ms = core::unix_time_ms();
  if (now_ms - disk_checked_ms_ >= 1000 || now_ms < disk_checked_ms_) {
    const auto folder = std::filesystem::path(db_.path()).parent_path();
    const auto free = core::free_bytes(folder.empty() ? "." : folder.string());
    disk_low_ = free && *free < limits_.min_free_bytes;
    disk_checked_ms_ = now_ms;
  }
  return disk_low_;
}

void StoreWriter::drop_beyond_retention() {
  StoreLimits limits;
  {
    std::lock_guard lock(mutex_);
    limits = limits_;
  }
  auto audit = AuditLog(db_).drop_oldest(limits.audit_max_rows);
  auto runs = RunTable(db_).drop_oldest(limits.runs_max_rows);
  if (!audit || !runs) {
    if (log_) log_("store: cannot drop rows beyond the retention: " + (!audit ? audit.error() : runs.error()).message);
    return;
  }
  // Said once a minute at most: under a write flood the retention runs every second.
  dropped_audit_rows_ += static_cast<std::uint64_t>(*audit);
  const std::int64_t now_ms = core::unix_time_ms();
  if (dropped_audit_rows_ > 0 && log_ && (now_ms - dropped_logged_ms_ >= 60'000 || now_ms < dropped_logged_ms_)) {
    log_("store: dropped the " + std::to_string(dropped_audit_rows_) + " oldest audit rows since the last report (retention: the newest " +
         std::to_string(std::max(limits.audit_max_rows, core::kAuditMinRows)) + ")");
    dropped_audit_rows_ = 0;
    dropped_logged_ms_ = now_ms;
  }
}

StoreHealth StoreWriter::health() const {
  std::lock_guard lock(mutex_);
  StoreHealth h = health_;
  h.pending = accepted_ - saved_.load();
  return h;
}

core::Status StoreWriter::write(const std::deque<Item>& batch, TuningSet& running) {
  auto tx = Transaction::begin(db_);
  if (!tx) return tx.error();
  AuditLog audit(db_);
  RetainedPoints retained(db_);
  RunTable runs(db_);
  bool tuning_changed = false;
  for (const Item& item : batch) {
    if (const auto* run = std::get_if<RunRecord>(&item)) {
      RunRecord r = *run;
      r.tuning_set_id = running.id;
      if (auto id = runs.insert(r); !id) return id.error();
      continue;
    }
    if (const auto* fault = std::get_if<runtime::FaultRecord>(&item)) {
      if (auto s = FaultTable(db_).add(*fault); !s) return s;
      continue;
    }
    if (const auto* sw = std::get_if<SetSwitch>(&item)) {
      if (tuning_changed)  // the edits so far belong to the set that ran until now
        if (auto s = TuningSetTable(db_).update(running); !s) return s;
      tuning_changed = false;
      running = sw->set;
      if (sw->persist)
        if (auto s = activate_audited(db_, sw->set.id, sw->source); !s) return s;
      continue;
    }
    for (const core::AuditEntry& e : std::get<std::vector<core::AuditEntry>>(item)) {
      if (auto s = audit.append(e); !s) return s;
      const points::PointDef* point = points::find_point(e.point);
      if (!point || !persisted_.contains(point->id)) continue;
      if (apply_tuning_point(running, point->id, e.new_value)) {
        running.modified_ms = e.unix_time_ms;
        tuning_changed = true;
      } else if (auto s = retained.put(e.point, e.new_value, e.unix_time_ms); !s) {
        return s;
      }
    }
  }
  if (tuning_changed)
    if (auto s = TuningSetTable(db_).update(running); !s) return s;
  return tx->commit();
}

bool StoreWriter::flush() {
  std::lock_guard writing(write_mutex_);
  std::deque<Item> batch;
  {
    std::lock_guard lock(mutex_);
    batch = pending_;  // copied, not taken: on failure it stays queued, in order
  }
  if (batch.empty()) return true;
  TuningSet running = running_;
  const auto status = write(batch, running);
  if (!status) {
    std::lock_guard lock(mutex_);
    ++health_.failures;
    if (health_.ok && log_) log_("store: cannot save (will retry): " + status.error().message);
    health_.ok = false;
    health_.last_error = status.error().message;
    return false;
  }
  {
    std::lock_guard lock(mutex_);
    if (!health_.ok && log_) log_("store: saving again after " + std::to_string(health_.failures) + " failed attempts");
    health_.ok = true;
    running_ = running;
    running_set_id_.store(running.id, std::memory_order_release);
    std::uint64_t changes = 0;
    for (const Item& item : batch) changes += std::holds_alternative<std::vector<core::AuditEntry>>(item) ? 1 : 0;
    pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(batch.size()));
    saved_.fetch_add(changes);
  }
  // The retention runs every so many saved items, not per batch: a DELETE per saved write would
  // double a busy store's work; the bound is exceeded by at most that many rows between runs.
  rows_since_retention_ += batch.size();
  if (rows_since_retention_ >= kItemsBetweenRetention) {
    rows_since_retention_ = 0;
    drop_beyond_retention();
  }
  return true;
}

void StoreWriter::loop() {
  auto pause = std::chrono::milliseconds(0);
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      if (pause.count() > 0) wake_.wait_for(lock, pause, [this] { return stop_; });
      wake_.wait(lock, [this] { return stop_ || !pending_.empty(); });
      if (stop_) return;
    }
    // Retry pause after a failure: 50 ms doubling to 800 ms, so a full disk is retried often
    // enough that a change is on disk within a second of the space coming back.
    pause = flush() ? std::chrono::milliseconds(0) : std::clamp(pause * 2, std::chrono::milliseconds(50), std::chrono::milliseconds(800));
  }
}

}  // namespace epa::store
