#include "runtime/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstring>

namespace epa::runtime {

std::vector<std::string> request_realtime(int fifo_priority, bool lock_memory) {
  std::vector<std::string> warnings;
  if (lock_memory && mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
    warnings.push_back(std::string("memory not locked (mlockall: ") + std::strerror(errno) + "); page faults may delay cycles");
  if (fifo_priority > 0) {
    sched_param param{};
    param.sched_priority = fifo_priority;
    if (const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param); rc != 0)
      warnings.push_back("real-time priority SCHED_FIFO " + std::to_string(fifo_priority) + " refused (" +
                         std::strerror(rc) + "); running at normal priority");
  }
  return warnings;
}

}  // namespace epa::runtime
