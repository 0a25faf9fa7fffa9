#pragma once
// A command's text output (JSON, SVG, Markdown, CSV) to a file, or to standard output for "-".
#include <fstream>
#include <ostream>
#include <string>

#include "core/result.hpp"

namespace epa::app {

inline core::Status write_output(const std::string& path, const std::string& text, std::ostream& out) {
  if (path == "-") {
    out << text;
    return core::ok();
  }
  std::ofstream f(path, std::ios::trunc);
  if (!(f << text) || !f.flush()) return core::io_error("cannot write " + path);
  return core::ok();
}

}  // namespace epa::app
