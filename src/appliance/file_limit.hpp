#pragma once
// The process's open-files limit. Each HTTP and Modbus connection is a descriptor, and a process
// started with the usual soft limit of 1024 ran out under 1300 idle HTTP connections (then new
// Modbus connections waited and the page starved). The soft limit may be raised to the hard one
// without privilege (the unit sets both with LimitNOFILE), so serve does that at start.
#include <string>

namespace epa::appliance {

// Raises RLIMIT_NOFILE's soft limit to its hard limit; returns the line to log (what it is now).
std::string raise_file_limit();

}  // namespace epa::appliance
