#pragma once
// The plant a controller meets when its model is wrong in the ways a robustness check asks about:
// the gain (B scaled) and the valve's dead band (both break points moved outwards). One rule for
// `epa simulate`'s robustness options and the commissioning's simulated verification.
#include "core/hammerstein_model.hpp"

namespace epa::sim {

struct ModelPerturbation {
  double gain_factor = 1.0;           // B multiplied by this
  double dead_band_widening_v = 0.0;  // > 0: the dead band wider by this on each side; < 0: narrower
};

inline core::HammersteinModel perturbed(const core::HammersteinModel& m, const ModelPerturbation& p) {
  core::HammersteinModel out = m;
  out.B = m.B * p.gain_factor;
  if (p.dead_band_widening_v != 0.0) {
    out.dead_zone.b_r = m.dead_zone.b_r + p.dead_band_widening_v;
    out.dead_zone.b_l = m.dead_zone.b_l - p.dead_band_widening_v;
    if (out.dead_zone.b_r < 0.0) out.dead_zone.b_r = 0.0;  // narrowed away: no dead band left on that side
    if (out.dead_zone.b_l > 0.0) out.dead_zone.b_l = 0.0;
  }
  return out;
}

}  // namespace epa::sim
