#include "diag/axis_change.hpp"

#include <algorithm>
#include <cmath>

#include "core/format.hpp"

namespace epa::diag {

using plant::EffectKind;

EffectKind effect_of(ChangeTerm term) {
  switch (term) {
    case ChangeTerm::kFriction: return EffectKind::kStaticFriction;
    case ChangeTerm::kFlowGain:
    case ChangeTerm::kSupply: return EffectKind::kGainChange;
    case ChangeTerm::kDeadBand: return EffectKind::kDeadzoneShift;
    case ChangeTerm::kSpoolLag: return EffectKind::kValveLag;
    case ChangeTerm::kDeadTime: return EffectKind::kInputDelay;
  }
  return EffectKind::kGainChange;
}

std::vector<ChangeParam> change_params(ChangeTerm term, const core::StickSlipParams& c) {
  switch (term) {
    case ChangeTerm::kFriction: return {{"friction_ratio", 1.0, 0.2, 6.0, true, true}};
    case ChangeTerm::kFlowGain: return {{"flow_gain_ratio", 1.0, 0.3, 2.0, true}};
    // Jagged as friction: it moves the breakaways as friction does.
    case ChangeTerm::kSupply: return {{"spring_frequency_ratio", 1.0, 0.55, 1.4, true, true}};
    case ChangeTerm::kDeadBand: return {{"shift_r_V", 0.0, -1.0, 1.0, false}, {"shift_l_V", 0.0, -1.0, 1.0, false}};
    case ChangeTerm::kSpoolLag: return {{"spool_lag_s", c.spool_lag_s, 0.0, 0.15, false}};
    case ChangeTerm::kDeadTime: return {};
  }
  return {};
}

bool AxisChange::has(ChangeTerm term) const { return std::find(terms.begin(), terms.end(), term) != terms.end(); }

const std::vector<double>* AxisChange::values_of(ChangeTerm term) const {
  for (std::size_t i = 0; i < terms.size(); ++i)
    if (terms[i] == term) return &values[i];
  return nullptr;
}

core::StickSlipParams apply_change(const core::StickSlipParams& commissioned, const AxisChange& change) {
  core::StickSlipParams p = commissioned;
  for (std::size_t i = 0; i < change.terms.size(); ++i) {
    const auto& v = change.values[i];
    switch (change.terms[i]) {
      case ChangeTerm::kFriction: p.coulomb_mm *= v[0], p.static_mm *= v[0]; break;
      case ChangeTerm::kFlowGain: p.speed_right_mm_s_per_v *= v[0], p.speed_left_mm_s_per_v *= v[0]; break;
      // A softer spring winds further under a friction force; the seals press less at a lower
      // pressure, so the wind-ups go as the frequency, not as the stiffness (notes/model-health.md).
      case ChangeTerm::kSupply: p.spring_rad_s *= v[0], p.coulomb_mm /= v[0], p.static_mm /= v[0]; break;
      case ChangeTerm::kDeadBand: p.break_right_v += v[0], p.break_left_v += v[1]; break;
      case ChangeTerm::kSpoolLag: p.spool_lag_s = v[0]; break;
      case ChangeTerm::kDeadTime: p.delay_samples = change.delay_samples; break;
    }
  }
  // A shift cannot close the dead band past the valve's centre.
  p.break_right_v = std::max(p.break_right_v, 0.0), p.break_left_v = std::min(p.break_left_v, 0.0);
  return p;
}

AxisChange change_between(ChangeTerm term, const core::StickSlipParams& from, const core::StickSlipParams& to) {
  AxisChange change;
  change.terms = {term};
  change.delay_samples = to.delay_samples;
  switch (term) {
    case ChangeTerm::kFriction: change.values = {{to.static_mm / from.static_mm}}; break;
    case ChangeTerm::kFlowGain: change.values = {{to.speed_right_mm_s_per_v / from.speed_right_mm_s_per_v}}; break;
    case ChangeTerm::kSupply: change.values = {{to.spring_rad_s / from.spring_rad_s}}; break;
    case ChangeTerm::kDeadBand: change.values = {{to.break_right_v - from.break_right_v, to.break_left_v - from.break_left_v}}; break;
    case ChangeTerm::kSpoolLag: change.values = {{to.spool_lag_s}}; break;
    case ChangeTerm::kDeadTime: change.values = {{}}; break;
  }
  return change;
}

double change_size(ChangeTerm term, const AxisChange& change, const core::StickSlipParams& c) {
  if (term == ChangeTerm::kDeadTime) return std::abs(change.delay_samples - c.delay_samples);
  const auto* v = change.values_of(term);
  if (!v) return 0.0;
  switch (term) {
    case ChangeTerm::kFriction:
    case ChangeTerm::kFlowGain:
    case ChangeTerm::kSupply: return std::abs(std::log((*v)[0]));
    case ChangeTerm::kDeadBand: return std::max(std::abs((*v)[0]), std::abs((*v)[1]));
    case ChangeTerm::kSpoolLag: return std::abs((*v)[0] - c.spool_lag_s);
    case ChangeTerm::kDeadTime: break;
  }
  return 0.0;
}

bool beyond_tolerance(ChangeTerm term, const AxisChange& change, const core::StickSlipParams& c, const core::StickSlipSpread& spread) {
  const double size = change_size(term, change, c), m = kSpreadMargin;
  switch (tolerance_term(term)) {
    case ChangeTerm::kFriction: return size > std::max(std::log1p(kFrictionRatioTolerance), m * spread.friction_log_ratio);
    case ChangeTerm::kFlowGain: return size > std::max(std::log1p(kGainRatioTolerance), m * spread.flow_gain_log_ratio);
    case ChangeTerm::kDeadBand: return size > std::max(kBreakToleranceV, m * spread.break_v);
    case ChangeTerm::kSpoolLag: return size > std::max(kLagToleranceS, m * spread.spool_lag_s);
    case ChangeTerm::kDeadTime: return size > m * spread.delay_samples;
    case ChangeTerm::kSupply: break;  // held to friction's
  }
  return false;
}

namespace {

std::string percent_change(double ratio, const char* up, const char* down) {
  const double pct = (ratio - 1.0) * 100.0;
  return std::string(pct >= 0 ? up : down) + " " + core::format_number(std::round(std::abs(pct))) + " %";
}

std::string signed_volts(double v) { return (v >= 0 ? "+" : "") + core::format_number(std::round(v * 100.0) / 100.0) + " V"; }

}  // namespace

std::string describe_change(ChangeTerm term, const AxisChange& change, const core::StickSlipParams& c) {
  const auto* v = change.values_of(term);
  switch (term) {
    case ChangeTerm::kFriction: return percent_change((*v)[0], "friction up", "friction down");
    case ChangeTerm::kFlowGain: return percent_change((*v)[0], "flow gain up", "flow gain down") + " (supply pressure or valve)";
    case ChangeTerm::kSupply: {
      const double to_rad_s = c.spring_rad_s * (*v)[0];
      return std::string((*v)[0] < 1.0 ? "air spring softer" : "air spring stiffer") + ": " + core::format_number(std::round(c.spring_rad_s)) +
             " -> " + core::format_number(std::round(to_rad_s)) + " rad/s (supply pressure " + ((*v)[0] < 1.0 ? "down)" : "up)");
    }
    case ChangeTerm::kDeadBand:
      return "dead band moved: right break point " + signed_volts((*v)[0]) + ", left " + signed_volts((*v)[1]);
    case ChangeTerm::kSpoolLag:
      return std::string((*v)[0] > c.spool_lag_s ? "spool slower" : "spool faster") + ": lag " +
             core::format_number(std::round(c.spool_lag_s * 1e4) / 10.0) + " -> " + core::format_number(std::round((*v)[0] * 1e4) / 10.0) + " ms";
    case ChangeTerm::kDeadTime:
      return std::string(change.delay_samples > c.delay_samples ? "line longer" : "line shorter") + ": dead time " +
             std::to_string(c.delay_samples) + " -> " + std::to_string(change.delay_samples) + " samples";
  }
  return "";
}

}  // namespace epa::diag
