#pragma once
// The run recorder's writer: a thread that takes RecordRequests from the loop and writes the
// requested samples from the SampleRing as epa-run/1 files, off the real-time thread, so a rig's
// runs feed `epa identify` and `epa diagnose` directly. One file per move (if enabled), one per
// explicit request, and one per excitation experiment (EXCITE), complete or ended early.
#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "core/run.hpp"
#include "runtime/loop_channels.hpp"
#include "runtime/run_directory_quota.hpp"

namespace epa::runtime {

struct RecorderConfig {
  std::string directory = "runs";
  bool per_move = true;
  double Ts = 0.005;
  std::string source = "appliance";  // run-file metadata: sim backend or which rig
  // What a client's flood of moves or record requests can put on the disk: the run files stay
  // within quota_bytes (the oldest deleted), move files are written at most move_files_per_minute
  // (the rest counted, not written), and nothing is written while the disk has less than
  // min_free_bytes free, so the tuning store keeps room to save.
  std::uint64_t quota_bytes = 512ull * 1024 * 1024;
  double move_files_per_minute = 60;
  std::uint64_t min_free_bytes = 256ull * 1024 * 1024;
  // A move handed to on_move_with_rest() holds up to this much before its first cycle, back to the
  // end of the move before it: the rest it started from (its file holds the move alone).
  double rest_before_s = 1.0;
};

class Recorder {
 public:
  using Log = std::function<void(const std::string&)>;
  using Written = std::function<void(const std::string& path, const core::Run& run)>;  // e.g. into the run history
  using MoveWithRest = std::function<void(const core::Run& move)>;
  Recorder(RecorderConfig config, LoopChannels& channels, Log log = {}, Written written = {});
  // Each move whose file was written, again with the rest before it (rest_before_s; metadata as its
  // file's, and rest_before_samples): what the model-health monitor judges. Before start().
  void on_move_with_rest(MoveWithRest f) { move_with_rest_ = std::move(f); }
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  void start();  // the writer thread polls every 20 ms
  void stop();   // writes what is pending, then joins

  // Writes every pending request now (the thread calls this; tests may call it directly).
  // Returns the number of files written.
  std::size_t process_pending();

  std::uint64_t files_written() const { return files_written_.load(); }
  // Files not written: move files beyond the rate, anything while the disk was low.
  std::uint64_t files_skipped() const { return files_skipped_.load(); }
  std::string last_file() const;

 private:
  void write(const RecordRequest& request);
  void hand_over_with_rest(const RecordRequest& request, const core::Run& move) const;
  bool may_write(const RecordRequest& request);  // the rate and the disk's free space

  RecorderConfig config_;
  LoopChannels& ch_;
  Log log_;
  Written written_;
  MoveWithRest move_with_rest_;
  std::uint64_t last_move_end_ = 0;  // the sample after the last move the loop reported: a rest before a move starts there
  std::atomic<bool> stop_{false};
  std::thread thread_;
  std::atomic<std::uint64_t> files_written_{0};
  std::atomic<std::uint64_t> files_skipped_{0};
  std::optional<RunDirectoryQuota> quota_;  // built on the first write: the directory may not exist before
  double move_tokens_ = 0;                   // the move-file rate's bucket, and when it was last filled
  std::chrono::steady_clock::time_point tokens_at_{};
  std::uint64_t request_count_ = 0;
  std::uint64_t excitation_count_ = 0;
  mutable std::mutex last_file_mutex_;
  std::string last_file_;
};

}  // namespace epa::runtime
