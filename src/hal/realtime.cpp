#include "hal/realtime.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>

namespace epa::hal {

std::vector<std::string> request_realtime(const RealtimeRequest& r) {
  std::vector<std::string> warnings;
  if (r.lock_memory && mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
    warnings.push_back(std::string("memory not locked (mlockall: ") + std::strerror(errno) + "); page faults may delay cycles");
  if (r.fifo_priority > 0) {
    sched_param param{};
    param.sched_priority = r.fifo_priority;
    if (const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param); rc != 0)
      warnings.push_back("real-time priority SCHED_FIFO " + std::to_string(r.fifo_priority) + " refused (" +
                         std::strerror(rc) + "); running at normal priority");
  }
  if (r.cpu_dma_latency_us >= 0) {
    static int qos_fd = -1;  // kept open for the life of the process: closing it ends the request
    if (qos_fd < 0) qos_fd = open("/dev/cpu_dma_latency", O_WRONLY | O_CLOEXEC);
    const std::int32_t limit = r.cpu_dma_latency_us;
    if (qos_fd < 0 || write(qos_fd, &limit, sizeof limit) != static_cast<ssize_t>(sizeof limit))
      warnings.push_back(std::string("CPU idle-state limit not set (/dev/cpu_dma_latency: ") + std::strerror(errno) +
                         "); wake-up latency may be higher");
  }
  return warnings;
}

}  // namespace epa::hal
