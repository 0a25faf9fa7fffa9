// Test-only LD_PRELOAD shim: makes a directory behave as if its file system had become read-only
// (as ext4 does with errors=remount-ro), which a test cannot otherwise do while the database is
// open (the kernel refuses to remount a file system with files open for writing). While the file
// named by EPA_EROFS_TRIGGER exists, every write, truncate and sync of a file under EPA_EROFS_DIR
// fails with EROFS. Used by tests/hardening/fault_injection_test.py only.
#include <dlfcn.h>
#include <sys/types.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace {

bool read_only(int fd) {
  const char* dir = getenv("EPA_EROFS_DIR");
  const char* trigger = getenv("EPA_EROFS_TRIGGER");
  if (!dir || !trigger || access(trigger, F_OK) != 0) return false;
  char link[64], path[4096];
  snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
  const ssize_t n = readlink(link, path, sizeof path - 1);
  if (n <= 0) return false;
  path[n] = '\0';
  return std::strncmp(path, dir, std::strlen(dir)) == 0;
}

}  // namespace

#define FORWARD(ret, name, params, args)                                              \
  extern "C" ret name params {                                                        \
    using Real = ret(*) params;                                                       \
    static Real real = reinterpret_cast<Real>(dlsym(RTLD_NEXT, #name));               \
    if (read_only(fd)) {                                                              \
      errno = EROFS;                                                                  \
      return -1;                                                                      \
    }                                                                                 \
    return real args;                                                                 \
  }

FORWARD(ssize_t, write, (int fd, const void* buf, size_t count), (fd, buf, count))
FORWARD(ssize_t, pwrite, (int fd, const void* buf, size_t count, off_t offset), (fd, buf, count, offset))
FORWARD(ssize_t, pwrite64, (int fd, const void* buf, size_t count, off_t offset), (fd, buf, count, offset))
FORWARD(int, fsync, (int fd), (fd))
FORWARD(int, fdatasync, (int fd), (fd))
FORWARD(int, ftruncate, (int fd, off_t length), (fd, length))
FORWARD(int, ftruncate64, (int fd, off_t length), (fd, length))
