#pragma once
// A fresh path in the temp folder, unique per process and call (ctest runs test cases in parallel
// processes). Nothing is created there.
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>

namespace epa::test {

inline std::filesystem::path unique_temp_path(const std::string& name) {
  static int counter = 0;
  const auto now = std::chrono::system_clock::now().time_since_epoch().count();
  return std::filesystem::temp_directory_path() / ("epa-test-" + std::to_string(getpid()) + "-" + std::to_string(now) + "-" +
                                                   std::to_string(counter++) + "-" + name);
}

}  // namespace epa::test
