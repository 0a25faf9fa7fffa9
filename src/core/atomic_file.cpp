#include "core/atomic_file.hpp"

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>

namespace epa::core {

namespace {
std::string unique_suffix() {
  static std::atomic<unsigned> counter{0};
  const auto now = std::chrono::steady_clock::now().time_since_epoch().count();
  return std::to_string(now) + "-" + std::to_string(counter++);
}
}  // namespace

Status write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  namespace fs = std::filesystem;
  std::error_code ec;
  try {
    const fs::path tmp = fs::path(path) += ".tmp-" + unique_suffix();
    errno = 0;
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out)
      return io_error("cannot create " + tmp.string() + (errno != 0 ? std::string(": ") + std::strerror(errno) : std::string()));
    write(out);
    out.close();
    if (!out) {
      fs::remove(tmp, ec);
      return io_error("writing '" + tmp.string() + "' failed");
    }
    fs::rename(tmp, path, ec);
    if (ec) {
      const std::string reason = ec.message();
      fs::remove(tmp, ec);
      return io_error("rename failed: " + reason);
    }
  } catch (const std::exception& e) {
    return io_error(e.what());
  }
  return ok();
}

Status write_file_atomically(const std::string& path, const std::string& text) {
  return write_file_atomically(path, [&text](std::ostream& out) { out << text; });
}

}  // namespace epa::core
