#pragma once
// Shared set-up of the store tests: a scratch folder, the paper's model and tuning as a seed.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "core/paper_reference.hpp"
#include "store/database.hpp"
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
