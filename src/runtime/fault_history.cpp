#include "runtime/fault_history.hpp"

#include <algorithm>
#include <cmath>

namespace epa::runtime {

namespace {

// "3 reads in a row failed, the last timed out (no answer in time)".
std::string failed_io(int count, const char* what, hal::IoStatus last) {
  const std::string how = last == hal::IoStatus::kTimeout
                              ? "timed out (no answer in time)"
                              : "reported an error (a link down, a refused connection, an exception answer or an undecodable value)";
  return std::to_string(count) + " " + what + " in a row failed, the last " + how;
}

}  // namespace

FaultRecord fault_record(const FaultEvent& e, std::int64_t time_ms) {
  std::string text(describe(e.code));
  if (e.code == FaultCode::kIoErrors) {  // which exchange failed, and how: what the engineer checks first
    std::string cause;
    if (e.failed_reads > 0) cause = failed_io(e.failed_reads, e.failed_reads == 1 ? "read" : "reads", e.last_read);
    if (e.failed_writes > 0)
      cause += (cause.empty() ? "" : "; ") + failed_io(e.failed_writes, e.failed_writes == 1 ? "write" : "writes", e.last_write);
    if (!cause.empty()) text += ": " + cause;
  }
  return {time_ms, e.code, e.mode, e.position_mm, e.setpoint_mm, e.valve_v, e.sensor_v, std::string(to_string(e.code)), std::move(text)};
}

std::int64_t fault_time_ms(const FaultEvent& e, double loop_now_s, std::int64_t now_ms) {
  const double age_s = std::max(0.0, loop_now_s - e.loop_time_s);
  return now_ms - std::llround(age_s * 1000.0);
}

void FaultHistory::load(std::span<const FaultRecord> newest_first, std::uint64_t total) {
  std::lock_guard lock(mutex_);
  entries_.assign(newest_first.begin(), newest_first.begin() + static_cast<std::ptrdiff_t>(
                                                                   std::min(newest_first.size(), kFaultHistoryEntries)));
  total_ = std::max<std::uint64_t>(total, entries_.size());
}

void FaultHistory::add(FaultRecord record) {
  std::lock_guard lock(mutex_);
  entries_.push_front(std::move(record));
  if (entries_.size() > kFaultHistoryEntries) entries_.pop_back();
  ++total_;
}

std::vector<FaultRecord> FaultHistory::newest(std::size_t limit, std::uint64_t* total) const {
  take_in();
  std::lock_guard lock(mutex_);
  if (total) *total = total_;
  const std::size_t n = std::min(limit, entries_.size());
  return {entries_.begin(), entries_.begin() + static_cast<std::ptrdiff_t>(n)};
}

std::uint64_t FaultHistory::total() const {
  take_in();
  std::lock_guard lock(mutex_);
  return total_;
}

std::uint64_t FaultHistory::copy_newest(std::span<FaultRecord> out) const {
  take_in();
  std::lock_guard lock(mutex_);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = i < entries_.size() ? entries_[i] : FaultRecord{};
  return total_;
}

}  // namespace epa::runtime
