#pragma once
// Numbers in the TOML files we write: the shortest text that reads back to the same double, so
// identified values round-trip exactly and printed ones stay as printed (0.9094, not
// 0.90939999999999999, which is what toml++'s own printer gives).
#include <charconv>
#include <string>
#include <vector>

namespace epa::core {

inline std::string toml_float(double v) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, res.ptr);
  if (s.find_first_of(".en") == std::string::npos) s += ".0";  // keep TOML floats floats
  return s;
}

inline std::string toml_float_array(const std::vector<double>& values) {
  std::string s = "[";
  for (std::size_t i = 0; i < values.size(); ++i) s += (i ? ", " : "") + toml_float(values[i]);
  return s + "]";
}

}  // namespace epa::core
