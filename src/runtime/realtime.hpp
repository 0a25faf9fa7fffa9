#pragma once
// Real-time set-up of the loop thread: lock memory (no page faults mid-cycle) and ask for
// SCHED_FIFO. Either may be refused (no privilege, container limits): the appliance then runs
// best-effort, and each refusal is returned as a warning for the log, never as a failure.
#include <string>
#include <vector>

namespace epa::runtime {

std::vector<std::string> request_realtime(int fifo_priority, bool lock_memory);

}  // namespace epa::runtime
