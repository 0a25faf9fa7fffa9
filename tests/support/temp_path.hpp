#pragma once
// A fresh path in the temp folder, unique per process and call (ctest runs test cases in parallel
// processes), and a folder made there for one test and removed with it.
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <system_error>

namespace epa::test {

inline std::filesystem::path unique_temp_path(const std::string& name) {
  static int counter = 0;
  const auto now = std::chrono::system_clock::now().time_since_epoch().count();
  return std::filesystem::temp_directory_path() / ("epa-test-" + std::to_string(getpid()) + "-" + std::to_string(now) + "-" +
                                                   std::to_string(counter++) + "-" + name);
}

// A fresh, empty folder for one test; it and everything in it go when the test ends, also when an
// ASSERT leaves the test early.
struct TempDir {
  const std::filesystem::path path;
  explicit TempDir(const std::string& name) : path(unique_temp_path(name)) { std::filesystem::create_directories(path); }
  ~TempDir() {
    std::error_code ignored;  // a test may have removed it already
    std::filesystem::remove_all(path, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
};

}  // namespace epa::test
