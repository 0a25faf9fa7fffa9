// The comedi backend without a card: configuration checks, range choice, count conversion, rail
// detection, and open() failing with a message that names the device. Expected values are worked
// out by hand in the comments.
#include "hal/comedi_daq.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace epa::hal {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kVoltTol = 1e-12;
constexpr std::uint32_t kMax16 = 65535;  // 16-bit converter
const VoltRange kPm10{-10.0, 10.0};

// The AI ranges of an NI M-series card as comedilib reports them (microvolts * 1e-6).
const std::vector<VoltRange> kNiAiRanges = {
    {-10.0, 10.0}, {-5.0, 5.0}, {-0.5, 0.5}, {-50000 * 1e-6, 50000 * 1e-6}};

std::string message_of(const core::Status& s) { return s ? std::string("(ok)") : s.error().message; }

// ---- validate ----

TEST(ComediConfig, DefaultIsValid) { EXPECT_TRUE(validate(ComediConfig{})); }

TEST(ComediConfig, EmptyDeviceIsNamed) {
  ComediConfig c;
  c.device = "";
  EXPECT_NE(message_of(validate(c)).find("device"), std::string::npos) << message_of(validate(c));
}

TEST(ComediConfig, NegativeChannelIsNamed) {
  ComediConfig c;
  c.sensor.channel = -1;
  const std::string m = message_of(validate(c));
  EXPECT_NE(m.find("sensor.channel"), std::string::npos) << m;
  EXPECT_NE(m.find("-1"), std::string::npos) << m;
}

TEST(ComediConfig, SubdeviceBelowMinusOneIsNamed) {
  ComediConfig c;
  c.valve.subdevice = -2;
  EXPECT_NE(message_of(validate(c)).find("valve.subdevice"), std::string::npos) << message_of(validate(c));
}

TEST(ComediConfig, InvertedRangeIsNamed) {
  ComediConfig c;
  c.sensor.range_min_v = 10.0;
  c.sensor.range_max_v = 0.0;
  const std::string m = message_of(validate(c));
  EXPECT_NE(m.find("sensor.range_min_v"), std::string::npos) << m;
  EXPECT_NE(m.find("sensor.range_max_v"), std::string::npos) << m;
}

TEST(ComediConfig, EmptyRangeIsRejected) {
  ComediConfig c;
  c.sensor.range_min_v = c.sensor.range_max_v = 5.0;
  EXPECT_NE(message_of(validate(c)).find("sensor.range_min_v"), std::string::npos);
}

TEST(ComediConfig, NonFiniteRangeIsNamed) {
  ComediConfig c;
  c.sensor.range_max_v = kNan;
  const std::string m = message_of(validate(c));
  EXPECT_NE(m.find("sensor.range_max_v"), std::string::npos) << m;
  EXPECT_NE(m.find("finite"), std::string::npos) << m;
}

TEST(ComediConfig, ValveRangeMustCoverSaturation) {
  ComediConfig c;
  c.valve.range_min_v = 0.0;  // a unipolar 0-10 V output cannot drive the valve's negative side
  const std::string m = message_of(validate(c));
  EXPECT_NE(m.find("valve.range_min_v"), std::string::npos) << m;
  EXPECT_NE(m.find("[-5, 5] V"), std::string::npos) << m;

  c.valve = {-1, 0, -5.0, 4.9, AnalogReference::kGround};
  EXPECT_FALSE(validate(c));
  c.valve = {-1, 0, -5.0, 5.0, AnalogReference::kGround};  // exactly the saturation is enough
  EXPECT_TRUE(validate(c)) << message_of(validate(c));
}

// ---- choose_range ----

TEST(ComediChooseRange, UnipolarSensorTakesTenVoltRange) {
  EXPECT_EQ(choose_range(kNiAiRanges, 0.0, 10.0), 0);
}

TEST(ComediChooseRange, BipolarFiveTakesFiveVoltRange) {
  EXPECT_EQ(choose_range(kNiAiRanges, -5.0, 5.0), 1);
}

TEST(ComediChooseRange, SmallSignalTakesNarrowestCovering) {
  EXPECT_EQ(choose_range(kNiAiRanges, -0.05, 0.05), 3);  // despite -0.049999999999999996 from 1e-6 scaling
  EXPECT_EQ(choose_range(kNiAiRanges, 0.0, 0.3), 2);
}

TEST(ComediChooseRange, NothingCoversTwentyVolts) {
  EXPECT_EQ(choose_range(kNiAiRanges, 0.0, 20.0), std::nullopt);
  EXPECT_EQ(choose_range(std::span<const VoltRange>{}, 0.0, 1.0), std::nullopt);
}

TEST(ComediChooseRange, OrderOfListDoesNotMatterAndTiesTakeFirst) {
  const std::vector<VoltRange> ranges = {{-0.5, 0.5}, {0.0, 10.0}, {-10.0, 10.0}, {-5.0, 5.0}, {0.0, 10.0}};
  EXPECT_EQ(choose_range(ranges, 0.0, 10.0), 1);   // 0-10 (span 10) beats +-10 (span 20); index 1 before 4
  EXPECT_EQ(choose_range(ranges, -1.0, 1.0), 3);   // +-5
  EXPECT_EQ(choose_range(ranges, -6.0, 1.0), 2);   // +-10
}

TEST(ComediChooseRange, NonVoltRangesAreSkipped) {
  const std::vector<VoltRange> ranges = {{kNan, kNan}, {-10.0, 10.0}};  // e.g. a 4-20 mA range first
  EXPECT_EQ(choose_range(ranges, 0.0, 0.01), 1);
}

TEST(ComediChooseRange, FormatListsWhatTheCardOffers) {
  const std::vector<VoltRange> ranges = {{-10.0, 10.0}, {kNan, kNan}, {0.0, 5.0}};
  EXPECT_EQ(format_ranges(ranges), "[-10, 10] V, non-volt range, [0, 5] V");
  EXPECT_EQ(format_ranges(std::span<const VoltRange>{}), "none");
}

// ---- volts <-> counts (16-bit, +-10 V: one count is 20/65535 V) ----

TEST(ComediCounts, ZeroVoltsRoundsHalfUp) {
  // (0 - -10) / 20 * 65535 = 32767.5 -> floor(32767.5 + 0.5) = 32768, as comedi_from_phys does.
  EXPECT_EQ(volts_to_counts(0.0, kPm10, kMax16), 32768u);
}

TEST(ComediCounts, EndsAndInteriorPoints) {
  EXPECT_EQ(volts_to_counts(10.0, kPm10, kMax16), 65535u);
  EXPECT_EQ(volts_to_counts(-10.0, kPm10, kMax16), 0u);
  EXPECT_EQ(volts_to_counts(5.0, kPm10, kMax16), 49151u);   // 15/20 * 65535 = 49151.25
  EXPECT_EQ(volts_to_counts(-5.0, kPm10, kMax16), 16384u);  // 5/20 * 65535 = 16383.75
  // 12-bit 0-10 V: 2.5 V -> 0.25 * 4095 = 1023.75 -> 1024
  EXPECT_EQ(volts_to_counts(2.5, VoltRange{0.0, 10.0}, 4095), 1024u);
}

TEST(ComediCounts, BeyondRangeClamps) {
  EXPECT_EQ(volts_to_counts(12.0, kPm10, kMax16), 65535u);
  EXPECT_EQ(volts_to_counts(-12.0, kPm10, kMax16), 0u);
  EXPECT_EQ(volts_to_counts(std::numeric_limits<double>::infinity(), kPm10, kMax16), 65535u);
  EXPECT_EQ(volts_to_counts(-std::numeric_limits<double>::infinity(), kPm10, kMax16), 0u);
}

TEST(ComediCounts, NanGivesZeroVoltCount) {
  EXPECT_EQ(volts_to_counts(kNan, kPm10, kMax16), 32768u);
  EXPECT_EQ(volts_to_counts(kNan, VoltRange{1.0, 10.0}, 4095), 0u);  // 0 V below the range: clamped
}

TEST(ComediCounts, DegenerateInputsGiveZeroCounts) {
  EXPECT_EQ(volts_to_counts(1.0, kPm10, 0), 0u);
  EXPECT_EQ(volts_to_counts(1.0, VoltRange{1.0, 1.0}, kMax16), 0u);
  EXPECT_TRUE(std::isnan(counts_to_volts(5, kPm10, 0)));
}

TEST(ComediCounts, CountsToVolts) {
  EXPECT_NEAR(counts_to_volts(0, kPm10, kMax16), -10.0, kVoltTol);
  EXPECT_NEAR(counts_to_volts(65535, kPm10, kMax16), 10.0, kVoltTol);
  // 32768 * 20/65535 - 10 = (655360 - 655350)/65535 = 10/65535 V: half a count above 0 V.
  EXPECT_NEAR(counts_to_volts(32768, kPm10, kMax16), 10.0 / 65535.0, kVoltTol);
  EXPECT_NEAR(counts_to_volts(1024, VoltRange{0.0, 10.0}, 4095), 10240.0 / 4095.0, kVoltTol);
}

TEST(ComediCounts, RoundTripIsWithinHalfACount) {
  const double count_v = 20.0 / kMax16;
  for (double v = -10.0; v <= 10.0; v += 0.37) {
    const double back = counts_to_volts(volts_to_counts(v, kPm10, kMax16), kPm10, kMax16);
    EXPECT_LE(std::abs(back - v), 0.5 * count_v + kVoltTol) << v;
  }
}

TEST(ComediRail, EndsOfScaleAreRails) {
  EXPECT_TRUE(is_rail(0, kMax16));
  EXPECT_TRUE(is_rail(kMax16, kMax16));
  EXPECT_FALSE(is_rail(1, kMax16));
  EXPECT_FALSE(is_rail(kMax16 - 1, kMax16));
  EXPECT_FALSE(is_rail(32768, kMax16));
  EXPECT_TRUE(is_rail(4095, 4095));
}

// ---- the device (absent: a machine without a Comedi board) ----

TEST(ComediDaq, OpenMissingDeviceNamesIt) {
  ComediConfig c;
  c.device = "/dev/comedi-does-not-exist";
  ComediDaq daq(c);
  const core::Status s = daq.open();
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("/dev/comedi-does-not-exist"), std::string::npos) << s.error().message;
  if (!comedi_support_built()) {
    EXPECT_NE(s.error().message.find("no comedi support"), std::string::npos) << s.error().message;
  }
  EXPECT_FALSE(daq.is_open());
}

TEST(ComediDaq, OpenNonComediFileFails) {
  ComediConfig c;
  c.device = "/dev/null";  // exists, but answers no comedi ioctl
  ComediDaq daq(c);
  const core::Status s = daq.open();
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("/dev/null"), std::string::npos) << s.error().message;
  EXPECT_FALSE(daq.is_open());
}

TEST(ComediDaq, OpenValidatesBeforeTouchingTheDevice) {
  ComediConfig c;
  c.device = "/dev/comedi-does-not-exist";
  c.valve.range_max_v = 2.0;
  ComediDaq daq(c);
  const core::Status s = daq.open();
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("valve.range_max_v"), std::string::npos) << s.error().message;
}

TEST(ComediDaq, DescribeNamesDeviceAndChannels) {
  ComediConfig c;
  c.device = "/dev/comedi3";
  c.sensor.channel = 2;
  c.valve.subdevice = 1;
  const ComediDaq daq(c);
  const std::string d = daq.describe();
  EXPECT_NE(d.find("/dev/comedi3"), std::string::npos) << d;
  EXPECT_NE(d.find("sensor AI subdevice auto channel 2 needs [0, 10] V"), std::string::npos) << d;
  EXPECT_NE(d.find("valve AO subdevice 1 channel 0 needs [-10, 10] V"), std::string::npos) << d;
}

TEST(ComediDaq, CyclePathBeforeOpenReportsErrors) {
  ComediDaq daq(ComediConfig{});
  EXPECT_EQ(daq.read_sensor().status, IoStatus::kError);
  EXPECT_EQ(daq.write_valve(1.0), IoStatus::kError);
  daq.close();  // harmless when never opened
  daq.close();
  EXPECT_FALSE(daq.is_open());
}

}  // namespace
}  // namespace epa::hal
