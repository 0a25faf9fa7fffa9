// Identification on a plant that is not its own model: open-loop runs of the physics
// plant (plant/pneumatic_plant.hpp: 5/3 valve with spool overlap, Stribeck friction, compressible
// air) made in-process as `epa excite --plant physics` makes them, identified as `epa identify`
// does by default, and checked against the plant itself. The truth for each break point is
// measured here on the plant, independently of any fit: the command at which the piston, at rest
// at mid-stroke with the valve centred, has moved 0.5 mm on a slow ramp (the overlap plus what
// friction and the filling chamber add).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "ident/arx_metrics.hpp"
#include "ident/excitation.hpp"
#include "ident/hammerstein_identification.hpp"
#include "ident/ident_data.hpp"
#include "ident/stick_slip_fit.hpp"
#include "plant/plant_adapter.hpp"
#include "plant/pneumatic_params.hpp"
#include "plant/pneumatic_plant.hpp"
#include "../support/sanitizer_run.hpp"

namespace epa::ident {
namespace {

constexpr double kTs = 0.005;
constexpr double kRunS = 90.0;
constexpr double kNoiseMm = 0.1;
constexpr std::uint64_t kNoiseStream = 0x6E6F697365ull;  // as epa excite: the noise's own stream
constexpr double kMidStrokeMm = 250.0;
constexpr double kRampVPerS = 0.1;       // a slow ramp: the start of motion with little dynamics in it
constexpr double kStartTravelMm = 0.5;   // "the piston has moved"
constexpr double kBreakPointTolV = 0.15; // the acceptance for a break point
// A validation fit of >= 90 % is the aim; no Hammerstein model reaches that on these runs (fitted to
// the validation run itself the best whole-run fit is 83-88 %, README). This floor only guards the
// method's level (52 %, 59 %, 42 % for the three plants below when it was set).
constexpr double kValidationFitFloorPct = 35.0;
constexpr double kStickSlipValidationFloorPct = 90.0;  // the aim, which the stick-slip model reaches

plant::PneumaticOptions plant_options(std::uint64_t noise_seed, double noise_mm) {
  plant::PneumaticOptions o;
  o.initial_position_mm = kMidStrokeMm;
  o.initial_pressure_bar = 3.0;
  o.noise_std_mm = noise_mm;
  o.seed = noise_seed;
  o.Ts = kTs;
  return o;
}

// The independent truth: the command when the piston has travelled kStartTravelMm on a ramp of
// kRampVPerS towards `direction` (true position, no sensor noise).
double ramp_start_v(const plant::PneumaticParams& params, double direction) {
  auto p = plant::PneumaticPlant::make(params, plant_options(1, 0.0));
  if (!p) return ADD_FAILURE() << p.error().message, NAN;
  const double start_mm = p->position_mm();
  double u = 0.0;
  for (int k = 1; std::abs(u) < 10.0; ++k) {
    if (std::abs(p->position_mm() - start_mm) >= kStartTravelMm) return u;
    u = direction * kRampVPerS * kTs * k;
    p->step(u);
  }
  return NAN;
}

std::vector<Segment> physics_run(const plant::PneumaticParams& params, std::uint64_t seed) {
  auto plant = plant::make_pneumatic_simulator(params, plant_options(seed ^ kNoiseStream, kNoiseMm));
  EXPECT_TRUE(plant.has_value()) << plant.error().message;
  ExcitationOptions eo;
  eo.duration_s = kRunS;
  eo.seed = seed;
  eo.stroke_mm = params.stroke_mm;
  auto r = run_excitation(**plant, params.stroke_mm / 10.0, eo, kNoiseMm, "physics test");
  EXPECT_TRUE(r.has_value()) << r.error().message;
  EXPECT_EQ(r->run.meta("controller"), "open-loop");
  EXPECT_EQ(r->samples_at_stops, 0u);
  return split_run(r->run, "physics-" + std::to_string(seed), {});
}

// `epa identify est --validate val` with its defaults.
IdentificationOptions identify_defaults() {
  IdentificationOptions o;
  o.search = {.na = {1, 4}, .nb = {1, 4}, .nk = {1, 2}};
  o.swarm.orders = {.na = 4, .nb = 5, .nk = 1};
  o.swarm.particles = 30;
  o.swarm.generations = 60;
  return o;
}

void check_plant(const plant::PneumaticParams& params) {
  const double truth_r = ramp_start_v(params, 1.0), truth_l = ramp_start_v(params, -1.0);
  // The truth itself: beyond the overlap, by less than friction could ever need.
  EXPECT_GT(truth_r, params.overlap_pos_v);
  EXPECT_LT(truth_r, params.overlap_pos_v + 0.5);
  EXPECT_LT(truth_l, params.overlap_neg_v);
  EXPECT_GT(truth_l, params.overlap_neg_v - 0.5);

  const auto est = physics_run(params, 1), val = physics_run(params, 2);
  const auto id = identify_hammerstein(est, val, identify_defaults());
  ASSERT_TRUE(id.has_value()) << id.error().message;
  const auto& dz = id->fit.dead_zone;
  EXPECT_NEAR(dz.b_r, truth_r, kBreakPointTolV);
  EXPECT_NEAR(dz.b_l, truth_l, kBreakPointTolV);
  const auto fit = fit_percent(id->fit.arx.model, through_dead_zone(val, dz), 0);
  EXPECT_GE(fit.simulation_pct, kValidationFitFloorPct);
  EXPECT_NEAR(id->fit.arx.model.A().at(1.0), 0.0, 1e-12);  // it integrates, as the cylinder does
  std::printf("b_r %.4f V (ramp %.4f V), b_l %.4f V (ramp %.4f V), validation free-run fit %.2f %%, %s\n", dz.b_r, truth_r,
              dz.b_l, truth_l, fit.simulation_pct, id->fit.arx.model.orders.to_string().c_str());

  // The stick-slip model, as `epa identify` fits it after the Hammerstein one: its own piston must
  // start where the plant's does on the same slow ramp, and its free run must follow the held-out run.
  StickSlipFitOptions so;
  so.Ts = kTs;
  const auto model = id->fit.model(kTs, 50.0);
  const auto ss = identify_stick_slip(est, val, model, id->fit.arx.model.orders.nk, so);
  ASSERT_TRUE(ss.has_value()) << ss.error().message;
  EXPECT_NEAR(ss->ramp_right_v, truth_r, kBreakPointTolV);
  EXPECT_NEAR(ss->ramp_left_v, truth_l, kBreakPointTolV);
  EXPECT_GE(ss->validation_pct, kStickSlipValidationFloorPct);
  std::printf("stick-slip model: starts at %.4f / %.4f V on the ramp, free-run fit estimation %.2f %%, validation %.2f %%\n",
              ss->ramp_right_v, ss->ramp_left_v, ss->estimation_pct, ss->validation_pct);
}

TEST(PhysicsIdentification, DefaultPlant) { check_plant({}); }

// The two other plants take the default plant's paths with other numbers (67 s each under ASan):
// under the sanitizers (tests/support/sanitizer_run.hpp) the default plant alone.
TEST(PhysicsIdentification, LowerSupplyPressure) {
  if (epa::test::sanitizer_run()) GTEST_SKIP() << "the sanitizer run identifies the default plant only";
  plant::PneumaticParams p;
  p.supply_pressure_bar = 4.8;
  check_plant(p);
}

TEST(PhysicsIdentification, WiderSpoolOverlap) {
  if (epa::test::sanitizer_run()) GTEST_SKIP() << "the sanitizer run identifies the default plant only";
  plant::PneumaticParams p;
  p.overlap_pos_v = 1.4;
  p.overlap_neg_v = -1.9;
  check_plant(p);
}

}  // namespace
}  // namespace epa::ident
