#include "ident/ramp_reading.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/paper_reference.hpp"
#include "ident_test_data.hpp"

namespace epa::ident {
namespace {

using testdata::kPaperDz;

constexpr double kBandWidthMaxV = 0.15;  // the readings sit close around a static break point

TEST(RampReading, TheBandOfAHammersteinPlantHoldsItsBreakPoints) {
  for (std::uint64_t seed : {1, 2}) {
    auto reading = read_dead_band(testdata::paper_segments(seed, 30.0, 0.1), {});
    ASSERT_TRUE(reading.has_value()) << reading.error().message;
    ASSERT_EQ(reading->ramps.size(), 2u) << "seed " << seed;  // one each way
    EXPECT_EQ(reading->ramps[0].direction, 1);
    EXPECT_EQ(reading->ramps[1].direction, -1);
    ASSERT_TRUE(reading->right && reading->left);
    EXPECT_LT(reading->right->lo_v, kPaperDz.b_r);
    EXPECT_GT(reading->right->hi_v, kPaperDz.b_r);
    EXPECT_LT(reading->right->hi_v - reading->right->lo_v, kBandWidthMaxV);
    EXPECT_LT(reading->left->lo_v, kPaperDz.b_l);
    EXPECT_GT(reading->left->hi_v, kPaperDz.b_l);
    EXPECT_LT(reading->left->hi_v - reading->left->lo_v, kBandWidthMaxV);
    // Where the excitation itself saw the piston move (2 mm from the ramp's start) is later still.
    EXPECT_LE(reading->ramps[0].start_v, reading->ramps[0].peak_v);
  }
}

TEST(RampReading, PulsesAreNotRamps) {
  // A segment of steps only, held for several samples each.
  Segment s;
  s.name = "pulses";
  for (int k = 0; k < 2000; ++k) {
    const int phase = (k / 60) % 4;
    s.u.push_back(phase == 1 ? 2.0 : phase == 3 ? -2.5 : 0.0);
    s.y.push_back(5.0 + 0.001 * k);
  }
  auto reading = read_dead_band({s}, {});
  ASSERT_TRUE(reading.has_value());
  EXPECT_TRUE(reading->ramps.empty());
  EXPECT_FALSE(reading->right.has_value());
  EXPECT_FALSE(reading->left.has_value());
}

TEST(RampReading, ARampThatNeverMovesThePistonBoundsNothing) {
  // Ramps up to 1.0 V stay inside the paper's dead band on both sides.
  auto reading = read_dead_band(testdata::paper_segments(5, 12.0, 0.1, 1.0), {});
  ASSERT_TRUE(reading.has_value());
  ASSERT_FALSE(reading->ramps.empty());
  for (const auto& r : reading->ramps) {
    EXPECT_TRUE(std::isnan(r.start_v));
    EXPECT_TRUE(std::isnan(r.stop_v));
    EXPECT_NEAR(std::abs(r.peak_v), 1.0, 0.01);
  }
  EXPECT_FALSE(reading->right.has_value());
  EXPECT_FALSE(reading->left.has_value());
}

TEST(RampReading, OptionsAreChecked) {
  RampReadingOptions o;
  o.motion_mm = 0.0;
  auto r = read_dead_band({}, o);
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("motion threshold"), std::string::npos) << r.error().message;
  o = {};
  o.Ts = -1.0;
  EXPECT_FALSE(read_dead_band({}, o).has_value());
}

}  // namespace
}  // namespace epa::ident
