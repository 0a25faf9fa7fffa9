#pragma once
// Everything the paper (Sunar et al., docs/paper.md) prints that the product reproduces,
// in one place. Interpretations as docs/paper.md gives them; deviations are explained where used.
#include <array>

#include "core/hammerstein_model.hpp"

namespace epa::core::paper {

// Eq 9 (ARX, y in sensor volts) and eq 10 (dead zone; m_l = 1.0707 as the text states twice).
inline HammersteinModel model() {
  HammersteinModel m;
  m.A = {1.0, -0.9094, -0.6110, 0.5204};
  m.B = {0.0, 1.024, -2.046, 1.029};
  m.dead_zone = {.m_r = 1.7627, .m_l = 1.0707, .b_r = 1.232, .b_l = -1.722};
  m.Ts = 0.005;  // not printed: docs/paper.md, best match of Table 1 timings
  m.mm_per_volt = 50.0;
  return m;
}

// Eq 11-13: desired characteristic polynomial and the printed controller (H = G, docs/paper.md).
inline Polynomial T() { return {1.0, -2.865, 2.7344, -0.8694}; }
inline Polynomial F() { return {1.0, -1.778, 0.7828}; }
inline Polynomial G() { return {-0.1734, 0.577, -0.3958}; }

// Eq 14 (u_l active) and eq 15 (u_r active), descending powers of z.
inline constexpr std::array<double, 6> kEq14 = {1.0, -3.0551, 3.7470, -2.7583, 1.5027, -0.4362};
inline constexpr std::array<double, 6> kEq15 = {1.0, -3.1780, 4.4014, -3.9791, 2.4740, -0.7181};

inline constexpr double kLcDefaultMm = 5.0;     // l_c, docs/paper.md
inline constexpr double kValveLimitV = 5.0;     // section 4.1

// Table 1 (experimental results on the rig).
inline constexpr double kGreaterThan5 = -1.0;  // marker for the paper's ">5"
struct Table1Row {
  double rise_s;        // kGreaterThan5 where the paper prints ">5"
  double settling_s;
  double ess_mm;
  double overshoot_pct;
};
struct Table1Entry {
  double step_mm;
  Table1Row pp, ngidz, ffidz;
};
inline constexpr std::array<Table1Entry, 4> kTable1 = {{
    {25, {kGreaterThan5, kGreaterThan5, 14.72, 0}, {0.47, 1.16, 1.96, 0}, {0.24, 0.51, 0.67, 0}},
    {50, {kGreaterThan5, kGreaterThan5, 13.92, 0}, {0.60, 1.07, 2.84, 0}, {0.30, 0.72, 1.04, 0}},
    {100, {14.21, kGreaterThan5, 13.50, 0}, {0.63, 1.35, 2.43, 0}, {0.41, 0.78, 0.46, 0}},
    {200, {2.39, kGreaterThan5, 13.02, 0}, {0.68, 1.50, 0.49, 0}, {0.34, 0.81, 0.51, 0}},
}};

}  // namespace epa::core::paper
