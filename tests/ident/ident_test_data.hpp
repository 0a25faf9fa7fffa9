#pragma once
// Data with a known generating model for the identification tests.
#include <algorithm>
#include <cmath>
#include <vector>

#include "core/paper_reference.hpp"
#include "core/polynomial.hpp"
#include "core/random.hpp"
#include "ident/arx_estimator.hpp"
#include "ident/excitation.hpp"
#include "ident/ident_data.hpp"

namespace epa::ident::testdata {

inline constexpr double kNoiseFreeTol = 1e-6;  // ARX coefficients from noise-free data (the check)
inline constexpr double kExactTol = 1e-9;      // hand-derived examples: only rounding error
inline const ArxOrders kEq9{.na = 3, .nb = 3, .nk = 1};  // the paper's orders
inline const core::DeadZone kPaperDz = core::paper::model().dead_zone;

inline double max_abs_diff(const core::Polynomial& a, const core::Polynomial& b) {
  double m = 0.0;
  for (std::size_t i = 0; i < std::max(a.size(), b.size()); ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
}

// y(k) from A y = B u exactly (no noise, no end stops), y = 0 before the first input; u is a
// seeded random multi-level signal held for a few samples, so every order is excited.
inline Segment linear_arx_segment(const core::Polynomial& A, const core::Polynomial& B, std::size_t n,
                                  std::uint64_t seed, const char* name = "arx") {
  core::Random rng(seed);
  Segment s;
  s.name = name;
  s.u.resize(n);
  s.y.assign(n, 0.0);
  double level = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    if (k % 7 == 0) level = 2.0 * rng.uniform() - 1.0;
    s.u[k] = level;
  }
  for (std::size_t k = 0; k < n; ++k) {
    double y = 0.0;
    for (std::size_t i = 1; i < A.size(); ++i)
      if (k >= i) y -= A[i] * s.y[k - i];
    for (std::size_t j = 0; j < B.size(); ++j)
      if (k >= j) y += B[j] * s.u[k - j];
    s.y[k] = y;
  }
  return s;
}

// A stable, non-integrating 3rd-order test plant (poles 0.45 +- 0.55i and 0.5), so long
// noise-free records stay bounded.
inline core::Polynomial stable_A() { return core::Polynomial{1.0, -0.9, 0.5} * core::Polynomial{1.0, -0.5}; }
inline core::Polynomial stable_B() { return {0.0, 0.5, 0.2, -0.1}; }

// An excitation run on the paper's plant (eq 9-10), split into segments.
inline std::vector<Segment> paper_segments(std::uint64_t seed, double duration_s, double noise_mm,
                                           double amplitude_max_v = 3.0, bool sweep = true) {
  ExcitationOptions o;
  o.sweep = sweep;
  o.duration_s = duration_s;
  o.seed = seed;
  o.amplitude_max_v = amplitude_max_v;
  auto r = run_excitation(core::paper::model(), o, noise_mm, "test");
  return split_run(r.value().run, "paper-" + std::to_string(seed), {});
}

}  // namespace epa::ident::testdata
