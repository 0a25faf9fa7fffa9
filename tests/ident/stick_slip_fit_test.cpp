// The stick-slip fit (ident/stick_slip_fit.hpp). Here on data from the stick-slip model itself, so
// these tests check the optimiser and the plumbing; whether the form suits a plant that is not
// its own model is checked on the physics plant (physics_identification_test.cpp).
#include <gtest/gtest.h>

#include <cmath>

#include "core/random.hpp"
#include "ident/arx_metrics.hpp"
#include "ident/excitation.hpp"
#include "ident/stick_slip_fit.hpp"
#include "plant/stick_slip_model.hpp"

namespace epa::ident {
namespace {

constexpr double kTs = 0.005;
constexpr double kMmPerVolt = 50.0;

plant::StickSlipParams truth() {
  plant::StickSlipParams p;
  p.break_right_v = 1.1;
  p.break_left_v = -1.6;
  p.speed_right_mm_s_per_v = 110.0;
  p.speed_left_mm_s_per_v = 90.0;
  p.spring_rad_s = 55.0;
  p.damping_ratio = 0.35;
  p.coulomb_mm = 4.5;
  p.static_mm = 7.0;
  p.spool_lag_s = 0.012;
  p.delay_samples = 1;
  return p;
}

// An excitation run of `seconds` on the model itself, with 0.1 mm of sensor noise.
Segment model_run(const plant::StickSlipParams& p, std::uint64_t seed, double seconds) {
  auto model = plant::StickSlipModel::make(p, kTs);
  EXPECT_TRUE(model.has_value());
  model->reset(250.0);
  ExcitationOptions eo;
  eo.duration_s = seconds;
  eo.seed = seed;
  auto gen = ExcitationGenerator::make(eo);
  EXPECT_TRUE(gen.has_value());
  core::Random noise(seed + 77);
  Segment s;
  s.name = "model-" + std::to_string(seed);
  double y = model->position_mm();
  while (!gen->done()) {
    const double measured = y + 0.1 * noise.normal();
    const double u = gen->next(measured);
    s.y.push_back(measured / kMmPerVolt);
    s.u.push_back(u);
    y = model->step(u);
  }
  return s;
}

TEST(StickSlipFit, RecoversTheModelFromItsOwnRunsFromATypicalStart) {
  const auto p = truth();
  const std::vector<Segment> est{model_run(p, 1, 60.0)}, val{model_run(p, 2, 60.0)};
  plant::StickSlipParams start;  // the struct's typical values, not the truth
  start.break_right_v = 1.3;
  start.break_left_v = -1.8;
  StickSlipFitOptions o;
  auto fit = fit_stick_slip(est, start, o);
  ASSERT_TRUE(fit.has_value()) << fit.error().message;
  const auto& f = fit->params;
  const double val_pct = nrmse_fit_percent(val, simulate_stick_slip(val, f, kTs, kMmPerVolt), 0);
  // Even the truth does not free-run its own noisy run exactly: a reading decides no stick, but
  // the model's start does, and a breakaway one sample off moves a whole jump. The fit must come
  // within 3 points of what the truth itself scores.
  const double truth_pct = nrmse_fit_percent(val, simulate_stick_slip(val, p, kTs, kMmPerVolt), 0);
  EXPECT_GT(truth_pct, 95.0);
  EXPECT_GT(val_pct, truth_pct - 3.0);
  EXPECT_NEAR(f.break_right_v, p.break_right_v, 0.05);
  EXPECT_NEAR(f.break_left_v, p.break_left_v, 0.05);
  EXPECT_NEAR(f.speed_right_mm_s_per_v, p.speed_right_mm_s_per_v, 0.05 * p.speed_right_mm_s_per_v);
  EXPECT_NEAR(f.speed_left_mm_s_per_v, p.speed_left_mm_s_per_v, 0.05 * p.speed_left_mm_s_per_v);
  EXPECT_NEAR(f.static_mm - f.coulomb_mm, p.static_mm - p.coulomb_mm, 1.0);  // the jump's size
  std::printf("validation %.2f %% (the truth %.2f %%): b %.3f / %.3f V, speeds %.1f / %.1f, spring %.1f, zeta %.3f, friction %.2f / %.2f mm, "
              "lag %.1f ms, delay %d, %zu simulations\n",
              val_pct, truth_pct, f.break_right_v, f.break_left_v, f.speed_right_mm_s_per_v, f.speed_left_mm_s_per_v, f.spring_rad_s,
              f.damping_ratio, f.coulomb_mm, f.static_mm, 1e3 * f.spool_lag_s, f.delay_samples, fit->evaluations);
}

TEST(StickSlipFit, BadInputIsRefusedByName) {
  StickSlipFitOptions o;
  EXPECT_FALSE(fit_stick_slip({}, {}, o).has_value());
  const std::vector<Segment> one{model_run(truth(), 1, 5.0)};
  o.Ts = 0.0;
  auto r = fit_stick_slip(one, {}, o);
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("Ts"), std::string::npos);
  o = {};
  plant::StickSlipParams bad;
  bad.spring_rad_s = -1.0;
  r = fit_stick_slip(one, bad, o);
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("spring_rad_s"), std::string::npos);
}

TEST(StickSlipFit, TheStartComesFromTheHammersteinModelsSpeedsAndBreakPoints) {
  core::HammersteinModel m;  // an integrator with 100 mm/s per V on both sides
  m.Ts = kTs;
  m.mm_per_volt = kMmPerVolt;
  m.A = core::Polynomial({1.0, -1.0});
  m.B = core::Polynomial({0.0, 100.0 * kTs / kMmPerVolt});
  m.dead_zone = {1.0, 1.0, 1.4, -1.9};
  const auto s = stick_slip_start(m, 2);
  EXPECT_NEAR(s.speed_right_mm_s_per_v, 100.0, 1e-9);
  EXPECT_NEAR(s.speed_left_mm_s_per_v, 100.0, 1e-9);
  EXPECT_LT(s.break_right_v, 1.4);  // the flow starts inside where the piston moves
  EXPECT_GT(s.break_left_v, -1.9);
  EXPECT_EQ(s.delay_samples, 1);    // nk = 2 counts the sample every ARX model has
  EXPECT_TRUE(s.validate().has_value());
}

}  // namespace
}  // namespace epa::ident
