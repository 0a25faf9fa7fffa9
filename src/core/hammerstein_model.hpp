#pragma once
// A Hammerstein plant model: valve dead zone followed by an ARX model A(q) y = B(q) u_d,
// with y in sensor volts. This is what identification produces and what design and the
// simulators consume.
#include "core/dead_zone.hpp"
#include "core/polynomial.hpp"
#include "core/result.hpp"

namespace epa::core {

inline constexpr std::size_t kMaxModelOrder = 6;  // fixed storage bound for na, nb in the loop

struct HammersteinModel {
  Polynomial A;            // monic, A[0] = 1, in q^-1
  Polynomial B;            // in q^-1; B[0] = 0 when the plant has at least one sample of delay
  DeadZone dead_zone;
  double Ts = 0.005;       // sample time, s
  double mm_per_volt = 50; // sensor scale: position_mm = y * mm_per_volt

  // A monic, orders within kMaxModelOrder, finite coefficients, Ts > 0, valid dead zone.
  Status validate() const;
};

// Steady piston speed per volt of valve command beyond a break point, mm/s per V:
// slope * B(1) / (-A'(1)) * mm_per_volt / Ts, where -A'(1) = -sum i a_i is A(q) / (1 - q) at q = 1
// for an integrating A. Independent of the normalisation and of the orders, so it compares any
// identified model with the paper's.
double piston_speed_mm_s_per_v(const HammersteinModel& model, double slope);

}  // namespace epa::core
