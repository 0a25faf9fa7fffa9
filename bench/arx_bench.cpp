// ARX estimation benchmark (run by bench/arx_vs_octave.sh, not by ctest).
//
//   arx_bench DATA.csv [samples] [repeats]
//
// Generates `samples` samples from the paper's eq 9 (na = 3, nb = 3, nk = 1) driven by a seeded
// multi-level input, with seeded white equation noise e (so ARX is the true structure and least
// squares is consistent): A(q) y = B(q) u + e. Writes them as CSV (u, y; 17 significant digits, so
// Octave reads exactly the same numbers), estimates the model `repeats` times with our estimator
// and prints the fastest and median time and the coefficients, one `key value...` per line.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/paper_reference.hpp"
#include "core/random.hpp"
#include "ident/arx_estimator.hpp"

int main(int argc, char** argv) {
  if (argc < 2 || argv[1][0] == '-') {  // the first argument is a file it writes: never an option
    std::fprintf(stderr, "usage: arx_bench DATA.csv [samples=100000] [repeats=20]\n");
    return 2;
  }
  const std::string path = argv[1];
  const std::size_t n = argc > 2 ? std::strtoul(argv[2], nullptr, 10) : 100000;
  const int repeats = argc > 3 ? std::atoi(argv[3]) : 20;
  const auto model = epa::core::paper::model();
  const auto& A = model.A;
  const auto& B = model.B;

  epa::core::Random rng(2024);
  epa::ident::Segment s;
  s.name = "bench";
  s.u.resize(n);
  s.y.assign(n, 0.0);
  double level = 0.0;
  constexpr double kNoiseStd = 0.01;  // V of equation noise
  for (std::size_t k = 0; k < n; ++k) {
    if (k % 10 == 0) level = std::round(8.0 * (2.0 * rng.uniform() - 1.0)) / 4.0;  // 17 levels in [-2, 2]
    s.u[k] = level;
    double y = kNoiseStd * rng.normal();
    for (std::size_t i = 1; i < A.size(); ++i)
      if (k >= i) y -= A[i] * s.y[k - i];
    for (std::size_t j = 1; j < B.size(); ++j)
      if (k >= j) y += B[j] * s.u[k - j];
    s.y[k] = y;
  }
  FILE* f = std::fopen(path.c_str(), "w");
  if (!f) {
    std::fprintf(stderr, "arx_bench: cannot write %s\n", path.c_str());
    return 1;
  }
  for (std::size_t k = 0; k < n; ++k) std::fprintf(f, "%.17g,%.17g\n", s.u[k], s.y[k]);
  std::fclose(f);

  const std::vector<epa::ident::Segment> data = {s};
  const epa::ident::ArxOrders orders{.na = 3, .nb = 3, .nk = 1};
  std::vector<double> ms;
  epa::ident::ArxEstimate est;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    auto e = epa::ident::estimate_arx(data, orders);  // regression matrix + QR + solve
    const auto t1 = std::chrono::steady_clock::now();
    if (!e) {
      std::fprintf(stderr, "arx_bench: %s\n", e.error().message.c_str());
      return 1;
    }
    est = std::move(*e);
    ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
  }
  std::sort(ms.begin(), ms.end());
  std::printf("samples %zu\nrows %zu\n", n, est.N);
  std::printf("ours_ms_min %.4f\nours_ms_median %.4f\n", ms.front(), ms[ms.size() / 2]);
  std::printf("a");
  for (double a : est.model.a) std::printf(" %.17g", a);
  std::printf("\nb");
  for (double b : est.model.b) std::printf(" %.17g", b);
  std::printf("\n");
  return 0;
}
