#pragma once
// What the write gate answers: accepted, or refused with a protocol-neutral kind and a reason.
// Each interface maps the kind to its own error (modbus/refusal_exception.hpp,
// web/refusal_status.hpp); the reason goes out as it is.
#include <cstdint>
#include <string>

namespace epa::points {

enum class Refusal : std::uint8_t {
  kNone,
  kNotWritable,   // a read-only point, or one with nothing behind it
  kInvalidValue,  // out of range, not whole, tuning that does not validate
  kForbidden,     // no write rights, or a tuning point while locked
  kConflict,      // not now: wrong mode, a fault latched, a recording too soon
  kBusy,          // the loop's command queue is full: try again
};

struct GateResult {
  Refusal refusal = Refusal::kNone;
  std::string reason;  // names the point and what was wrong
  bool accepted() const { return refusal == Refusal::kNone; }
};

}  // namespace epa::points
