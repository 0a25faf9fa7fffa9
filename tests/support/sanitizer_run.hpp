#pragma once
// True in the suite's run under the sanitizers (EPA_SANITIZER_RUN=1, set by the asan test preset).
// That run judges memory and undefined behaviour on the paths the tests reach; the few tests that
// repeat the same paths over more data to judge a rate or a figure do the paths once there, and
// the release run judges the figures (CI's time budget: they took most of the ASan run's 25 min).
#include <cstdlib>
#include <string_view>

namespace epa::test {

inline bool sanitizer_run() {
  const char* value = std::getenv("EPA_SANITIZER_RUN");
  return value != nullptr && std::string_view(value) == "1";
}

}  // namespace epa::test
