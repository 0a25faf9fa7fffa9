// Writes the runs for the diagnosis benchmark and the CLI test: `diagnose_data DIR [EFFECT] [RUNS]
// [SECONDS]` writes DIR/run-N.csv (epa-run/1), closed- and open-loop in turn, from the paper's
// model slightly perturbed, with EFFECT (a docs/formats.md name at its self-check size, or "none")
// hidden in the simulator. bench/diagnose_bench.sh times `epa diagnose` on 9 x 20 s of them.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/run_file.hpp"
#include "../tests/diag/diag_test_data.hpp"

int main(int argc, char** argv) {
  if (argc < 2) return std::fprintf(stderr, "usage: diagnose_data DIR [EFFECT|none] [RUNS] [SECONDS]\n"), 2;
  const std::string dir = argv[1], effect = argc > 2 ? argv[2] : "none";
  const int runs = argc > 3 ? std::atoi(argv[3]) : 9;
  const double seconds = argc > 4 ? std::atof(argv[4]) : 20.0;
  epa::testing::Hidden hidden;
  if (effect != "none") {
    auto kind = epa::plant::parse_effect(effect);
    if (!kind) return std::fprintf(stderr, "diagnose_data: %s\n", kind.error().message.c_str()), 2;
    hidden.effects = epa::testing::typical_effect(*kind);
  }
  const auto c = epa::testing::make_case(hidden, 1, static_cast<std::size_t>(runs), 0, seconds);
  for (std::size_t i = 0; i < c.train.size(); ++i) {
    const std::string path = dir + "/run-" + std::to_string(i + 1) + ".csv";
    if (auto s = epa::core::write_run_file(path, c.train[i]); !s) return std::fprintf(stderr, "%s\n", s.error().message.c_str()), 1;
  }
  return 0;
}
