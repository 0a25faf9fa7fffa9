#pragma once
// Free space on the file system that holds a path, for the watchers that stop
// writing before the disk is full (the recorder's runs, the store's warning).
// statvfs: what an unprivileged writer can use (f_bavail), not the blocks
// reserved for root.
#include <sys/statvfs.h>

#include <cstdint>
#include <optional>
#include <string>

namespace epa::core {

inline std::optional<std::uint64_t> free_bytes(const std::string &path) {
  struct statvfs s {};
  if (::statvfs(path.c_str(), &s) != 0)
    return std::nullopt;
  return static_cast<std::uint64_t>(s.f_bavail) * s.f_frsize;
}

} // namespace epa::core
