// The windowed gap: zero on noise-free data from the model itself (also with each effect on in
// both), growing with the horizon when the model drifts from the plant.
#include <gtest/gtest.h>

#include "diag/windowed_gap.hpp"
#include "diag_test_data.hpp"

namespace {

using epa::diag::ReplayModel;

TEST(WindowedGap, IsZeroOnNoiseFreeDataFromTheModelItself) {
  const auto model = epa::core::paper::model();
  for (bool closed : {true, false}) {
    const auto run = epa::testing::make_run(model, {}, {.closed_loop = closed, .duration_s = 8, .noise_std_mm = 0.0});
    const std::vector<const epa::core::Run*> runs{&run};
    for (std::size_t horizon : {1u, 10u, 100u}) EXPECT_LT(epa::diag::windowed_gap_mm({model, {}, 500}, runs, horizon), 1e-9);
  }
}

TEST(WindowedGap, IsZeroWithTheHiddenEffectSwitchedOnInTheReplay) {
  const auto model = epa::core::paper::model();
  for (auto kind : epa::plant::kAllEffects) {
    epa::testing::Hidden h{epa::testing::typical_effect(kind)};
    const auto run = epa::testing::make_run(model, h, {.closed_loop = true, .duration_s = 10, .noise_std_mm = 0.0});
    const std::vector<const epa::core::Run*> runs{&run};
    const double with = epa::diag::windowed_gap_mm({model, h.effects, 500}, runs, 10);
    const double without = epa::diag::windowed_gap_mm({model, {}, 500}, runs, 10);
    EXPECT_GT(without, 0.05) << epa::plant::to_string(kind);
    // A restart from a quantised reading cannot know the true position, so quantising the
    // prediction does not bring it back to zero (why the self-check may call it unexplained).
    if (kind != epa::plant::EffectKind::kSensorQuantization) { EXPECT_LT(with, 1e-9) << epa::plant::to_string(kind); }
  }
}

TEST(WindowedGap, TheFamiliesOtherMembersReplayExactlyToo) {
  // A steady speed off B's, a soft per-direction flow knee, friction that sticks (breakaway well
  // above Coulomb): the simulator and the replay share the forms and the force path.
  const auto model = epa::core::paper::model();
  std::vector<epa::plant::EffectSet> sets(3);
  sets[0].set(epa::plant::EffectKind::kGainChange, {1.0, 0.85});
  sets[1].set(epa::plant::EffectKind::kFlowSaturation, {150.0, 0.6, 2.5});
  sets[2].set(epa::plant::EffectKind::kStaticFriction, {0.9, 0.2});
  sets[2].set(epa::plant::EffectKind::kGainChange, {1.1, 1.15});
  for (const auto& e : sets) {
    const auto run = epa::testing::make_run(model, epa::testing::Hidden{e}, {.closed_loop = true, .duration_s = 10, .noise_std_mm = 0.0});
    const std::vector<const epa::core::Run*> runs{&run};
    EXPECT_GT(epa::diag::windowed_gap_mm({model, {}, 500}, runs, 10), 0.05) << e.describe();
    EXPECT_LT(epa::diag::windowed_gap_mm({model, e, 500}, runs, 10), 1e-9) << e.describe();
  }
}

TEST(WindowedGap, GrowsWithTheHorizonOnADriftingPlant) {
  epa::testing::Hidden h;
  h.effects.set(epa::plant::EffectKind::kGainChange, {0.8});
  const auto run = epa::testing::make_run(epa::core::paper::model(), h, {.closed_loop = true, .duration_s = 8, .noise_std_mm = 0.0});
  const std::vector<const epa::core::Run*> runs{&run};
  const ReplayModel nominal{epa::core::paper::model(), {}, 500};
  double last = 0.0;
  for (std::size_t horizon : {1u, 5u, 20u, 80u}) {
    const double gap = epa::diag::windowed_gap_mm(nominal, runs, horizon);
    EXPECT_GT(gap, last) << "horizon " << horizon;
    last = gap;
  }
}

TEST(WindowedGap, ReplayListsEveryPredictionOnce) {
  const auto model = epa::core::paper::model();
  const auto run = epa::testing::make_run(model, {}, {.closed_loop = true, .duration_s = 2});
  const auto r = epa::diag::windowed_replay({model, {}, 500}, run, 10);
  ASSERT_EQ(r.k.size(), run.size() - 1 - epa::diag::first_window_start(model));
  for (std::size_t i = 1; i < r.k.size(); ++i) EXPECT_EQ(r.k[i], r.k[i - 1] + 1);
  EXPECT_EQ(r.sum.n, r.k.size());
}

TEST(WindowedGap, WindowsThatTouchAnEndStopAreLeftOutAndCounted) {
  const auto model = epa::core::paper::model();
  const ReplayModel replay{model, {}, 500};
  const auto clean = epa::testing::make_run(model, {}, {.closed_loop = true, .duration_s = 8, .noise_std_mm = 0.0});
  const std::size_t all_windows = epa::diag::windowed_sse(replay, clean, 10).windows;
  ASSERT_EQ(epa::diag::windowed_sse(replay, clean, 10).windows_at_end_stop, 0u);
  // 20 readings at the cap (0.4 mm) or at the far end, which the model cannot predict: without
  // the rule they would make a gap of hundreds of millimetres.
  for (double at_stop_mm : {0.4, 499.7}) {
    auto hit = clean;
    for (std::size_t k = 800; k < 820; ++k) hit.y_mm[k] = at_stop_mm;
    const auto s = epa::diag::windowed_sse(replay, hit, 10);
    EXPECT_LT(s.rms_mm(), 1e-9) << at_stop_mm;
    // Samples 800-819 reach into windows that start up to 10 samples before (their own span) or
    // whose measured past (3 model orders, 6 positions) reaches back to them: 3 or 4 windows.
    EXPECT_GE(s.windows_at_end_stop, 3u) << at_stop_mm;
    EXPECT_LE(s.windows_at_end_stop, 4u) << at_stop_mm;
    EXPECT_EQ(s.windows + s.windows_at_end_stop, all_windows) << at_stop_mm;
  }
  // The same readings 2 mm inside the stroke are a gap like any other.
  auto near = clean;
  for (std::size_t k = 800; k < 820; ++k) near.y_mm[k] = 2.0;
  EXPECT_GT(epa::diag::windowed_sse(replay, near, 10).rms_mm(), 1.0);
}

}  // namespace
