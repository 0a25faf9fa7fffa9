#pragma once
// The compiler-style start of a message about a place in a TOML file, "file:line: ", which editors
// jump to; the line left out when the parser gave none (0). For every TOML reader.
#include <string>
#include <toml++/toml.h>

namespace epa::core {

inline std::string at_line(const std::string& file, const toml::source_region& where) {
  return file + (where.begin.line > 0 ? ":" + std::to_string(where.begin.line) : std::string()) + ": ";
}

}  // namespace epa::core
