#pragma once
// The appliance's commissioning service as the interfaces see it (appliance/commissioning_service.*
// implements it): Modbus starts and aborts it through the write gate's commission_command point
// and reads its state points; the status page starts it with a spec and shows its progress.
#include <cstdint>
#include <string>

namespace epa::points {

// Numeric values are the Modbus interface (commission_stage, commission_verdict): append only.
struct CommissionView {
  bool available = false;  // a service is attached
  bool running = false;
  int stage = 0;           // 0 idle, 1 exciting, 2 identifying, 3 designing, 4 simulating, 5 saving, 6 verifying, 7 done
  int verdict = 0;         // 0 none, 1 deployed, 2 rolled-back, 3 aborted
  double percent = 0.0;
};

enum class CommissionStart : std::uint8_t { kStarted, kBadSpec, kBusy };

struct CommissionStartResult {
  CommissionStart result = CommissionStart::kStarted;
  std::string message;  // why not: the spec's key and value, or what is running
};

class CommissionControl {
 public:
  virtual ~CommissionControl() = default;
  // `spec_json` may be empty (the defaults); `source` is who asked, for the audit trail.
  virtual CommissionStartResult start(const std::string& spec_json, const std::string& source) = 0;
  virtual bool abort(const std::string& source) = 0;  // false: nothing runs
  virtual CommissionView view() const = 0;
};

}  // namespace epa::points
