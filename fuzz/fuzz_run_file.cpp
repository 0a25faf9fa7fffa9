// Run-file text (epa-run/1) into the reader that `epa identify`, `epa diagnose` and the tests use:
// a run or a parse error, never a crash; with and without an expected Ts. A run that parses is
// written back and read again, so the writer meets every odd run the reader lets through (the
// reread may refuse it: the writer rounds times, and a run with odd times is refused, not crashed).
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "core/run_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace epa::core;
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::istringstream in(text);
  auto run = parse_run(in, "fuzz.csv");
  std::istringstream in_ts(text);
  (void)parse_run(in_ts, "fuzz.csv", 0.005);
  if (!run) return 0;
  std::ostringstream out;
  write_run(out, *run);
  std::istringstream back(out.str());
  (void)parse_run(back, "fuzz-rewritten.csv");
  return 0;
}
