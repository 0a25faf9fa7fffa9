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
  // What is mapped now holds everything the scan cycle touches (its stack, its buffers, made
  // before it starts, and the code), so MCL_CURRENT; with MCL_ONFAULT a page is locked once it
  // is touched, so libraries the appliance maps but the loop never runs (pagmo: 20 MB) stay out,
  // and after its first cycles the loop runs on locked pages only. MCL_FUTURE would also lock every
  // later thread's whole stack and every page the HTTP, Modbus and store threads map: 632 MB with
  // 71 threads, where this locks about 10 MB.
  if (r.lock_memory && mlockall(MCL_CURRENT | MCL_ONFAULT) != 0)
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

void set_default_thread_stack(std::size_t bytes) {
  pthread_attr_t attr;
  if (pthread_attr_init(&attr) != 0) return;
  if (pthread_attr_setstacksize(&attr, bytes) == 0) pthread_setattr_default_np(&attr);
  pthread_attr_destroy(&attr);
}

}  // namespace epa::hal
