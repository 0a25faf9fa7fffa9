#pragma once
// The paper's controller (eq 12-13, H = G) with its dead zone (eq 10) and l_c = 5 mm, as a
// ControllerConfig for any of the four laws (pp-traj with its default parameters).
#include "control/controller.hpp"
#include "core/paper_reference.hpp"
#include "core/units.hpp"

namespace epa::control {

inline ControllerConfig paper_controller_config(ControllerKind kind) {
  ControllerConfig c;
  c.kind = kind;
  c.F = core::paper::F();
  c.G = core::paper::G();
  c.dead_zone = core::paper::model().dead_zone;
  c.lc_v = core::mm_to_sensor_v(core::paper::kLcDefaultMm);
  c.valve_limit_v = core::paper::kValveLimitV;
  c.A = core::paper::model().A;
  c.B = core::paper::model().B;
  c.Ts = core::paper::model().Ts;
  return c;
}

}  // namespace epa::control
