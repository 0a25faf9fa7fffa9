#include "web/trend_buffer.hpp"

#include <cmath>

namespace epa::web {

TrendBuffer::TrendBuffer() : ring_(static_cast<std::size_t>(std::lround(kWindowS / kPeriodS))) { moves_.reserve(kMaxMoves); }

void TrendBuffer::add(const runtime::Snapshot& s) {
  std::lock_guard lock(mutex_);
  ring_[next_] = {s.time_s, s.setpoint_mm, s.position_mm, s.valve_v};
  next_ = (next_ + 1) % ring_.size();
  if (size_ < ring_.size()) ++size_;
  if (s.last_move.number != 0 && s.last_move.number != last_move_number_) {
    if (moves_.size() == kMaxMoves) moves_.erase(moves_.begin());
    moves_.push_back({s.last_move, s.time_s});
  }
  last_move_number_ = s.last_move.number;
}

std::vector<TrendPoint> TrendBuffer::points() const {
  std::lock_guard lock(mutex_);
  std::vector<TrendPoint> out;
  out.reserve(size_);
  const std::size_t first = (next_ + ring_.size() - size_) % ring_.size();
  for (std::size_t i = 0; i < size_; ++i) out.push_back(ring_[(first + i) % ring_.size()]);
  return out;
}

std::vector<MoveRecord> TrendBuffer::moves() const {
  std::lock_guard lock(mutex_);
  return {moves_.rbegin(), moves_.rend()};
}

}  // namespace epa::web
