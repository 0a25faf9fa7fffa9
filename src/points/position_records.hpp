#pragma once
// The position-record table: numbered moves an HMI starts with one control-word edge (record_select,
// then start). Each record is a target with its own speed limit, in-position window, law and side
// of approach. The
// write gate owns the table (it resolves a start into a move); its fields are points, persisted as
// retained values in the store and edited like tuning (Modbus after unlock, HTTP with the token).
#include <array>
#include <cstdint>

#include "points/point_id.hpp"

namespace epa::points {

inline constexpr int kKeepController = 255;  // a record's controller: run the move with the law running now

// Which side a record's move comes to its target from (pp-traj arriving while sliding:
// control/sliding_approach.hpp). kNearSide never passes the target; the other two approach from
// that side even when the piston stands on the other, passing the target by up to one approach
// length and back, as machine tools do against backlash.
enum RecordApproach : int { kNearSide = 0, kFromBelow = 1, kFromAbove = 2 };
// +1 from below, -1 from above, 0 from the near side (ApproachState::next_direction).
inline double approach_direction(int approach) { return approach == kFromBelow ? 1.0 : approach == kFromAbove ? -1.0 : 0.0; }

struct PositionRecord {
  double target_mm = 0.0;
  double speed_mm_s = 0.0;  // 0: no limit (the law's own step response)
  double window_mm = 0.0;   // 0: [motion] in_position_window_mm
  int controller = kKeepController;  // 0 pp, 1 pp-ngidz, 2 pp-ffidz, 3 pp-traj, 255 the running one
  int approach = kNearSide;          // RecordApproach
};

using PositionRecords = std::array<PositionRecord, kPositionRecords>;

// The record points: kRecordFields per record, field by field (kRecordTarget0 + field * kPositionRecords + record).
inline constexpr std::size_t kRecordFields = 5;
inline constexpr std::size_t kRecordPoints = kRecordFields * kPositionRecords;

// Which record field a point is, or nullptr when it is none: records[i].*field for record i + 1.
struct RecordField {
  std::size_t record = 0;  // 0-based
  enum Kind : std::uint8_t { kTarget, kSpeed, kWindow, kController, kApproach } kind = kTarget;
};
inline bool record_field(PointId id, RecordField& out) {
  const auto i = static_cast<std::size_t>(id);
  const auto first = static_cast<std::size_t>(PointId::kRecordTarget0);
  if (i < first || i >= first + kRecordPoints) return false;
  out.record = (i - first) % kPositionRecords;
  out.kind = static_cast<RecordField::Kind>((i - first) / kPositionRecords);
  return true;
}
inline double record_value(const PositionRecord& r, RecordField::Kind k) {
  switch (k) {
    case RecordField::kTarget: return r.target_mm;
    case RecordField::kSpeed: return r.speed_mm_s;
    case RecordField::kWindow: return r.window_mm;
    case RecordField::kController: return r.controller;
    case RecordField::kApproach: return r.approach;
  }
  return 0.0;
}
inline void set_record_value(PositionRecord& r, RecordField::Kind k, double v) {
  switch (k) {
    case RecordField::kTarget: r.target_mm = v; break;
    case RecordField::kSpeed: r.speed_mm_s = v; break;
    case RecordField::kWindow: r.window_mm = v; break;
    case RecordField::kController: r.controller = static_cast<int>(v); break;
    case RecordField::kApproach: r.approach = static_cast<int>(v); break;
  }
}

}  // namespace epa::points
