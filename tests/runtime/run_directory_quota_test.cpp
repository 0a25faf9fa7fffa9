#include "runtime/run_directory_quota.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "../support/temp_path.hpp"

namespace epa::runtime {
namespace {

namespace fs = std::filesystem;

void write_bytes(const fs::path &path, std::size_t bytes) {
  std::ofstream(path) << std::string(bytes, 'x');
}

TEST(RunDirectoryQuota,
     TheOldestRunFilesGoOnceTheQuotaIsExceededAndOtherFilesAreNeverTouched) {
  const test::TempDir dir("quota");
  write_bytes(dir.path / "move-0001-pp-0to50mm.csv",
              400); // from an earlier run: counted
  write_bytes(dir.path / "notes.txt",
              5000); // not the recorder's: never counted or deleted
  std::vector<std::string> lines;
  RunDirectoryQuota quota(dir.path.string(), 1000,
                          [&](const std::string &l) { lines.push_back(l); });
  EXPECT_EQ(quota.used_bytes(), 400u);
  for (int i = 2; i <= 4; ++i) {
    const auto name =
        dir.path / ("record-000" + std::to_string(i) + "-sample1.csv");
    write_bytes(name, 400);
    quota.add(name.string());
  }
  // 4 x 400 bytes against 1000: the two oldest went, the newest two stay.
  EXPECT_EQ(quota.files(), 2u);
  EXPECT_EQ(quota.used_bytes(), 800u);
  EXPECT_EQ(quota.deleted(), 2u);
  EXPECT_FALSE(fs::exists(dir.path / "move-0001-pp-0to50mm.csv"));
  EXPECT_FALSE(fs::exists(dir.path / "record-0002-sample1.csv"));
  EXPECT_TRUE(fs::exists(dir.path / "record-0004-sample1.csv"));
  EXPECT_TRUE(fs::exists(dir.path / "notes.txt"));
  ASSERT_FALSE(lines.empty());
  EXPECT_NE(lines.back().find("oldest run file"), std::string::npos)
      << lines.back();
}

TEST(RunDirectoryQuota,
     AFileLargerThanTheQuotaIsKeptAloneNotDeletedAsItIsWritten) {
  const test::TempDir dir("quota-big");
  RunDirectoryQuota quota(dir.path.string(), 100);
  const auto name = dir.path / "excite-x-0001-seed1.csv";
  write_bytes(name, 500);
  quota.add(name.string());
  EXPECT_TRUE(fs::exists(name));
  EXPECT_EQ(quota.files(), 1u);
}

TEST(RunDirectoryQuota, OnlyTheRecordersNamesAreRunFiles) {
  EXPECT_TRUE(RunDirectoryQuota::is_run_file("move-0003-pp-ffidz-0to50mm.csv"));
  EXPECT_TRUE(
      RunDirectoryQuota::is_run_file("excite-20261206T010203Z-0001-seed7.csv"));
  EXPECT_FALSE(RunDirectoryQuota::is_run_file("move-0003.txt"));
  EXPECT_FALSE(RunDirectoryQuota::is_run_file("epa.db"));
}

} // namespace
} // namespace epa::runtime
