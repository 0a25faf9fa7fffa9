#pragma once
// Shared set-up of the store tests: a scratch folder, the paper's model and tuning as a seed.
#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <string>

#include "core/paper_reference.hpp"
#include "store/database.hpp"
#include "store/model_record.hpp"
#include "store/schema.hpp"
#include "store/store_file.hpp"

namespace epa::store::testing {

inline StoreSeed paper_seed() {
  StoreSeed seed;
  seed.model.name = "paper";
  seed.model.source = "paper eq 9-10";
  seed.model.model = core::paper::model();
  seed.tuning.name = "paper";
  seed.tuning.source = "paper eq 12-13";
  seed.tuning.F = core::paper::F();
  seed.tuning.G = core::paper::G();
  seed.tuning.H = core::paper::G();
  seed.tuning.dead_zone = core::paper::model().dead_zone;
  seed.tuning.lc_mm = core::paper::kLcDefaultMm;
  seed.tuning.valve_limit_v = core::paper::kValveLimitV;
  return seed;
}

// The paper's model with everything a model file can say of the axis beside it: a stick-slip model
// (values that do not round to few digits, so a round trip must be exact), its spread, the verdict
// and the drive range.
inline ModelRecord stick_slip_model_record() {
  ModelRecord m = paper_seed().model;
  m.name = "rig-2";
  m.source = "epa identify: na=3 nb=3 nk=1 from a.csv";
  m.axis_model = core::AxisModel::kStickSlip;
  m.identified_drive_v = std::array<double, 2>{-3.0 - 1.0 / 3.0, 2.875};
  core::StickSlipParams p;
  p.break_right_v = 1.17;
  p.break_left_v = -1.0 / 0.6;
  p.speed_right_mm_s_per_v = 107.5;
  p.speed_left_mm_s_per_v = 101.0 / 3.0;
  p.spring_rad_s = 52.0;
  p.damping_ratio = 0.3;
  p.coulomb_mm = 5.0;
  p.static_mm = 7.25;
  p.spool_lag_s = 0.013;
  p.delay_samples = 2;
  m.stick_slip = p;
  m.stick_slip_spread = core::StickSlipSpread{.friction_log_ratio = 0.33, .flow_gain_log_ratio = 0.08, .break_v = 0.11,
                                              .spool_lag_s = 0.012, .delay_samples = 1.0};
  return m;
}

// A migrated, seeded in-memory database.
inline Database seeded_memory_db() {
  auto db = Database::open(":memory:", true);
  EXPECT_TRUE(db) << db.error().message;
  EXPECT_TRUE(configure_connection(*db));
  EXPECT_TRUE(migrate(*db));
  EXPECT_TRUE(seed_if_empty(*db, paper_seed(), 1000));
  return std::move(*db);
}

class ScratchDir : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("epa-store-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "-" +
            std::to_string(::getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::filesystem::path dir_;
};

}  // namespace epa::store::testing
