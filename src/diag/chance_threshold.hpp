#pragma once
// The held-out gap reduction (%) that fitting each effect gives by chance: on effect-free data
// (the nominal model slightly perturbed, as its printed rounding allows, with seeded sensor
// noise, closed- and open-loop runs), calibrated by tests/diag/self_check_test.cpp, which prints
// the distribution and checks these values stay above the largest reduction it observes.
#include "plant/effects.hpp"

namespace epa::diag {

inline double chance_threshold_pct(plant::EffectKind kind) {
  switch (kind) {
    case plant::EffectKind::kGainChange: return 8.0;
    case plant::EffectKind::kDeadzoneShift: return 8.0;
    case plant::EffectKind::kInputDelay: return 8.0;
    case plant::EffectKind::kValveLag: return 8.0;
    case plant::EffectKind::kStaticFriction: return 8.0;
    case plant::EffectKind::kFlowSaturation: return 8.0;
    case plant::EffectKind::kPositionDependentGain: return 8.0;
    case plant::EffectKind::kSensorQuantization: return 8.0;
  }
  return 8.0;
}

}  // namespace epa::diag
