#pragma once
// A tuning set ready for the loop: validated parameters of all three laws from one base
// configuration, so switching the controller is a lookup at a cycle boundary, never a rebuild.
#include "control/controller.hpp"

namespace epa::runtime {

struct Tuning {
  control::ControllerParams pp, ngidz, ffidz;

  const control::ControllerParams& for_kind(control::ControllerKind kind) const noexcept {
    switch (kind) {
      case control::ControllerKind::kPp: return pp;
      case control::ControllerKind::kPpNgidz: return ngidz;
      case control::ControllerKind::kPpFfidz: return ffidz;
    }
    return pp;
  }
};

// Validates `base` (its kind is ignored) once per law; the error says what is wrong.
inline core::Result<Tuning> make_tuning(control::ControllerConfig base) {
  Tuning t;
  control::ControllerParams* slots[] = {&t.pp, &t.ngidz, &t.ffidz};
  for (std::size_t i = 0; i < 3; ++i) {
    base.kind = control::kAllControllerKinds[i];
    auto p = control::ControllerParams::make(base);
    if (!p) return p.error();
    *slots[i] = *p;
  }
  return t;
}

}  // namespace epa::runtime
