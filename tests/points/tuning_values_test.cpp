// The one map from a tuning point to its value, and the one way those values enter the law: the
// lengths (l_c, pp-traj's hold band) through the sensor calibration, everything else as written.
#include "points/tuning_values.hpp"

#include <gtest/gtest.h>

#include "control/paper_controller.hpp"
#include "points/point_catalog.hpp"

namespace epa::points {
namespace {

bool excitation_or_record_or_command(PointId id) {
  RecordField f;
  return id == PointId::kExciteSeed || id == PointId::kExciteAmplitudeMin || id == PointId::kExciteAmplitudeMax ||
         id == PointId::kExciteDuration || id == PointId::kCommissionCommand || id == PointId::kHealthCommand || record_field(id, f);
}

TEST(TuningValues, EveryTuningPointOfTheLawHasAValueAndNoOtherPointHasOne) {
  int values = 0;
  for (const PointDef& p : point_catalog()) {
    const bool law_tuning = p.tuning() && !excitation_or_record_or_command(p.id);
    EXPECT_EQ(tuning_value(p.id) != nullptr, law_tuning) << p.name;
    values += tuning_value(p.id) != nullptr;
  }
  EXPECT_EQ(values, 8);
  EXPECT_EQ(tuning_value(PointId::kController), nullptr);  // a choice of law, not a value of one
}

TEST(TuningValues, LengthsEnterTheLawInSensorVoltsTheRestAsWritten) {
  const core::SensorCalibration sensor{40.0};
  control::ControllerConfig law = control::paper_controller_config(control::ControllerKind::kPpFfidz);
  ASSERT_TRUE(set_tuning_value(law, PointId::kLc, 6.0, sensor));
  ASSERT_TRUE(set_tuning_value(law, PointId::kTrajHoldBand, 0.2, sensor));
  ASSERT_TRUE(set_tuning_value(law, PointId::kMr, 1.25, sensor));
  ASSERT_TRUE(set_tuning_value(law, PointId::kTrajBandwidth, 7.0, sensor));
  EXPECT_DOUBLE_EQ(law.lc_v, 6.0 / 40.0);
  EXPECT_DOUBLE_EQ(law.trajectory.hold_band_v, 0.2 / 40.0);
  EXPECT_DOUBLE_EQ(law.dead_zone.m_r, 1.25);
  EXPECT_DOUBLE_EQ(law.trajectory.feedback_bandwidth_rad_s, 7.0);
  EXPECT_FALSE(set_tuning_value(law, PointId::kSetpoint, 1.0, sensor));
}

TEST(TuningValues, AWholeSetEntersTheLawValueByValue) {
  const core::SensorCalibration sensor{50.0};
  const TuningValues v{.m_r = 1.1, .m_l = 1.2, .b_r = 0.3, .b_l = -0.4, .lc_mm = 5.0, .traj_speed_fraction = 0.5,
                       .traj_bandwidth_rad_s = 8.0, .traj_hold_band_mm = 0.1};
  const auto law = with_tuning_values(control::paper_controller_config(control::ControllerKind::kPp), v, sensor);
  EXPECT_DOUBLE_EQ(law.dead_zone.m_r, 1.1);
  EXPECT_DOUBLE_EQ(law.dead_zone.m_l, 1.2);
  EXPECT_DOUBLE_EQ(law.dead_zone.b_r, 0.3);
  EXPECT_DOUBLE_EQ(law.dead_zone.b_l, -0.4);
  EXPECT_DOUBLE_EQ(law.lc_v, 0.1);
  EXPECT_DOUBLE_EQ(law.trajectory.speed_fraction, 0.5);
  EXPECT_DOUBLE_EQ(law.trajectory.feedback_bandwidth_rad_s, 8.0);
  EXPECT_DOUBLE_EQ(law.trajectory.hold_band_v, 0.002);
}

}  // namespace
}  // namespace epa::points
