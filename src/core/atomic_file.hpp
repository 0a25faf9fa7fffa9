#pragma once
// Writes a file so that a reader sees the old contents or the whole new ones, never half: the
// contents go to a uniquely named temporary file in the same folder (so the rename is atomic),
// which is then renamed over `path`, or removed on failure. Errors are io_errors that say what
// failed; callers put their own context (which file, of what kind) in front.
#include <functional>
#include <ostream>
#include <string>

#include "core/result.hpp"

namespace epa::core {

Status write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);
Status write_file_atomically(const std::string& path, const std::string& text);

}  // namespace epa::core
