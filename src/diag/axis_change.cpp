#include "diag/axis_change.hpp"

#include <algorithm>
#include <cmath>

#include "core/format.hpp"

namespace epa::diag {

using plant::EffectKind;

std::vector<ChangeParam> change_params(EffectKind kind, const core::StickSlipParams& c) {
  switch (kind) {
    case EffectKind::kStaticFriction: return {{"friction_ratio", 1.0, 0.2, 6.0, true, true}};
    case EffectKind::kGainChange: return {{"flow_gain_ratio", 1.0, 0.3, 2.0, true}};
    case EffectKind::kDeadzoneShift: return {{"shift_r_V", 0.0, -1.0, 1.0, false}, {"shift_l_V", 0.0, -1.0, 1.0, false}};
    case EffectKind::kValveLag: return {{"spool_lag_s", c.spool_lag_s, 0.0, 0.15, false}};
    default: return {};
  }
}

bool AxisChange::has(EffectKind kind) const { return std::find(kinds.begin(), kinds.end(), kind) != kinds.end(); }

const std::vector<double>* AxisChange::values_of(EffectKind kind) const {
  for (std::size_t i = 0; i < kinds.size(); ++i)
    if (kinds[i] == kind) return &values[i];
  return nullptr;
}

core::StickSlipParams apply_change(const core::StickSlipParams& commissioned, const AxisChange& change) {
  core::StickSlipParams p = commissioned;
  for (std::size_t i = 0; i < change.kinds.size(); ++i) {
    const auto& v = change.values[i];
    switch (change.kinds[i]) {
      case EffectKind::kStaticFriction: p.coulomb_mm *= v[0], p.static_mm *= v[0]; break;
      case EffectKind::kGainChange: p.speed_right_mm_s_per_v *= v[0], p.speed_left_mm_s_per_v *= v[0]; break;
      case EffectKind::kDeadzoneShift: p.break_right_v += v[0], p.break_left_v += v[1]; break;
      case EffectKind::kValveLag: p.spool_lag_s = v[0]; break;
      case EffectKind::kInputDelay: p.delay_samples = change.delay_samples; break;
      default: break;
    }
  }
  // A shift cannot close the dead band past the valve's centre.
  p.break_right_v = std::max(p.break_right_v, 0.0), p.break_left_v = std::min(p.break_left_v, 0.0);
  return p;
}

AxisChange change_between(EffectKind kind, const core::StickSlipParams& from, const core::StickSlipParams& to) {
  AxisChange change;
  change.kinds = {kind};
  change.delay_samples = to.delay_samples;
  switch (kind) {
    case EffectKind::kStaticFriction: change.values = {{to.static_mm / from.static_mm}}; break;
    case EffectKind::kGainChange: change.values = {{to.speed_right_mm_s_per_v / from.speed_right_mm_s_per_v}}; break;
    case EffectKind::kDeadzoneShift: change.values = {{to.break_right_v - from.break_right_v, to.break_left_v - from.break_left_v}}; break;
    case EffectKind::kValveLag: change.values = {{to.spool_lag_s}}; break;
    default: change.values = {{}}; break;
  }
  return change;
}

double change_size(EffectKind kind, const AxisChange& change, const core::StickSlipParams& c) {
  if (kind == EffectKind::kInputDelay) return std::abs(change.delay_samples - c.delay_samples);
  const auto* v = change.values_of(kind);
  if (!v) return 0.0;
  switch (kind) {
    case EffectKind::kStaticFriction:
    case EffectKind::kGainChange: return std::abs(std::log((*v)[0]));
    case EffectKind::kDeadzoneShift: return std::max(std::abs((*v)[0]), std::abs((*v)[1]));
    case EffectKind::kValveLag: return std::abs((*v)[0] - c.spool_lag_s);
    default: return 0.0;
  }
}

bool beyond_tolerance(EffectKind kind, const AxisChange& change, const core::StickSlipParams& c, const core::StickSlipSpread& spread) {
  const double size = change_size(kind, change, c), m = kSpreadMargin;
  switch (kind) {
    case EffectKind::kStaticFriction: return size > std::max(std::log1p(kFrictionRatioTolerance), m * spread.friction_log_ratio);
    case EffectKind::kGainChange: return size > std::max(std::log1p(kGainRatioTolerance), m * spread.flow_gain_log_ratio);
    case EffectKind::kDeadzoneShift: return size > std::max(kBreakToleranceV, m * spread.break_v);
    case EffectKind::kValveLag: return size > std::max(kLagToleranceS, m * spread.spool_lag_s);
    case EffectKind::kInputDelay: return size > m * spread.delay_samples;
    default: return false;
  }
}

namespace {

std::string percent_change(double ratio, const char* up, const char* down) {
  const double pct = (ratio - 1.0) * 100.0;
  return std::string(pct >= 0 ? up : down) + " " + core::format_number(std::round(std::abs(pct))) + " %";
}

std::string signed_volts(double v) { return (v >= 0 ? "+" : "") + core::format_number(std::round(v * 100.0) / 100.0) + " V"; }

}  // namespace

std::string describe_change(EffectKind kind, const AxisChange& change, const core::StickSlipParams& c) {
  const auto* v = change.values_of(kind);
  switch (kind) {
    case EffectKind::kStaticFriction: return percent_change((*v)[0], "friction up", "friction down");
    case EffectKind::kGainChange: return percent_change((*v)[0], "flow gain up", "flow gain down") + " (supply pressure or valve)";
    case EffectKind::kDeadzoneShift:
      return "dead band moved: right break point " + signed_volts((*v)[0]) + ", left " + signed_volts((*v)[1]);
    case EffectKind::kValveLag:
      return std::string((*v)[0] > c.spool_lag_s ? "spool slower" : "spool faster") + ": lag " +
             core::format_number(std::round(c.spool_lag_s * 1e4) / 10.0) + " -> " + core::format_number(std::round((*v)[0] * 1e4) / 10.0) + " ms";
    case EffectKind::kInputDelay:
      return std::string(change.delay_samples > c.delay_samples ? "line longer" : "line shorter") + ": dead time " +
             std::to_string(c.delay_samples) + " -> " + std::to_string(change.delay_samples) + " samples";
    default: return "";
  }
}

}  // namespace epa::diag
