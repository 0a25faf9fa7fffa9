#include "ident/excitation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "core/paper_reference.hpp"
#include "plant/plant_adapter.hpp"

#include "ident_test_data.hpp"

namespace epa::ident {
namespace {

using testdata::kPaperDz;

ExcitationResult paper_run(std::uint64_t seed, double duration_s, double noise_mm, ExcitationOptions o = {}) {
  o.seed = seed;
  o.duration_s = duration_s;
  return run_excitation(core::paper::model(), o, noise_mm, "test").value();
}

// Drives a generator with positions from `position(u_previous)` and returns its commands.
template <typename Position>
std::vector<double> drive(ExcitationOptions o, std::size_t n, Position position) {
  o.duration_s = static_cast<double>(n) * o.Ts;
  auto g = ExcitationGenerator::make(o).value();
  std::vector<double> u;
  double last = 0.0;
  for (std::size_t k = 0; k < n; ++k) u.push_back(last = g.next(position(last)));
  return u;
}

TEST(Excitation, TheSameSeedGivesTheSameRun) {
  const auto a = paper_run(5, 20.0, 0.1), b = paper_run(5, 20.0, 0.1), c = paper_run(6, 20.0, 0.1);
  EXPECT_EQ(a.run.u_V, b.run.u_V);
  EXPECT_EQ(a.run.y_mm, b.run.y_mm);
  EXPECT_NE(a.run.u_V, c.run.u_V);
  EXPECT_EQ(a.run.size(), 4000u);  // 20 s at 5 ms
  EXPECT_EQ(a.run.meta("controller"), "open-loop");
}

TEST(Excitation, NoiseDoesNotChangeTheValveSequenceOnlyTheReadings) {
  // Noise may change a pulse sign through the position rule, but not the first ramp.
  const auto quiet = paper_run(5, 3.0, 0.0), noisy = paper_run(5, 3.0, 0.5);
  EXPECT_EQ(quiet.run.u_V, noisy.run.u_V);
  EXPECT_NE(quiet.run.y_mm, noisy.run.y_mm);
}

TEST(Excitation, ThePistonStaysInsideTheStrokeOnThePapersPlant) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const auto r = paper_run(seed, 120.0, 0.1);
    EXPECT_EQ(r.samples_at_stops, 0u) << "seed " << seed;
    const auto [lo, hi] = std::minmax_element(r.run.y_mm.begin(), r.run.y_mm.end());
    EXPECT_GT(*lo, 1.0);
    EXPECT_LT(*hi, 499.0);
  }
}

TEST(Excitation, AnyPlantRunsTheSameExperiment) {
  // The model's run is the generic run on the model's plant: same commands, same readings.
  ExcitationOptions o;
  o.seed = 7;
  o.duration_s = 30.0;
  const auto by_model = run_excitation(core::paper::model(), o, 0.1, "test").value();
  auto plant = plant::make_hammerstein_simulator(
      core::paper::model(), {.initial_position_mm = 250.0, .noise_std_mm = 0.1, .seed = 7 ^ 0x6E6F697365ull, .stroke_mm = 500.0});
  ASSERT_TRUE(plant.has_value());
  const auto generic = run_excitation(**plant, core::paper::model().mm_per_volt, o, 0.1, "test").value();
  EXPECT_EQ(generic.run.u_V, by_model.run.u_V);
  EXPECT_EQ(generic.run.y_mm, by_model.run.y_mm);
  EXPECT_EQ(generic.run.metadata, by_model.run.metadata);
  EXPECT_FALSE(run_excitation(**plant, 0.0, o, 0.1, "test").has_value());  // no sensor scale
}

TEST(Excitation, ThePistonStaysInsideTheStrokeOnThePhysicsPlant) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    plant::PneumaticOptions po;
    po.initial_position_mm = 250.0;
    po.noise_std_mm = 0.1;
    po.seed = seed;
    auto plant = plant::make_pneumatic_simulator({}, po);
    ASSERT_TRUE(plant.has_value());
    ExcitationOptions o;
    o.seed = seed;
    o.duration_s = 90.0;
    const auto r = run_excitation(**plant, 50.0, o, 0.1, "test").value();
    EXPECT_EQ(r.samples_at_stops, 0u) << "seed " << seed;
    EXPECT_EQ(r.run.meta("controller"), "open-loop");
    // The slow ramp saw the piston move beyond the spool overlap, [-1.7, +1.2] V, each way.
    EXPECT_GT(r.ramp_motion_up_v, 1.2) << "seed " << seed;
    EXPECT_LT(r.ramp_motion_down_v, -1.7) << "seed " << seed;  // not the creep left from the ramp before
    EXPECT_GT(r.pulses, 100u);
  }
}

TEST(Excitation, PulsesAreMultiLevelThroughAndBeyondTheDeadBand) {
  const auto r = paper_run(1, 120.0, 0.1);
  std::set<double> levels;
  std::size_t inside = 0, beyond_right = 0, beyond_left = 0;
  for (double u : r.run.u_V) {
    EXPECT_LE(std::abs(u), 3.0 + 1e-12);
    if (u == 0.0) continue;
    levels.insert(std::abs(u));
    if (u > kPaperDz.b_r) ++beyond_right;
    else if (u < kPaperDz.b_l) ++beyond_left;
    else ++inside;
  }
  EXPECT_GE(levels.size(), 15u);  // 15 pulse levels, plus the ramps' values
  EXPECT_GT(inside, 1000u);
  EXPECT_GT(beyond_right, 1000u);
  EXPECT_GT(beyond_left, 1000u);
  EXPECT_GT(r.pulses, 150u);
}

TEST(Excitation, TheFirstRampRisesAtTheGivenRate) {
  ExcitationOptions o;  // 0.5 V/s at 5 ms: 0.0025 V per sample
  const auto u = drive(o, 200, [](double) { return 250.0; });  // a piston that never moves
  for (std::size_t k = 0; k < 200; ++k) EXPECT_NEAR(u[k], 0.0025 * static_cast<double>(k + 1), 1e-12);
}

TEST(Excitation, WhereTheRampsFirstMoveThePistonBoundsTheBreakPoints) {
  // Noise-free paper plant: motion (2 mm) shows shortly after the command passes each break point.
  const auto r = paper_run(1, 30.0, 0.0);
  EXPECT_GT(r.ramp_motion_up_v, kPaperDz.b_r);
  EXPECT_LT(r.ramp_motion_up_v, kPaperDz.b_r + 0.15);
  EXPECT_LT(r.ramp_motion_down_v, kPaperDz.b_l);
  EXPECT_GT(r.ramp_motion_down_v, kPaperDz.b_l - 0.15);
}

TEST(Excitation, CentringPulseSignsLeanTowardsTheMiddle) {
  ExcitationOptions o;
  o.sweep = false;
  o.ramp_rate_v_per_s = 100.0;  // get the ramps out of the way quickly
  o.ramp_rest_s = 0.0;
  const std::size_t n = 20000, after_ramps = 1000;
  const auto high = drive(o, n, [](double) { return 420.0; });  // beyond the upper guard line
  const auto low = drive(o, n, [](double) { return 60.0; });
  const auto middle = drive(o, n, [](double) { return 250.0; });
  auto count = [&](const std::vector<double>& u, int sign) {
    return std::count_if(u.begin() + after_ramps, u.end(), [&](double v) { return sign * v > 0.0; });
  };
  EXPECT_EQ(count(high, +1), 0);
  EXPECT_GT(count(high, -1), 1000);
  EXPECT_EQ(count(low, -1), 0);
  EXPECT_GT(count(low, +1), 1000);
  EXPECT_GT(count(middle, +1), 2000);  // about half each way
  EXPECT_GT(count(middle, -1), 2000);
}

TEST(Excitation, SweepingPulseSignsFavourOneWayUntilItTurnsAndNeverLeaveTheHalfWayRule) {
  ExcitationOptions o;  // sweep is the default
  ASSERT_TRUE(o.sweep);
  o.ramp_rate_v_per_s = 100.0;
  o.ramp_rest_s = 0.0;
  const std::size_t n = 20000, after_ramps = 1000;
  auto count = [&](const std::vector<double>& u, int sign) {
    return std::count_if(u.begin() + after_ramps, u.end(), [&](double v) { return sign * v > 0.0; });
  };
  // Half way from the middle to a guard line (the guard lines at 100 and 400 mm) and beyond: only
  // back, as with centring.
  const auto high = drive(o, n, [](double) { return 330.0; });
  const auto low = drive(o, n, [](double) { return 170.0; });
  EXPECT_EQ(count(high, +1), 0);
  EXPECT_EQ(count(low, -1), 0);
  // Just below the middle, a sweep starts upwards (the longer way is as long; it picks +) and
  // favours + about 0.8 - 0 = 80 % of the pulses' samples; a piston held there never turns it.
  const auto middle = drive(o, n, [](double) { return 249.0; });
  EXPECT_GT(count(middle, +1), 3 * count(middle, -1));
  EXPECT_GT(count(middle, -1), 0);  // but not all: still a random experiment
  // A piston that has been up past the turning point (0.45 of the way) sweeps down from then on.
  bool been_up = false;
  std::size_t k = 0;
  const auto turned = drive(o, n, [&](double) {
    ++k;
    if (k > 4000) return 249.0;
    been_up = true;
    return 320.0;
  });
  ASSERT_TRUE(been_up);
  const std::vector<double> later(turned.begin() + 5000, turned.end());
  const auto plus = std::count_if(later.begin(), later.end(), [](double v) { return v > 0.0; });
  const auto minus = std::count_if(later.begin(), later.end(), [](double v) { return v < 0.0; });
  EXPECT_GT(minus, 3 * plus);
}

TEST(Excitation, AGuardCutsAPulseThatCarriesThePistonTowardsAnEnd) {
  ExcitationOptions o;
  o.ramp_rate_v_per_s = 100.0;
  o.ramp_rest_s = 0.0;
  o.duration_s = 50.0;
  auto g = ExcitationGenerator::make(o).value();
  double u = 0.0;
  std::size_t longest_positive = 0, run = 0;
  for (std::size_t k = 0; k < 10000; ++k) {
    const double y = u > 0.0 ? 450.0 : 250.0;  // every positive command throws the piston past the guard
    u = g.next(y);
    run = u > 0.0 && k > 1000 ? run + 1 : 0;
    longest_positive = std::max(longest_positive, run);
  }
  EXPECT_EQ(longest_positive, 1u);  // cut in the sample after it starts
  EXPECT_GT(g.pulses_cut(), 10u);
}

TEST(Excitation, BadOptionsNameTheOption) {
  ExcitationOptions o;
  o.amplitude_max_v = 12.0;
  auto g = ExcitationGenerator::make(o);
  ASSERT_FALSE(g.has_value());
  EXPECT_NE(g.error().message.find("--amplitude-max"), std::string::npos);
  o = {};
  o.guard_mm = 300.0;
  g = ExcitationGenerator::make(o);
  ASSERT_FALSE(g.has_value());
  EXPECT_NE(g.error().message.find("--guard"), std::string::npos);
  o = {};
  o.duration_s = 0.0;
  EXPECT_FALSE(ExcitationGenerator::make(o).has_value());
}

}  // namespace
}  // namespace epa::ident
