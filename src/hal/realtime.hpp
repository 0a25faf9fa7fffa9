#pragma once
// Real-time set-up of a thread (the scan cycle; the remote I/O simulator's threads): lock memory (no page faults mid-cycle), ask for SCHED_FIFO,
// and hold a PM QoS request on /dev/cpu_dma_latency so the CPU does not sleep in idle states it
// takes longer to wake from than the limit (measured here: median wake-up 25 us without it,
// 13 us with it; cyclictest does the same by default). Any of these may be refused (no
// privilege, containers): the appliance then runs best-effort, and each refusal is returned as a
// warning for the log, never as a failure.
#include <cstddef>
#include <string>
#include <vector>

namespace epa::hal {

struct RealtimeRequest {
  int fifo_priority = 80;       // 0: stay at normal priority
  bool lock_memory = true;
  int cpu_dma_latency_us = 0;   // < 0: leave the CPU's idle states alone
};

// The PM QoS request lasts as long as the process (the kernel drops it when the file closes).
std::vector<std::string> request_realtime(const RealtimeRequest& request);

// The stack size of threads created from now on (std::thread included). glibc's default is the
// stack rlimit, usually 8 MiB; the appliance's threads need far less, and every stack that
// exists when the loop locks memory is locked whole.
void set_default_thread_stack(std::size_t bytes);

}  // namespace epa::hal
