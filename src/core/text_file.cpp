#include "core/text_file.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace epa::core {

namespace {

const char* file_type_name(mode_t mode) {
  if (S_ISDIR(mode)) return "folder";
  if (S_ISCHR(mode)) return "character device";
  if (S_ISBLK(mode)) return "block device";
  if (S_ISFIFO(mode)) return "FIFO";
  if (S_ISSOCK(mode)) return "socket";
  return "special file";
}

// Closes the descriptor on every path out of the reader.
struct Descriptor {
  int fd;
  ~Descriptor() {
    if (fd >= 0) ::close(fd);
  }
};

Error above_cap(const std::string& path, const std::string& what, const std::string& size, std::size_t max_bytes) {
  return io_error(path + ": " + size + ", above the " + byte_size_text(max_bytes) + " cap for a " + what);
}

}  // namespace

std::string byte_size_text(std::size_t bytes) {
  if (bytes >= kMiB && bytes % kMiB == 0) return std::to_string(bytes / kMiB) + " MiB";
  if (bytes >= 1024 && bytes % 1024 == 0) return std::to_string(bytes / 1024) + " KiB";
  return std::to_string(bytes) + " bytes";
}

Result<std::string> read_text_file(const std::string& path, const std::string& what, std::size_t max_bytes) {
  // O_NONBLOCK: opening a FIFO with no writer would otherwise wait for ever before fstat can refuse it.
  Descriptor file{::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY)};
  if (file.fd < 0) return io_error(path + ": cannot open the " + what + ": " + std::strerror(errno));
  struct stat st {};
  if (::fstat(file.fd, &st) != 0) return io_error(path + ": cannot read the " + what + ": " + std::strerror(errno));
  if (!S_ISREG(st.st_mode))
    return io_error(path + ": not a regular file (" + file_type_name(st.st_mode) + "): cannot read the " + what);
  if (static_cast<std::size_t>(st.st_size) > max_bytes)
    return above_cap(path, what, std::to_string(st.st_size) + " bytes", max_bytes);

  std::string text;
  text.resize(static_cast<std::size_t>(st.st_size) + 1);  // one byte more shows a file that grew
  std::size_t used = 0;
  for (;;) {
    if (used == text.size()) {
      if (used > max_bytes) return above_cap(path, what, "more than " + std::to_string(max_bytes) + " bytes", max_bytes);
      text.resize(std::min(used * 2 + 4096, max_bytes + 1));
    }
    const ssize_t n = ::read(file.fd, text.data() + used, text.size() - used);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return io_error(path + ": cannot read the " + what + ": " + std::strerror(errno));
    if (n == 0) break;
    used += static_cast<std::size_t>(n);
  }
  if (used > max_bytes) return above_cap(path, what, "more than " + std::to_string(max_bytes) + " bytes", max_bytes);
  text.resize(used);
  return text;
}

}  // namespace epa::core
