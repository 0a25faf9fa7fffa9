// Each effect is the identity at its neutral parameters and changes the output in the expected
// direction; the augmented plant with no effects is the Hammerstein plant.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/paper_reference.hpp"
#include "plant/augmented_plant.hpp"
#include "plant/effects.hpp"
#include "plant/hammerstein_plant.hpp"

namespace {

using epa::plant::AugmentedPlant;
using epa::plant::EffectKind;
using epa::plant::EffectSet;

// Position after `samples` of a constant command from mid-stroke.
double travel_mm(const EffectSet& e, double valve_v, int samples = 100, double start_mm = 250.0) {
  auto p = AugmentedPlant::make(epa::core::paper::model(), e, {.initial_position_mm = start_mm});
  EXPECT_TRUE(p.has_value());
  for (int k = 0; k < samples; ++k) p->step(valve_v);
  return p->measured_mm() - start_mm;
}

TEST(Effects, NamesRoundTripAndUnknownNamesListTheValidOnes) {
  for (auto kind : epa::plant::kAllEffects) {
    auto parsed = epa::plant::parse_effect(epa::plant::to_string(kind));
    ASSERT_TRUE(parsed.has_value());
    EXPECT_EQ(*parsed, kind);
    EXPECT_FALSE(epa::plant::param_specs(kind).empty());
    EXPECT_LE(epa::plant::param_specs(kind).size(), epa::plant::kMaxEffectParams);
  }
  auto bad = epa::plant::parse_effect("friction");
  ASSERT_FALSE(bad.has_value());
  EXPECT_NE(bad.error().message.find("static_friction"), std::string::npos);
}

TEST(Effects, EveryEffectAtItsNeutralParametersIsTheNominalPlant) {
  auto nominal = epa::plant::HammersteinPlant::make(epa::core::paper::model(), {.initial_position_mm = 250.0});
  ASSERT_TRUE(nominal.has_value());
  EffectSet all;
  for (auto kind : epa::plant::kAllEffects) all.set(kind, {});  // every parameter at its neutral value
  auto augmented = AugmentedPlant::make(epa::core::paper::model(), all, {.initial_position_mm = 250.0});
  ASSERT_TRUE(augmented.has_value()) << augmented.error().message;
  for (int k = 0; k < 600; ++k) {
    const double u = 2.5 * std::sin(0.02 * k);
    nominal->step(u), augmented->step(u);
    ASSERT_NEAR(augmented->measured_mm(), nominal->measured_mm(), 1e-9) << "k = " << k;
  }
}

TEST(Effects, EachEffectChangesTheMotionTheWayItShould) {
  const double base = travel_mm({}, 2.5);
  ASSERT_GT(base, 50.0);
  auto with = [](EffectKind kind, std::initializer_list<double> p) { EffectSet e; e.set(kind, p); return e; };
  EXPECT_GT(travel_mm(with(EffectKind::kGainChange, {1.3}), 2.5), 1.2 * base);
  EXPECT_LT(travel_mm(with(EffectKind::kDeadzoneShift, {0.4, 0.0}), 2.5), 0.8 * base);
  EXPECT_NEAR(travel_mm(with(EffectKind::kDeadzoneShift, {0.0, -0.5}), 2.5), base, 1e-9);  // the other side only
  EXPECT_LT(travel_mm(with(EffectKind::kInputDelay, {10}), 2.5), base - 5.0);
  EXPECT_LT(travel_mm(with(EffectKind::kValveLag, {0.05}), 2.5), base - 5.0);
  EXPECT_LT(travel_mm(with(EffectKind::kStaticFriction, {0.8, 0.4}), 2.5), 0.85 * base);
  EXPECT_LT(travel_mm(with(EffectKind::kFlowSaturation, {60.0}), 2.5), 0.5 * base);
  // Extending from mid-stroke with a positive slope: the gain grows as the piston goes out.
  EXPECT_GT(travel_mm(with(EffectKind::kPositionDependentGain, {0.3}), 2.5), base + 2.0);
  const double q = travel_mm(with(EffectKind::kSensorQuantization, {5.0}), 2.5);
  EXPECT_NEAR(std::fmod(q + 250.0, 5.0), 0.0, 1e-9);
}

// Steady piston speed (mm/s) over the last 100 of `samples` of a constant command, after
// `before` samples of another command (a piston set sliding first, or left at rest).
double steady_speed_mm_s(const EffectSet& e, double valve_v, double before_v = 0.0, int samples = 300) {
  auto p = AugmentedPlant::make(epa::core::paper::model(), e, {.initial_position_mm = 100.0, .stroke_mm = 1e6});
  EXPECT_TRUE(p.has_value());
  for (int k = 0; k < 100; ++k) p->step(before_v);
  for (int k = 0; k < samples - 100; ++k) p->step(valve_v);
  const double from = p->measured_mm();
  for (int k = 0; k < 100; ++k) p->step(valve_v);
  return (p->measured_mm() - from) / (100 * 0.005);
}

TEST(Effects, StaticFrictionHoldsBelowBreakawayAndSlidesAgainstCoulombAbove) {
  const double speed_per_V = epa::plant::steady_speed_mm_s_per_V(epa::core::paper::model().A.coefficients(),
                                                                  epa::core::paper::model().B.coefficients(), 0.005, 50.0);
  EffectSet e;
  e.set(EffectKind::kStaticFriction, {1.0, 0.3});
  // Drive u_d = m_r (u - b_r): 1.7627 * 0.4 = 0.71 V, below breakaway: the piston stays.
  EXPECT_NEAR(steady_speed_mm_s(e, 1.232 + 0.4), 0.0, 1e-6);
  EXPECT_NEAR(steady_speed_mm_s(EffectSet{}, 1.232 + 0.4), 0.705 * speed_per_V, 1.0);  // without friction it moves
  // 1.41 V breaks it loose; sliding, Coulomb friction takes 0.3 V of it.
  EXPECT_NEAR(steady_speed_mm_s(e, 1.232 + 0.8), (1.7627 * 0.8 - 0.3) * speed_per_V, 1.0);
  // Stick-slip: 0.71 V holds a piston at rest but keeps one sliding (above Coulomb).
  EXPECT_NEAR(steady_speed_mm_s(e, 1.232 + 0.4, 1.232 + 0.8), (1.7627 * 0.4 - 0.3) * speed_per_V, 1.0);
  // Below Coulomb a sliding piston stops.
  EXPECT_NEAR(steady_speed_mm_s(e, 1.232 + 0.1, 1.232 + 0.8), 0.0, 1e-6);
}

TEST(Effects, TheFlowCeilingIsPerDirectionAndItsKneeHardOrSoft) {
  const auto model = epa::core::paper::model();
  const double speed_per_V = epa::plant::steady_speed_mm_s_per_V(model.A.coefficients(), model.B.coefficients(), 0.005, 50.0);
  EffectSet hard;
  hard.set(EffectKind::kFlowSaturation, {60.0, 0.5});  // knee left out: a hard clip
  EXPECT_NEAR(steady_speed_mm_s(hard, 1.232 + 2.0), 60.0, 0.5);
  EXPECT_NEAR(steady_speed_mm_s(hard, -1.722 - 2.0), -30.0, 0.5);  // the rod side chokes at half
  EXPECT_NEAR(steady_speed_mm_s(hard, 1.232 + 0.1), 1.7627 * 0.1 * speed_per_V, 0.5);  // below the ceiling: untouched
  EffectSet soft;
  soft.set(EffectKind::kFlowSaturation, {60.0, 1.0, 2.0});
  // A drive whose unsaturated speed is the ceiling reaches 1/sqrt(2) of it through a knee of 2.
  const double at_ceiling_v = 1.232 + 60.0 / speed_per_V / 1.7627;
  EXPECT_NEAR(steady_speed_mm_s(soft, at_ceiling_v), 60.0 / std::sqrt(2.0), 0.5);
  EXPECT_NEAR(steady_speed_mm_s(soft, 1.232 + 3.0), 60.0, 3.0);  // far beyond: near the ceiling
}

// gain_change's drifting member: the gain moves with the run's time (a sagging supply), whatever
// the command, at drift_per_s from the start and settling with drift_settles_s; with Ts 0 the time
// stands still (a shape drawn against the command).
TEST(Effects, AGainThatDriftsMovesWithTheRunsTimeNotWithTheCommand) {
  EffectSet e;
  e.set(EffectKind::kGainChange, {0.9, 1.0, -0.01});  // drift_settles_s left out: 1000 s, all but linear
  const epa::core::DeadZone unit{.m_r = 1.0, .m_l = 1.0, .b_r = 0.0, .b_l = 0.0};
  epa::plant::DriveEffects drive(e, unit, 0.005, 0.0);
  EXPECT_DOUBLE_EQ(drive.drive_before_position(1.0), 0.9);
  for (int k = 1; k < 2000; ++k) drive.drive_before_position(k % 2 ? 1.0 : -1.0);
  const double at_10_s = 0.9 * (1.0 - 0.01 * 1000.0 * (1.0 - std::exp(-10.0 / 1000.0)));
  EXPECT_NEAR(at_10_s, 0.81, 0.001);
  EXPECT_NEAR(drive.drive_before_position(2.0), 2.0 * at_10_s, 1e-12);
  EXPECT_NEAR(drive.gain_at(10.0), at_10_s, 1e-12);
  EXPECT_NEAR(drive.gain_at(1000.0), 0.9 * 0.05, 1e-12);  // never below 5 % of the start: the drive never reverses
  epa::plant::DriveEffects still(e, unit, 0.0, 0.0);
  for (int k = 0; k < 2000; ++k) still.drive_before_position(1.0);
  EXPECT_DOUBLE_EQ(still.drive_before_position(1.0), 0.9);
  EffectSet settles;
  settles.set(EffectKind::kGainChange, {1.0, 1.0, -0.05, 2.0});  // 5 %/s at first, settling within seconds
  const epa::plant::DriveEffects settling(settles, unit, 0.005, 0.0);
  EXPECT_NEAR(settling.gain_at(0.1), 1.0 - 0.05 * 0.1, 2e-4);
  EXPECT_NEAR(settling.gain_at(20.0), 1.0 - 0.05 * 2.0, 1e-5);  // where the compressor catches up: 10 % down
  // In the plant: the same command moves the piston as far early in the run, 9-10 % less 4.5-5 s in.
  EffectSet sags;
  sags.set(EffectKind::kGainChange, {1.0, 1.0, -0.02});
  const double beyond_v = 1.232 + 0.1, start_mm = 20.0;
  auto late_mm = [&](const EffectSet& set) { return travel_mm(set, beyond_v, 1000, start_mm) - travel_mm(set, beyond_v, 900, start_mm); };
  ASSERT_LT(travel_mm(EffectSet{}, beyond_v, 1000, start_mm), 470.0);  // short of the end stop
  EXPECT_NEAR(travel_mm(sags, beyond_v, 100, start_mm) / travel_mm(EffectSet{}, beyond_v, 100, start_mm), 0.995, 0.006);
  EXPECT_NEAR(late_mm(sags) / late_mm(EffectSet{}), 0.905, 0.01);
}

// The spool family against the continuous-time step responses it stands for: one lag,
// 1 - exp(-t/tau); two in series, 1 - (t1 exp(-t/t1) - t2 exp(-t/t2)) / (t1 - t2), which starts
// flat (a spool and its amplifier). Sample k is the spool at the end of that sample.
TEST(Effects, TheSpoolIsOneLagOrTwoInSeries) {
  constexpr double Ts = 0.005;
  auto step = [](std::initializer_list<double> p, int k) {
    EffectSet e;
    e.set(EffectKind::kValveLag, p);
    epa::plant::ValveEffects v(e, Ts);
    double s = 0;
    for (int i = 0; i <= k; ++i) s = v.apply(1.0);
    return s;
  };
  const double t1 = 0.03, t2 = 0.012;
  for (int k : {0, 2, 5, 10, 20, 40}) {
    const double t = Ts * (k + 1);
    EXPECT_NEAR(step({t1}, k), 1.0 - std::exp(-t / t1), 1e-9) << k;
    EXPECT_NEAR(step({t1, 0.0}, k), step({t1}, k), 1e-12) << "second_tau_s 0 is first order";
    // The discrete cascade updates the second lag from the first's new value, which leads the
    // continuous one by up to about a sample's share of the second lag.
    EXPECT_NEAR(step({t1, t2}, k), 1.0 - (t1 * std::exp(-t / t1) - t2 * std::exp(-t / t2)) / (t1 - t2), 0.05) << k;
  }
  EXPECT_LT(step({t1, t2}, 0), 0.5 * step({t1 + t2}, 0));  // second order starts flat
  EXPECT_NEAR(step({t1, t2}, 400), 1.0, 1e-6);
}

// The spool limited by its speed (a solenoid's force runs out): a large step is followed at the
// limit (the rounded knee gives a little less once the spool is near the command); a step well
// inside one sample's travel passes whole, and a ramp at half the limit is followed as if there
// were none.
TEST(Effects, ASpoolLimitedByItsSpeedRampsAtThatSpeed) {
  constexpr double Ts = 0.01, rate_V_per_s = 20.0;
  EffectSet e;
  e.set(EffectKind::kValveLag, {0.0, 0.0, rate_V_per_s});
  epa::plant::ValveEffects v(e, Ts);
  double spool = 0.0;
  for (int k = 1; k <= 25; ++k) {
    spool = v.apply(10.0);
    EXPECT_NEAR(spool, rate_V_per_s * Ts * k, 0.01 * rate_V_per_s * Ts * k) << k;  // 0.2 V a sample
  }
  for (int k = 0; k < 40; ++k) spool = v.apply(10.0);
  EXPECT_NEAR(spool, 10.0, 1e-6) << "it reaches the command";
  const double small = 0.2 * rate_V_per_s * Ts;
  EXPECT_NEAR(v.apply(10.0 + small), 10.0 + small, 1e-9) << "a step well inside one sample's travel passes whole";
  epa::plant::ValveEffects free_spool(e, Ts);
  for (int k = 0; k < 50; ++k) EXPECT_NEAR(free_spool.apply(0.5 * rate_V_per_s * Ts * k), 0.5 * rate_V_per_s * Ts * k, 1e-6);
  // Left out, the limit is the neutral value: the spool follows any step at once.
  EffectSet lag_only;
  lag_only.set(EffectKind::kValveLag, {0.0});
  epa::plant::ValveEffects unlimited(lag_only, Ts);
  EXPECT_EQ(unlimited.apply(5.0), 5.0);
}

TEST(Effects, FrictionIsAForceOnThePistonNotAChangeOfTheValvesFlow) {
  // The valve's flow reaches B whatever friction does: a step of the drive held by friction still
  // gives B's swing (the chambers fill) but no steady motion, where a drive that never passes the
  // dead zone gives neither.
  EffectSet e;
  e.set(EffectKind::kStaticFriction, {1.0, 0.3});
  auto p = AugmentedPlant::make(epa::core::paper::model(), e, {.initial_position_mm = 250.0});
  ASSERT_TRUE(p.has_value());
  double largest_swing_mm = 0.0;
  for (int k = 0; k < 200; ++k) {
    p->step(1.232 + 0.4);
    largest_swing_mm = std::max(largest_swing_mm, std::abs(p->measured_mm() - 250.0));
  }
  EXPECT_GT(largest_swing_mm, 10.0);
  const double settled = p->measured_mm();
  for (int k = 0; k < 100; ++k) p->step(1.232 + 0.4);
  EXPECT_NEAR(p->measured_mm(), settled, 1e-6);
}

TEST(Effects, ValidateNamesTheEffectAndParameter) {
  EffectSet e;
  e.set(EffectKind::kValveLag, {5.0});
  auto s = e.validate();
  ASSERT_FALSE(s.has_value());
  EXPECT_NE(s.error().message.find("valve_lag: tau_s"), std::string::npos) << s.error().message;
}

TEST(Effects, WrapperCarriesDelayAndQuantisationAroundAnyPlant) {
  auto inner = epa::plant::HammersteinPlant::make(epa::core::paper::model(), {.initial_position_mm = 250.0});
  ASSERT_TRUE(inner.has_value());
  EffectSet e;
  e.set(EffectKind::kInputDelay, {5});
  e.set(EffectKind::kSensorQuantization, {2.0});
  epa::plant::WithValveAndSensorEffects wrapped(*inner, e, 0.005);
  for (int k = 0; k < 5; ++k) wrapped.step(3.0);
  EXPECT_DOUBLE_EQ(wrapped.position_mm(), 250.0);  // the command has not arrived yet
  for (int k = 0; k < 50; ++k) wrapped.step(3.0);
  EXPECT_GT(wrapped.position_mm(), 260.0);
  EXPECT_NEAR(std::fmod(wrapped.measured_mm(), 2.0), 0.0, 1e-9);
}

TEST(Effects, SteadySpeedPerVoltOfThePaperModel) {
  const auto m = epa::core::paper::model();
  // B(1) / A'(1) = 0.007 / 0.5702 V per sample per V, times 50 mm/V / 5 ms.
  EXPECT_NEAR(epa::plant::steady_speed_mm_s_per_V(m.A.coefficients(), m.B.coefficients(), m.Ts, m.mm_per_volt), 122.76, 0.05);
}

}  // namespace

namespace {

TEST(EffectSpecs, TextSpecsSwitchEffectsOnAndBadOnesAreNamed) {
  auto set = epa::plant::parse_effect_specs({"valve_lag=0.02", "static_friction=0.6,0.3"});
  ASSERT_TRUE(set) << set.error().message;
  EXPECT_TRUE(set->on(epa::plant::EffectKind::kValveLag));
  EXPECT_EQ(set->param(epa::plant::EffectKind::kValveLag, 0), 0.02);
  EXPECT_EQ(set->param(epa::plant::EffectKind::kStaticFriction, 1), 0.3);
  EXPECT_FALSE(set->on(epa::plant::EffectKind::kInputDelay));
  const std::pair<std::string, std::string> bad[] = {
      {"valve_lag", "name=value"},
      {"wind=3", "wind"},
      {"static_friction=0.6", "takes 2 value(s): breakaway_V,coulomb_V"},
      {"valve_lag=fast", "'fast' is not a number"},
      {"valve_lag=-1", "valve_lag"},
      {"position_dependent_gain=0.1,0,0,6.5", "where_samples = 6.5 is not a whole number"},
      {"position_dependent_gain=0.1,0,0,13", "where_samples = 13 lies outside [2, 12]"},
      {"input_delay=2.5", "delay_samples = 2.5 is not a whole number"},
  };
  for (const auto& [spec, expected] : bad) {
    auto r = epa::plant::parse_effect_specs({spec});
    ASSERT_FALSE(r) << spec;
    EXPECT_NE(r.error().message.find(expected), std::string::npos) << spec << ": " << r.error().message;
  }
}

}  // namespace
