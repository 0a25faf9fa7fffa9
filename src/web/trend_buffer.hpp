#pragma once
// What the page plots: the web thread samples the published snapshot every 50 ms into a fixed
// ring of the last 30 s, and keeps the recent finished moves (seen as last_move.number changing).
// Thread-safe: one sampler, any number of HTTP worker readers.
#include <cstdint>
#include <mutex>
#include <vector>

#include "control/controller_kind.hpp"
#include "runtime/snapshot.hpp"

namespace epa::web {

struct TrendPoint {
  double t_s = 0, setpoint_mm = 0, position_mm = 0, valve_v = 0;
};

struct MoveRecord {
  runtime::MoveMetricsView metrics;  // with the law that ran it
  double finished_s = 0;  // snapshot time when it was seen
};

class TrendBuffer {
 public:
  static constexpr double kPeriodS = 0.05;
  static constexpr double kWindowS = 30.0;
  static constexpr std::size_t kMaxMoves = 20;

  TrendBuffer();
  void add(const runtime::Snapshot& s);  // allocation-free once constructed (moves: bounded)
  std::vector<TrendPoint> points() const;  // oldest first
  std::vector<MoveRecord> moves() const;   // newest first

 private:
  mutable std::mutex mutex_;
  std::vector<TrendPoint> ring_;
  std::size_t next_ = 0, size_ = 0;
  std::vector<MoveRecord> moves_;
  std::uint32_t last_move_number_ = 0;
};

}  // namespace epa::web
