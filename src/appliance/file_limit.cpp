#include "appliance/file_limit.hpp"

#include <sys/resource.h>

#include <cerrno>
#include <cstring>

namespace epa::appliance {

namespace {
std::string text(rlim_t v) { return v == RLIM_INFINITY ? "unlimited" : std::to_string(v); }
}  // namespace

std::string raise_file_limit() {
  rlimit r{};
  if (::getrlimit(RLIMIT_NOFILE, &r) != 0) return std::string("open files limit unknown: ") + std::strerror(errno);
  if (r.rlim_cur >= r.rlim_max) return "open files limit " + text(r.rlim_cur) + " (the hard limit)";
  const rlim_t was = r.rlim_cur;
  r.rlim_cur = r.rlim_max;
  if (::setrlimit(RLIMIT_NOFILE, &r) != 0)
    return "open files limit " + text(was) + ": raising it to the hard limit " + text(r.rlim_max) + " failed: " + std::strerror(errno);
  return "open files limit raised from " + text(was) + " to the hard limit " + text(r.rlim_max);
}

}  // namespace epa::appliance
