#pragma once
// The store thread. The Modbus and web threads hand it accepted changes (AuditSink::record), the
// recorder hands it run files and the supervisor the faults the loop latched (record_fault); it
// writes them in one transaction per batch (group commit),
// appending the audit entries and applying the persisted points to the running tuning set or
// the retained points. The saved counter advances only after COMMIT returned, with
// synchronous=FULL, so "saved" means on disk. A failed write (disk full, read-only) keeps the
// batch and retries with a growing pause; nothing is dropped and the counter does not lie.
// The scan cycle never waits for any of this.
#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <variant>

#include "core/audit.hpp"
#include "points/point_id.hpp"
#include "runtime/fault_history.hpp"
#include "store/database.hpp"
#include "store/run_record.hpp"
#include "store/tuning_set.hpp"

namespace epa::store {

// What the store may hold: the audit log's and the run history's newest rows (the oldest dropped,
// logged), and the free space below which it warns (ChangeCounters::disk_low) before it cannot save.
struct StoreLimits {
  std::int64_t audit_max_rows = 1'000'000;
  std::int64_t runs_max_rows = 100'000;
  std::uint64_t min_free_bytes = 256ull * 1024 * 1024;
};

struct StoreHealth {
  bool ok = true;               // the last write succeeded
  std::string last_error;       // of the last failed write
  std::uint64_t pending = 0;    // accepted, not yet on disk
  std::uint64_t failures = 0;   // failed write attempts since start
};

class StoreWriter final : public core::AuditSink {
 public:
  using Log = std::function<void(const std::string&)>;

  // `running` is the row of the tuning set the loop runs: persisted tuning points edit it (the
  // write gate owns the running tuning; this is its stored image). `persisted` names the points
  // whose new values are kept (the register map's persisted column).
  StoreWriter(Database db, TuningSet running, std::set<points::PointId> persisted, Log log = {});
  ~StoreWriter() override;
  StoreWriter(const StoreWriter&) = delete;
  StoreWriter& operator=(const StoreWriter&) = delete;

  void set_limits(const StoreLimits& limits);  // before start()
  void start();
  // Writes what is pending (trying for at most `drain_s`), then joins. Logs what could not be saved.
  void stop(double drain_s = 2.0);

  void record(const std::vector<core::AuditEntry>& change) override;
  core::ChangeCounters counters() const override;
  void record_run(const RunRecord& run);
  // A fault for the fault history (store/fault_table.hpp: the newest 64 are kept).
  void record_fault(const runtime::FaultRecord& fault);
  // The loop runs `set` from now on (the write gate switched it): persisted tuning points edit its
  // row from here on, in order with the changes before. `persist`: it also becomes the store's
  // active set (audited "active_tuning_set" with `source`), what the next start loads.
  void switch_running_set(const TuningSet& set, bool persist, const std::string& source);

  StoreHealth health() const;
  // The set the loop runs, as of the last write (a switch still pending is not in it yet).
  TuningSet running_set() const;
  // Its id, without the lock: for a thread of low priority, which must not hold what the
  // interfaces wait for.
  std::int64_t running_set_id() const noexcept { return running_set_id_.load(std::memory_order_acquire); }

  // One write attempt of everything pending (the thread calls this; tests may call it directly).
  bool flush();

 private:
  struct SetSwitch {
    TuningSet set;
    bool persist = false;
    std::string source;
  };
  using Item = std::variant<std::vector<core::AuditEntry>, RunRecord, SetSwitch, runtime::FaultRecord>;
  core::Status write(const std::deque<Item>& batch, TuningSet& running);
  void drop_beyond_retention();  // after a saved batch, now and then
  void loop();

  Database db_;
  TuningSet running_;  // owned by the writing side (the thread, or flush() in tests)
  std::atomic<std::int64_t> running_set_id_{0};  // running_.id
  std::set<points::PointId> persisted_;
  Log log_;

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Item> pending_;
  std::uint64_t accepted_ = 0;
  std::atomic<std::uint64_t> saved_{0};
  StoreHealth health_;
  bool stop_ = false;
  std::mutex write_mutex_;  // one writer at a time: the thread, or a direct flush()
  StoreLimits limits_;
  std::uint64_t rows_since_retention_ = 1000;  // under write_mutex_; the first saved batch runs the retention
  std::uint64_t dropped_audit_rows_ = 0;       // not reported yet (under write_mutex_)
  std::int64_t dropped_logged_ms_ = 0;
  mutable std::int64_t disk_checked_ms_ = 0;  // disk_low_ is refreshed at most once a second (under mutex_)
  mutable bool disk_low_ = false;
  bool disk_low_now() const;  // mutex_ held
  std::thread thread_;
};

}  // namespace epa::store
