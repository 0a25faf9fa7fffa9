#pragma once
// Numbers in messages, file names and metadata: printf's %g (6 significant digits, no trailing
// zeros, locale-independent for the "C" locale the appliance runs in).
#include <cstdio>
#include <string>

namespace epa::core {

inline std::string format_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

}  // namespace epa::core
