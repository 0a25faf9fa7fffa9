#pragma once
// Numbers in messages, file names and metadata: printf's %g (6 significant digits, no trailing
// zeros, locale-independent for the "C" locale the appliance runs in), or, where a reader must get
// the same double back (a move's from and target, which its metrics are recomputed against), the
// shortest text that reads back exactly.
#include <charconv>
#include <cstdio>
#include <string>

namespace epa::core {

inline std::string format_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

inline std::string format_exact(double v) {
  char buf[32];
  return std::string(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

}  // namespace epa::core
