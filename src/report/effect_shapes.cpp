#include "report/effect_shapes.hpp"

#include <algorithm>
#include <initializer_list>
#include <string>

#include "plant/effects.hpp"
#include "plant/force_path.hpp"

namespace epa::report {

namespace {

using plant::EffectKind;

// The final model's effects of these kinds (those it has), without the others.
plant::EffectSet fitted(const diag::Diagnosis& d, std::initializer_list<EffectKind> kinds) {
  plant::EffectSet e;
  for (auto k : kinds)
    if (d.final_model.effects.on(k)) e.set(k, d.final_model.effects.params(k));
  return e;
}

// With the drive's fitted gain (at a run's start, if it drifts): beside a position dependence a gain
// that holds is its level, not an effect of its own (selection.cpp), so the curve shows it.
Panel position_gain(const diag::Diagnosis& d) {
  plant::DriveEffects drive(fitted(d, {EffectKind::kPositionDependentGain, EffectKind::kGainChange}), core::DeadZone{}, 0.0, 0.0);
  Panel p{"position_dependent_gain: gain along the stroke", "position (mm)", "gain / nominal", {}, {}, {}, {}, {}, {}};
  Series out{"extending", "#1f77b4", {}, {}, false}, in{"retracting", "#d62728", {}, {}, true};
  const double level = drive.gain_at(0.0);
  for (double x = 0.0; x <= d.final_model.stroke_mm + 1e-9; x += d.final_model.stroke_mm / 100.0) {
    out.x.push_back(x), out.y.push_back(level * drive.finish(1.0, x));
    in.x.push_back(x), in.y.push_back(-level * drive.finish(-1.0, x));
  }
  p.series = {out, in};
  p.y_min = 0.0;
  return p;
}

// The friction force against the piston's mechanical speed: Coulomb while sliding, and the band
// of drive that friction holds while the piston sticks.
Panel friction(const diag::Diagnosis& d) {
  Panel p{"static_friction: friction against the piston's speed", "mechanical speed (mm/s)", "friction (V of drive)",
          {}, {}, {}, {}, {}, {}};
  Series sliding{"sliding", "#1f77b4", {}, {}, false}, sticking{"sticking (holds up to)", "#d62728", {}, {}, true};
  const auto path = plant::force_path(d.nominal.model);
  const plant::DriveEffects form(fitted(d, {EffectKind::kStaticFriction}), core::DeadZone{}, 0.0, path.speed_mm_s_per_V, path.pole);
  for (double v = -100.0; v <= 100.0 + 1e-9; v += 0.5) sliding.x.push_back(v), sliding.y.push_back(form.friction_V(v, 0.0));
  for (double drive : {-10.0, 10.0}) sticking.x.push_back(0.0), sticking.y.push_back(form.friction_V(0.0, drive));
  p.series = {sliding, sticking};
  return p;
}

// The valve command's unit step as the spool sees it (delay and lag).
Panel spool_step(const diag::Diagnosis& d) {
  const double Ts = d.nominal.model.Ts;
  plant::ValveEffects valve(fitted(d, {EffectKind::kInputDelay, EffectKind::kValveLag}), Ts);
  Panel p{"input_delay / valve_lag: the spool's answer to a 1 V step", "time (ms)", "spool (V)", {}, {}, {}, {}, {}, {}};
  Series command{"command", "#9e9e9e", {}, {}, true}, spool{"spool", "#1f77b4", {}, {}, false};
  for (int k = 0; k < 60; ++k) {
    const double t_ms = 1000.0 * Ts * k;
    command.x.push_back(t_ms), command.y.push_back(1.0);
    spool.x.push_back(t_ms), spool.y.push_back(valve.apply(1.0));
  }
  p.series = {command, spool};
  return p;
}

// Piston speed against the valve command, nominal and fitted: gain, break points and ceiling.
Panel speed_map(const diag::Diagnosis& d) {
  const auto& m = d.nominal.model;
  const double speed = plant::steady_speed_mm_s_per_V(m.A.coefficients(), m.B.coefficients(), m.Ts, m.mm_per_volt);
  // Time stands still (Ts 0): the speed a run starts with, whatever the gain's drift.
  plant::DriveEffects nominal(plant::EffectSet{}, m.dead_zone, 0.0, speed),
      with(fitted(d, {EffectKind::kGainChange, EffectKind::kDeadzoneShift, EffectKind::kFlowSaturation}), m.dead_zone, 0.0, speed);
  Panel p{"gain_change / deadzone_shift / flow_saturation: steady speed", "valve command (V)", "piston speed (mm/s)", {}, {}, {}, {}, {}, {}};
  Series a{"nominal", "#9e9e9e", {}, {}, true}, b{"fitted", "#1f77b4", {}, {}, false};
  for (double u = -5.0; u <= 5.0 + 1e-9; u += 0.05) {
    a.x.push_back(u), a.y.push_back(speed * nominal.finish(nominal.drive_before_position(u), 250.0));
    b.x.push_back(u), b.y.push_back(speed * with.finish(with.drive_before_position(u), 250.0));
  }
  p.series = {a, b};
  return p;
}

// gain_change's drift: the gain over the nominal against the time since a run started (a supply
// that sags during each run), over 20 s, longer than a commissioning engineer's runs.
Panel gain_drift(const diag::Diagnosis& d) {
  const plant::DriveEffects drive(fitted(d, {EffectKind::kGainChange}), core::DeadZone{}, 0.0, 0.0);
  Panel p{"gain_change: gain during a run", "time since the run started (s)", "gain / nominal", {}, {}, {}, {}, {}, {}};
  Series gain{"gain", "#1f77b4", {}, {}, false}, nominal{"nominal", "#9e9e9e", {}, {}, true};
  for (double t = 0.0; t <= 20.0 + 1e-9; t += 0.5) {
    gain.x.push_back(t), gain.y.push_back(drive.gain_at(t));
    nominal.x.push_back(t), nominal.y.push_back(1.0);
  }
  p.series = {nominal, gain};
  p.y_min = 0.0;
  return p;
}

bool named(const diag::Diagnosis& d, EffectKind k) { return std::find(d.effects.begin(), d.effects.end(), k) != d.effects.end(); }

}  // namespace

std::vector<Panel> effect_shape_panels(const diag::Diagnosis& d) {
  std::vector<Panel> panels;
  if (named(d, EffectKind::kPositionDependentGain)) panels.push_back(position_gain(d));
  if (named(d, EffectKind::kStaticFriction)) panels.push_back(friction(d));
  if (named(d, EffectKind::kInputDelay) || named(d, EffectKind::kValveLag)) panels.push_back(spool_step(d));
  if (named(d, EffectKind::kGainChange) || named(d, EffectKind::kDeadzoneShift) || named(d, EffectKind::kFlowSaturation))
    panels.push_back(speed_map(d));
  if (named(d, EffectKind::kGainChange) && d.final_model.effects.param(EffectKind::kGainChange, 2) != 0.0)
    panels.push_back(gain_drift(d));
  return panels;
}

}  // namespace epa::report
