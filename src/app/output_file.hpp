#pragma once
// A command's text output (JSON, SVG, Markdown, CSV) to a file, written atomically, or to
// standard output for "-".
#include <ostream>
#include <string>

#include "core/atomic_file.hpp"
#include "core/result.hpp"

namespace epa::app {

inline core::Status write_output(const std::string& path, const std::string& text, std::ostream& out) {
  if (path == "-") {
    out << text;
    return core::ok();
  }
  if (auto s = core::write_file_atomically(path, text); !s) return core::io_error("cannot write " + path + ": " + s.error().message);
  return core::ok();
}

}  // namespace epa::app
