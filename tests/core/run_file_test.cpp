#include "core/run_file.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "../support/temp_path.hpp"
#include "../support/text_contains.hpp"

namespace epa::core {
namespace {

// Inside TEST bodies `Run` alone names testing::Test::Run, hence core::Run throughout.
// Failure output shows the whole text, so a wrong message is easy to read.
using epa::test::contains;

core::Run make_run(std::size_t n, bool optional_columns) {
  core::Run run;
  run.Ts = 0.005;
  run.metadata = {{"controller", "pp-ffidz"}, {"source", "sim"}, {"operator", "bench 2, left"}};
  for (std::size_t k = 0; k < n; ++k) {
    const double kd = static_cast<double>(k);
    run.t_s.push_back(kd * run.Ts);
    run.y_mm.push_back(0.1234 * kd - 3.5);
    run.u_V.push_back(-1.01234 + 0.25 * kd);
    if (optional_columns) {
      run.r_mm.push_back(50.0 - kd);
      run.uc_V.push_back(0.5 * kd - 2.00001);
    }
  }
  return run;
}

std::string to_text(const core::Run& run) {
  std::ostringstream out;
  write_run(out, run);
  return out.str();
}

Result<core::Run> parse_text(const std::string& text, std::optional<double> expected_Ts = std::nullopt) {
  std::istringstream in(text);
  return parse_run(in, "runs/a.csv", expected_Ts);
}

// Parses `text`, expects a parse error, returns its message.
std::string parse_error_of(const std::string& text, std::optional<double> expected_Ts = std::nullopt) {
  const auto result = parse_text(text, expected_Ts);
  EXPECT_FALSE(result.has_value()) << text;
  if (result.has_value()) return "";
  EXPECT_EQ(result.error().code, ErrorCode::kParse);
  return result.error().message;
}

using epa::test::unique_temp_path;

// Removes a temp file or folder even when an ASSERT leaves the test early.
struct RemoveOnExit {
  std::filesystem::path path;
  ~RemoveOnExit() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

// Equal up to the written precision (half a unit of the last decimal written).
void expect_same_run(const core::Run& a, const core::Run& b) {
  EXPECT_DOUBLE_EQ(a.Ts, b.Ts);
  EXPECT_EQ(a.metadata, b.metadata);
  const auto expect_near = [](const std::vector<double>& x, const std::vector<double>& y, double tol,
                              const char* name) {
    ASSERT_EQ(x.size(), y.size()) << name;
    for (std::size_t k = 0; k < x.size(); ++k) EXPECT_NEAR(x[k], y[k], tol) << name << "[" << k << "]";
  };
  expect_near(a.t_s, b.t_s, 0.5e-6, "t_s");
  expect_near(a.r_mm, b.r_mm, 0.5e-4, "r_mm");
  expect_near(a.y_mm, b.y_mm, 0.5e-4, "y_mm");
  expect_near(a.u_V, b.u_V, 0.5e-5, "u_V");
  expect_near(a.uc_V, b.uc_V, 0.5e-5, "uc_V");
}

constexpr const char* kSpecExample =
    "# epa-run/1\n# Ts=0.005\n# controller=pp-ffidz\n# source=sim\n"
    "t_s,r_mm,y_mm,u_V\n0.000,50.0,0.00,0.000\n0.005,50.0,0.00,-1.012\n";

TEST(RunFile, WriterEmitsVersionTsMetadataHeaderAndFixedDecimals) {
  core::Run run = make_run(2, true);
  run.metadata = {{"controller", "pp"}, {"source", "bench"}};
  EXPECT_EQ(to_text(run),
            "# epa-run/1\n# Ts=0.005\n# controller=pp\n# source=bench\n"
            "t_s,r_mm,y_mm,u_V,uc_V\n"
            "0.000000,50.0000,-3.5000,-1.01234,-2.00001\n"
            "0.005000,49.0000,-3.3766,-0.76234,-1.50001\n");
}

TEST(RunFile, ReadsTheSpecExample) {
  const auto run = parse_text(kSpecExample);
  ASSERT_TRUE(run.has_value()) << run.error().message;
  EXPECT_DOUBLE_EQ(run->Ts, 0.005);
  EXPECT_EQ(run->meta("controller"), "pp-ffidz");
  EXPECT_EQ(run->meta("source"), "sim");
  EXPECT_EQ(run->t_s, (std::vector<double>{0.0, 0.005}));
  EXPECT_EQ(run->r_mm, (std::vector<double>{50.0, 50.0}));
  EXPECT_EQ(run->u_V, (std::vector<double>{0.0, -1.012}));
  EXPECT_TRUE(run->uc_V.empty());
}

TEST(RunFile, RoundTripWithOptionalColumnsAndExtraMetadata) {
  const core::Run run = make_run(50, true);
  const auto back = parse_text(to_text(run), 0.005);
  ASSERT_TRUE(back.has_value()) << back.error().message;
  expect_same_run(run, *back);
  EXPECT_EQ(back->meta("operator"), "bench 2, left");
}

TEST(RunFile, RoundTripWithoutOptionalColumns) {
  const core::Run run = make_run(20, false);
  const std::string text = to_text(run);
  EXPECT_TRUE(contains(text, "\nt_s,y_mm,u_V\n0.000000,-3.5000,-1.01234\n"));
  const auto back = parse_text(text);
  ASSERT_TRUE(back.has_value()) << back.error().message;
  expect_same_run(run, *back);
  EXPECT_TRUE(back->r_mm.empty());
  EXPECT_TRUE(back->uc_V.empty());
}

TEST(RunFile, RoundTripRoundsToTheWrittenPrecision) {
  core::Run run = make_run(2, false);
  run.y_mm[1] = 1.23456789;
  run.u_V[1] = -0.0000001;  // prints as 0.00000, not -0.00000
  const std::string text = to_text(run);
  EXPECT_TRUE(contains(text, "0.005000,1.2346,0.00000\n"));
  const auto back = parse_text(text);
  ASSERT_TRUE(back.has_value()) << back.error().message;
  EXPECT_DOUBLE_EQ(back->y_mm[1], 1.2346);
  EXPECT_DOUBLE_EQ(back->u_V[1], 0.0);
}

TEST(RunFile, ColumnsInAnyOrderAndUnknownColumnsIgnored) {
  const auto run = parse_text("# Ts=0.01\nnote,u_V,p_bar,y_mm,t_s,uc_V\nabc,1.5,x,2.5,0.00,7\nz,-1.5,,3.5,0.01,8\n");
  ASSERT_TRUE(run.has_value()) << run.error().message;
  EXPECT_EQ(run->t_s, (std::vector<double>{0.0, 0.01}));
  EXPECT_EQ(run->y_mm, (std::vector<double>{2.5, 3.5}));
  EXPECT_EQ(run->u_V, (std::vector<double>{1.5, -1.5}));
  EXPECT_EQ(run->uc_V, (std::vector<double>{7.0, 8.0}));
  EXPECT_TRUE(run->r_mm.empty());
}

TEST(RunFile, MetadataKeptInOrderTrimmedAndPlainCommentsIgnored) {
  const auto run = parse_text(
      "# epa-run/1\n#  source = bench  \n# tuned by hand, kp=3 (a note, not metadata)\n# gain = 3, see log\n"
      "# Ts=0.005\n#controller=open-loop\nt_s,y_mm,u_V\n0,1,2\n0.005,1,2\n");
  ASSERT_TRUE(run.has_value()) << run.error().message;
  using Meta = std::vector<std::pair<std::string, std::string>>;
  EXPECT_EQ(run->metadata, (Meta{{"source", "bench"}, {"gain", "3, see log"}, {"controller", "open-loop"}}));
}

TEST(RunFile, CrlfBomAndBlankLinesAccepted) {
  const auto run =
      parse_text("\xEF\xBB\xBF# epa-run/1\r\n# Ts=0.005\r\n\r\nt_s,y_mm,u_V\r\n0.000,1,2\r\n  \r\n0.005,3,4\r\n");
  ASSERT_TRUE(run.has_value()) << run.error().message;
  EXPECT_EQ(run->y_mm, (std::vector<double>{1.0, 3.0}));
  EXPECT_EQ(run->u_V, (std::vector<double>{2.0, 4.0}));
}

TEST(RunFile, FileWithoutVersionTagOrTsInfersTs) {
  const auto run = parse_text("t_s,y_mm,u_V\n1.000,0,0\n1.010,0,0\n1.020,0,0\n");
  ASSERT_TRUE(run.has_value()) << run.error().message;
  EXPECT_NEAR(run->Ts, 0.01, 1e-12);
}

TEST(RunFile, InferredTsIsTheMeanStepOfTheRun) {
  std::string text = "t_s,y_mm,u_V\n";
  char line[64];
  for (int k = 0; k <= 300; ++k) {
    std::snprintf(line, sizeof line, "%.6f,0,0\n", k / 300.0);
    text += line;
  }
  const auto run = parse_text(text);
  ASSERT_TRUE(run.has_value()) << run.error().message;
  EXPECT_NEAR(run->Ts, 1.0 / 300.0, 1e-9);  // the first step alone, 0.003333, is 3e-7 off
}

TEST(RunFile, FileWithoutTsIsCheckedAgainstExpectedTs) {
  const std::string text = "t_s,y_mm,u_V\n0.000,0,0\n0.005,0,0\n0.010,0,0\n";
  const auto run = parse_text(text, 0.005);
  ASSERT_TRUE(run.has_value()) << run.error().message;
  EXPECT_EQ(run->Ts, 0.005);
  const std::string message = parse_error_of(text, 0.01);
  EXPECT_TRUE(contains(message, "runs/a.csv:3:"));
  EXPECT_TRUE(contains(message, "0.005"));
}

TEST(RunFile, DifferentVersionTagRefused) {
  const std::string message = parse_error_of("# epa-run/2\n# Ts=0.005\nt_s,y_mm,u_V\n0,0,0\n");
  EXPECT_TRUE(contains(message, "runs/a.csv:1:"));
  EXPECT_TRUE(contains(message, "epa-run/2"));
  EXPECT_TRUE(contains(message, "version"));
}

TEST(RunFile, EmptyFileIsError) {
  EXPECT_TRUE(contains(parse_error_of(""), "runs/a.csv: empty file"));
  EXPECT_TRUE(contains(parse_error_of("\n  \r\n"), "runs/a.csv:2: no header"));
  EXPECT_TRUE(contains(parse_error_of("# epa-run/1\n# Ts=0.005\n"), "runs/a.csv:2: no header"));
}

TEST(RunFile, HeaderWithoutDataRowsIsError) {
  const std::string message = parse_error_of("# epa-run/1\n# Ts=0.005\nt_s,y_mm,u_V\n\n");
  EXPECT_TRUE(contains(message, "runs/a.csv:3:"));
  EXPECT_TRUE(contains(message, "without data rows"));
}

TEST(RunFile, MissingRequiredColumnNamedWithColumnsFound) {
  const std::string message = parse_error_of("# Ts=0.005\nt_s,r_mm,u_V\n0,0,0\n");
  EXPECT_TRUE(contains(message, "runs/a.csv:2:"));
  EXPECT_TRUE(contains(message, "missing required column 'y_mm'"));
  EXPECT_TRUE(contains(message, "found columns: 't_s', 'r_mm', 'u_V'"));
}

TEST(RunFile, DuplicateColumnIsError) {
  const std::string message = parse_error_of("# Ts=0.005\nt_s,y_mm,u_V,y_mm\n0,0,0,0\n");
  EXPECT_TRUE(contains(message, "runs/a.csv:2:"));
  EXPECT_TRUE(contains(message, "duplicate column 'y_mm'"));
}

TEST(RunFile, RowWithWrongFieldCountNamesLine) {
  const std::string message = parse_error_of("# Ts=0.005\nt_s,y_mm,u_V\n0,0,0\n0.005,0\n");
  EXPECT_TRUE(contains(message, "runs/a.csv:4:"));
  EXPECT_TRUE(contains(message, "expected 3 fields"));
  EXPECT_TRUE(contains(message, "got 2"));
}

TEST(RunFile, NonNumericFieldNamesLineColumnAndText) {
  for (const std::string bad : {"abc", "nan", "inf", "-inf", "", "1.5x", "1e999", "0x10"}) {
    const std::string message = parse_error_of("# Ts=0.005\nt_s,y_mm,u_V\n0,0,0\n0.005, " + bad + " ,0\n");
    EXPECT_TRUE(contains(message, "runs/a.csv:4:")) << bad;
    EXPECT_TRUE(contains(message, "column 'y_mm'")) << bad;
    EXPECT_TRUE(contains(message, "got '" + bad + "'")) << bad;
  }
}

TEST(RunFile, SpacesAndPlusSignAroundNumbersAccepted) {
  const auto run = parse_text("# Ts=0.005\n t_s , y_mm ,u_V\n 0 , +1.5e1 ,\t-2 \n");
  ASSERT_TRUE(run.has_value()) << run.error().message;
  EXPECT_EQ(run->y_mm, (std::vector<double>{15.0}));
  EXPECT_EQ(run->u_V, (std::vector<double>{-2.0}));
}

TEST(RunFile, InvalidTsMetadataIsError) {
  for (const std::string bad : {"0", "-0.005", "abc", "nan", ""}) {
    const std::string message = parse_error_of("# epa-run/1\n# Ts=" + bad + "\nt_s,y_mm,u_V\n0,0,0\n");
    EXPECT_TRUE(contains(message, "runs/a.csv:2:")) << bad;
    EXPECT_TRUE(contains(message, "Ts must be a positive number")) << bad;
  }
  EXPECT_TRUE(contains(parse_error_of("# Ts=0.005\n# Ts=0.01\nt_s,y_mm,u_V\n0,0,0\n"), "runs/a.csv:2: Ts given twice"));
}

TEST(RunFile, TsMismatchWithExpectedNamesBothValues) {
  const std::string message = parse_error_of("# epa-run/1\n# Ts=0.01\nt_s,y_mm,u_V\n0,0,0\n0.01,0,0\n", 0.005);
  EXPECT_TRUE(contains(message, "runs/a.csv:2:"));
  EXPECT_TRUE(contains(message, "Ts=0.01"));
  EXPECT_TRUE(contains(message, "but 0.005 s is expected (the model's Ts, or the other runs')")) << message;
}

TEST(RunFile, TsEqualToExpectedWithinRelativeTolerance) {
  const auto run = parse_text("# Ts=0.0050000000001\nt_s,y_mm,u_V\n0,0,0\n0.005,0,0\n", 0.005);
  ASSERT_TRUE(run.has_value()) << run.error().message;
  EXPECT_FALSE(parse_text("# Ts=0.0050001\nt_s,y_mm,u_V\n0,0,0\n", 0.005).has_value());
}

TEST(RunFile, NonUniformTimeNamesLineExpectedAndActualStep) {
  const std::string message =
      parse_error_of("# Ts=0.005\nt_s,y_mm,u_V\n0.000,0,0\n0.005,0,0\n0.015,0,0\n0.020,0,0\n");
  EXPECT_TRUE(contains(message, "runs/a.csv:5:"));
  EXPECT_TRUE(contains(message, "non-uniform time"));
  EXPECT_TRUE(contains(message, "Ts=0.005"));
  EXPECT_TRUE(contains(message, "got 0.01 s"));
}

TEST(RunFile, NonUniformTimeDetectedWithInferredTs) {
  const std::string message = parse_error_of("t_s,y_mm,u_V\n0.00,0,0\n0.01,0,0\n0.02,0,0\n0.04,0,0\n");
  EXPECT_TRUE(contains(message, "runs/a.csv:5:"));
  EXPECT_TRUE(contains(message, "inferred"));
  EXPECT_TRUE(contains(parse_error_of("t_s,y_mm,u_V\n0.01,0,0\n0.00,0,0\n"), "runs/a.csv:3: t_s must increase"));
}

TEST(RunFile, SingleSampleWithoutTsIsError) {
  EXPECT_TRUE(contains(parse_error_of("t_s,y_mm,u_V\n0,0,0\n"), "runs/a.csv:2:"));
  EXPECT_TRUE(parse_text("# Ts=0.005\nt_s,y_mm,u_V\n0,0,0\n").has_value());
}

TEST(RunFile, UnknownControllerRefused) {
  const std::string message = parse_error_of("# Ts=0.005\n# controller=pid\nt_s,y_mm,u_V\n0,0,0\n");
  EXPECT_TRUE(contains(message, "runs/a.csv:2:"));
  EXPECT_TRUE(contains(message, "unknown controller 'pid'"));
}

TEST(RunFile, WriteRunFileToUnwritablePathIsIoError) {
  const Status status = write_run_file("/nonexistent-dir/x.csv", make_run(3, false));
  ASSERT_FALSE(status.has_value());
  EXPECT_EQ(status.error().code, ErrorCode::kIo);
  EXPECT_TRUE(contains(status.error().message, "/nonexistent-dir/x.csv"));
}

TEST(RunFile, WriteRunFileRefusesRunsItCouldNotReadBack) {
  core::Run ragged = make_run(3, true);
  ragged.r_mm.pop_back();
  core::Run gap = make_run(3, false);
  gap.t_s[2] = 1.0;
  for (const core::Run& bad : {ragged, gap, make_run(0, false)}) {
    const Status status = write_run_file("/nonexistent-dir/x.csv", bad);
    ASSERT_FALSE(status.has_value());
    EXPECT_EQ(status.error().code, ErrorCode::kInvalidArgument);
  }
}

TEST(RunFile, WriteThenReadFileGivesSameRunAndLeavesNoTempFile) {
  namespace fs = std::filesystem;
  const fs::path dir = unique_temp_path("dir");
  const RemoveOnExit cleanup{dir};
  ASSERT_TRUE(fs::create_directories(dir));
  const std::string path = (dir / "run.csv").string();
  const core::Run run = make_run(200, true);
  ASSERT_TRUE(write_run_file(path, make_run(5, false)).has_value());
  const Status status = write_run_file(path, run);  // replaces the existing file
  ASSERT_TRUE(status.has_value()) << status.error().message;
  const auto back = read_run_file(path, 0.005);
  ASSERT_TRUE(back.has_value()) << back.error().message;
  expect_same_run(run, *back);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);  // no temp file left
}

TEST(RunFile, ReadRunFileErrorsNameThePath) {
  const auto missing = read_run_file("/nonexistent-dir/x.csv");
  ASSERT_FALSE(missing.has_value());
  EXPECT_EQ(missing.error().code, ErrorCode::kIo);
  EXPECT_TRUE(contains(missing.error().message, "/nonexistent-dir/x.csv"));

  namespace fs = std::filesystem;
  const fs::path path = unique_temp_path("bad.csv");
  const RemoveOnExit cleanup{path};
  std::ofstream(path) << "# Ts=0.005\nt_s,y_mm,u_V\n0,0,0\n0.005,x,0\n";
  const auto bad = read_run_file(path.string());
  ASSERT_FALSE(bad.has_value());
  EXPECT_TRUE(contains(bad.error().message, path.string() + ":4:"));
}

}  // namespace
}  // namespace epa::core

namespace epa::core {
namespace {

// A run file larger than the cap is refused at the first sample past it, naming the line, so a
// 10^7-row file costs a bounded amount of memory, not gigabytes.
TEST(RunFile, MoreSamplesThanTheCapAreRefusedNamingTheLine) {
  std::stringstream in;
  in << "# epa-run/1\n# Ts=0.005\nt_s,y_mm,u_V\n";
  for (std::size_t k = 0; k <= kMaxRunSamples; ++k) in << k * 0.005 << ",1,0\n";
  const auto r = parse_run(in, "big.csv");
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("big.csv:" + std::to_string(kMaxRunSamples + 4) + ":"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("2000000"), std::string::npos) << r.error().message;
}

}  // namespace
}  // namespace epa::core
