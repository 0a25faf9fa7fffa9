#include "control/controller.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "control/dead_zone_compensation.hpp"

namespace epa::control {

namespace {

core::Status load_polynomial(const core::Polynomial& p, const char* name, std::array<double, kMaxLawOrder + 1>& out,
                             std::size_t& degree) {
  if (p.size() == 0) return core::invalid_argument(std::string("controller: ") + name + " is empty");
  if (p.size() > kMaxLawOrder + 1)
    return core::invalid_argument(std::string("controller: ") + name + " has " + std::to_string(p.size()) +
                                  " coefficients, at most " + std::to_string(kMaxLawOrder + 1) + " are supported");
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!std::isfinite(p[i]))
      return core::invalid_argument(std::string("controller: ") + name + "[" + std::to_string(i) + "] is not a finite number");
    out[i] = p[i];
  }
  degree = p.size() - 1;
  return core::ok();
}

}  // namespace

core::Result<ControllerParams> ControllerParams::make(const ControllerConfig& c) {
  ControllerParams p;
  p.kind_ = c.kind;
  if (auto s = load_polynomial(c.F, "F", p.rst_.F, p.rst_.nF); !s) return s.error();
  if (std::abs(c.F[0] - 1.0) > 1e-12)
    return core::invalid_argument("controller: F must be monic (F[0] = 1), got F[0] = " + std::to_string(c.F[0]));
  if (auto s = load_polynomial(c.G, "G", p.rst_.G, p.rst_.nG); !s) return s.error();
  const core::Polynomial& H = c.H.size() == 0 ? c.G : c.H;
  if (auto s = load_polynomial(H, "H", p.rst_.H, p.rst_.nH); !s) return s.error();
  if (auto s = c.dead_zone.validate(); !s) return core::invalid_argument("controller: " + s.error().message);
  if (!(c.lc_v >= 0.0) || !std::isfinite(c.lc_v))
    return core::invalid_argument("controller: l_c must be a finite number >= 0, got " + std::to_string(c.lc_v));
  if (!(c.valve_limit_v > 0.0) || !std::isfinite(c.valve_limit_v))
    return core::invalid_argument("controller: valve limit must be > 0 V, got " + std::to_string(c.valve_limit_v));
  if (!std::isfinite(c.safe_valve_v) || std::abs(c.safe_valve_v) > c.valve_limit_v)
    return core::invalid_argument("controller: safe valve command must lie within the valve limit");
  p.dead_zone_ = c.dead_zone;
  p.lc_v_ = c.lc_v;
  p.valve_limit_v_ = c.valve_limit_v;
  p.safe_valve_v_ = c.safe_valve_v;
  p.trajectory_config_ = c.trajectory;
  p.hunting_ = hunting_limits_for(c.Ts);
  if (c.kind == ControllerKind::kPpTraj) {
    auto t = make_trajectory_params(c.trajectory, c.A, c.B, c.dead_zone, c.valve_limit_v, c.Ts);
    if (!t) return core::invalid_argument("controller: " + t.error().message);
    p.trajectory_ = *t;
  }
  return p;
}

void controller_start(const ControllerParams& p, ControllerState& state, double y_v, double speed_v_s) noexcept {
  state = {};
  state.rst.y_past.fill(y_v);
  state.rst.r_past.fill(y_v);
  if (p.kind() == ControllerKind::kPpTraj) trajectory_reset(p.trajectory(), state.trajectory, y_v, speed_v_s);
}

ControllerOutput controller_step(const ControllerParams& p, ControllerState& state, double r_v, double y_v) noexcept {
  ControllerOutput out;
  if (!std::isfinite(r_v) || !std::isfinite(y_v)) {
    out.valve_v = p.safe_valve_v();
    out.fault = true;
    return out;
  }
  double u = 0.0, valve = 0.0;
  bool finite = true;
  if (p.kind() == ControllerKind::kPpTraj) {
    const TrajectoryState before = state.trajectory;
    const TrajectoryOutput t = trajectory_step(p.trajectory(), state.trajectory, r_v, y_v, state.saturated_sign);
    u = t.u;
    finite = std::isfinite(u);
    if (!finite) state.trajectory = before;  // overflow of a diverging loop: do not poison the state
    valve = t.holding   ? 0.0
            : t.arrived ? creeping_idz_command(p.dead_zone(), u, t.creep_margin_v)
                        : smooth_idz_command(p.dead_zone(), u, p.trajectory().idz_ramp);
  } else {
    const RstState before = state.rst;
    u = rst_step(p.rst(), state.rst, r_v, y_v);
    finite = std::isfinite(u);
    if (!finite) state.rst = before;  // overflow of a diverging loop: do not poison the state
    switch (p.kind()) {
      case ControllerKind::kPp: valve = u; break;
      case ControllerKind::kPpNgidz: valve = ngidz_command(p.dead_zone(), u); break;
      case ControllerKind::kPpFfidz: valve = ffidz_command(p.dead_zone(), u, r_v - y_v, p.lc_v()); break;
      case ControllerKind::kPpTraj: break;  // the branch above
    }
  }
  if (!finite) {
    out.valve_v = p.safe_valve_v();
    out.fault = true;
    return out;
  }
  const bool watched = p.watched_for_hunting() && !state.trajectory.sliding_fallback;
  if (watched && hunting_step(p.hunting(), state.hunting, r_v, y_v)) {
    if (p.kind() == ControllerKind::kPpTraj) {  // pp-traj arrives while sliding from now on (trajectory_law.hpp)
      trajectory_fall_back_to_sliding(state.trajectory, -state.hunting.start_side);  // from the side the move came from
      state.hunting = {};
      out.sliding_fallback_started = true;
    } else {
      out.hunting = true;
    }
  }
  if (out.hunting || out.sliding_fallback_started) valve = 0.0;  // centred: inside the dead band, the piston stays
  out.controller_v = u;
  out.valve_v = std::clamp(valve, -p.valve_limit_v(), p.valve_limit_v());
  out.saturated = out.valve_v != valve;
  state.saturated_sign = out.saturated ? (valve > 0.0 ? 1 : -1) : 0;
  return out;
}

}  // namespace epa::control
