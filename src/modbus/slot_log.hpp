#pragma once
// What the Modbus server says about its connection slots, bounded: a reconnecting crowd is
// evicted or refused hundreds of times a minute, and a line per event filled the disk and hid the
// real events. Evictions and refusals are counted (totals for /metrics) and told in one summary
// line a minute at most ("412 connections evicted and 30 refused in the last 60 s"); the first
// is told at once. Disconnect lines of other kinds pass, kDisconnectLines a window; the rest
// are counted in the summary. Not thread-safe: the server's one thread uses it.
#include <cstdint>
#include <string>

namespace epa::modbus {

class SlotLog {
 public:
  static constexpr std::int64_t kWindowNs = 60'000'000'000;
  static constexpr int kDisconnectLines = 20;

  void evicted(std::int64_t now_ns) { note(now_ns), ++evicted_, ++evicted_total_; }
  void refused(std::int64_t now_ns) { note(now_ns), ++refused_, ++refused_total_; }
  void out_of_descriptors(std::int64_t now_ns) { note(now_ns), ++no_descriptors_; }  // accept failed: EMFILE/ENFILE
  // Whether a disconnect line may be logged now (else it is counted for the summary).
  bool disconnect_line(std::int64_t now_ns) {
    if (now_ns - disconnect_window_ns_ >= kWindowNs) disconnect_window_ns_ = now_ns, disconnect_lines_ = 0;
    if (disconnect_lines_ < kDisconnectLines) return ++disconnect_lines_, true;
    note(now_ns);
    ++unlogged_;
    return false;
  }
  // The summary line due at `now_ns` ("" when none is); `closing`: what is pending, whenever.
  std::string due(std::int64_t now_ns, int max_clients, int max_per_address, bool closing = false) {
    if (pending_since_ns_ < 0 || (!closing && now_ns - last_line_ns_ < kWindowNs)) return "";
    std::string line = "modbus: " + std::to_string(evicted_) + " connection" + (evicted_ == 1 ? "" : "s") + " evicted and " +
                       std::to_string(refused_) + " refused in the last " +
                       std::to_string((now_ns - pending_since_ns_) / 1'000'000'000) + " s (max_clients " +
                       std::to_string(max_clients) + ", max_clients_per_address " + std::to_string(max_per_address) + ")";
    if (unlogged_ > 0) line += "; " + std::to_string(unlogged_) + " disconnect lines not logged";
    if (no_descriptors_ > 0)
      line += "; accepting paused " + std::to_string(no_descriptors_) + " times: out of file descriptors (LimitNOFILE)";
    evicted_ = refused_ = unlogged_ = no_descriptors_ = 0;
    pending_since_ns_ = -1;
    last_line_ns_ = now_ns;
    return line;
  }
  std::uint64_t evicted_total() const { return evicted_total_; }
  std::uint64_t refused_total() const { return refused_total_; }

 private:
  void note(std::int64_t now_ns) {
    if (pending_since_ns_ < 0) pending_since_ns_ = now_ns;
  }
  std::uint64_t evicted_ = 0, refused_ = 0, unlogged_ = 0, no_descriptors_ = 0, evicted_total_ = 0, refused_total_ = 0;
  std::int64_t pending_since_ns_ = -1;
  std::int64_t last_line_ns_ = -kWindowNs - 1;
  std::int64_t disconnect_window_ns_ = -kWindowNs - 1;
  int disconnect_lines_ = 0;
};

}  // namespace epa::modbus
