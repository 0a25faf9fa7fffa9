#include "core/model_file.hpp"

#include <gtest/gtest.h>

#include <tuple>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "core/paper_reference.hpp"
#include "../support/temp_path.hpp"
#include "../support/text_contains.hpp"

namespace epa::core {
namespace {

const std::string kPaperModelPath = std::string(EPA_SOURCE_DIR) + "/config/paper-model.toml";

using epa::test::contains;

// Field-by-field equality (HammersteinModel has no operator==), exact: every value in these
// files is a short decimal that parses to the same double as the C++ literal.
void expect_same_model(const HammersteinModel& actual, const HammersteinModel& expected) {
  EXPECT_EQ(actual.A.coefficients(), expected.A.coefficients());
  EXPECT_EQ(actual.B.coefficients(), expected.B.coefficients());
  EXPECT_EQ(actual.dead_zone, expected.dead_zone);
  EXPECT_EQ(actual.dead_zone.m_r, expected.dead_zone.m_r);
  EXPECT_EQ(actual.dead_zone.m_l, expected.dead_zone.m_l);
  EXPECT_EQ(actual.dead_zone.b_r, expected.dead_zone.b_r);
  EXPECT_EQ(actual.dead_zone.b_l, expected.dead_zone.b_l);
  EXPECT_EQ(actual.Ts, expected.Ts);
  EXPECT_EQ(actual.mm_per_volt, expected.mm_per_volt);
}

// A valid file in the documented layout; tests break one thing at a time.
const std::string kValidText = R"(schema = "epa-model/1"
Ts = 0.005
mm_per_volt = 50.0
source = "hand-written test model"

[arx]
A = [1.0, -0.9094, -0.6110, 0.5204]
B = [0.0, 1.024, -2.046, 1.029]

[dead_zone]
m_r = 1.7627
m_l = 1.0707
b_r = 1.232
b_l = -1.722
)";

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "test setup: '" << from << "' not in the text";
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}


TEST(ModelFile, PaperModelFileEqualsThePaperReference) {
  const auto file = read_model_file(kPaperModelPath);
  ASSERT_TRUE(file.has_value()) << file.error().message;
  expect_same_model(file->model, paper::model());
  EXPECT_FALSE(file->source.empty());
}

TEST(ModelFile, ValidTextParsesToTheDocumentedFields) {
  const auto file = parse_model_toml(kValidText, "test.toml");
  ASSERT_TRUE(file.has_value()) << file.error().message;
  EXPECT_EQ(file->model.A.coefficients(), (std::vector<double>{1.0, -0.9094, -0.6110, 0.5204}));
  EXPECT_EQ(file->model.B.coefficients(), (std::vector<double>{0.0, 1.024, -2.046, 1.029}));
  EXPECT_EQ(file->model.dead_zone.m_r, 1.7627);
  EXPECT_EQ(file->model.dead_zone.m_l, 1.0707);
  EXPECT_EQ(file->model.dead_zone.b_r, 1.232);
  EXPECT_EQ(file->model.dead_zone.b_l, -1.722);
  EXPECT_EQ(file->model.Ts, 0.005);
  EXPECT_EQ(file->model.mm_per_volt, 50.0);
  EXPECT_EQ(file->source, "hand-written test model");
}

// The valid text with `from` replaced by `to` is refused, the message holding `expected`.
void expect_refused(const std::string& from, const std::string& to, const std::string& expected) {
  const auto r = parse_model_toml(replaced(kValidText, from, to), "m.toml");
  ASSERT_FALSE(r.has_value()) << to;
  EXPECT_NE(r.error().message.find(expected), std::string::npos) << r.error().message;
}

// Every number is bounded: 1e300, NaN and infinities are refused naming the key and its line.
TEST(ModelFile, NumbersOutsideAnyPhysicalRangeAreRefusedNamingKeyAndLine) {
  for (const auto& [from, to, expected] :
       {std::tuple{"Ts = 0.005", "Ts = 1e300", "Ts 1e+300 is outside [-1e6, 1e6] (line "},
        std::tuple{"Ts = 0.005", "Ts = nan", "Ts nan is outside"},
        std::tuple{"-0.9094", "-inf", "A[1] -inf is outside"}}) {
    expect_refused(from, to, expected);
  }
}

// A misspelt key is refused naming it and its line, in every table: an outside walk-through's
// `mm_per_vlot = 25` had run on the default 50 mm/V, and `b_rx` in [dead_zone] had been ignored.
TEST(ModelFile, AMisspeltKeyIsRefusedNamingItAndItsLine) {
  for (const auto& [from, to, expected] :
       {std::tuple{"Ts = 0.005", "Ts = 0.005\nmm_per_vlot = 25.0",
                   "m.toml:3: unknown key 'mm_per_vlot' (expected one of: schema, Ts, mm_per_volt, source, axis_model, "
                   "identified_drive_v, arx, dead_zone, stick_slip, stick_slip_spread)"},
        std::tuple{"Ts = 0.005", "Ts = 0.005\naxis_modle = \"stick-slip\"", "m.toml:3: unknown key 'axis_modle' (expected"},
        std::tuple{"[dead_zone]", "[dead_zone]\nb_rx = 9.0",
                   "unknown key 'b_rx' in [dead_zone] (expected one of: m_r, m_l, b_r, b_l)"},
        std::tuple{"[arx]", "[arx]\nC = [1.0]", "unknown key 'C' in [arx] (expected one of: A, B)"}}) {
    expect_refused(from, to, expected);
  }
}

TEST(ModelFile, IntegerValuesAreAcceptedAsNumbers) {
  // A hand-written file may well say "mm_per_volt = 50" or "b_r = 1".
  std::string text = replaced(kValidText, "mm_per_volt = 50.0", "mm_per_volt = 50");
  text = replaced(text, "b_r = 1.232", "b_r = 1");
  text = replaced(text, "A = [1.0,", "A = [1,");
  const auto file = parse_model_toml(text, "int.toml");
  ASSERT_TRUE(file.has_value()) << file.error().message;
  EXPECT_EQ(file->model.mm_per_volt, 50.0);
  EXPECT_EQ(file->model.dead_zone.b_r, 1.0);
  EXPECT_EQ(file->model.A[0], 1.0);
}

TEST(ModelFile, FormatThenParseRoundTripsThePaperModel) {
  const ModelFile original{paper::model(), "round trip"};
  const auto back = parse_model_toml(format_model_toml(original), "formatted");
  ASSERT_TRUE(back.has_value()) << back.error().message;
  expect_same_model(back->model, original.model);
  EXPECT_EQ(back->source, original.source);
}

TEST(ModelFile, FormatThenParseRoundTripsOtherShortDecimals) {
  ModelFile original;
  original.model.A = {1.0, -1.25, 0.375};
  original.model.B = {0.0, 0.5, 0.125, -0.0625};
  original.model.dead_zone = {.m_r = 2.5, .m_l = 0.75, .b_r = 0.5, .b_l = -0.25};
  original.model.Ts = 0.01;
  original.model.mm_per_volt = 25.0;
  original.source = "identified on bench 2";
  const auto back = parse_model_toml(format_model_toml(original), "formatted");
  ASSERT_TRUE(back.has_value()) << back.error().message;
  expect_same_model(back->model, original.model);
  EXPECT_EQ(back->source, original.source);
}

// format_model_toml writes the shortest text that reads back to the same double.
TEST(ModelFile, FormatRoundTripsArbitraryValuesExactly) {
  ModelFile original{paper::model(), ""};
  original.model.A = {1.0, -0.90941234567891234, -0.61101234567891234, 0.52041234567891234};
  original.model.dead_zone.m_r = 1.0 / 3.0;
  const auto back = parse_model_toml(format_model_toml(original), "formatted");
  ASSERT_TRUE(back.has_value()) << back.error().message;
  for (std::size_t i = 0; i < original.model.A.size(); ++i)
    EXPECT_EQ(back->model.A[i], original.model.A[i]) << i;
  EXPECT_EQ(back->model.dead_zone.m_r, 1.0 / 3.0);
}

TEST(ModelFile, SourceWithQuotesAndBackslashesRoundTrips) {
  ModelFile original{paper::model(), "bench \"2\", C:\\runs\\a.csv; line\tend"};
  const auto back = parse_model_toml(format_model_toml(original), "formatted");
  ASSERT_TRUE(back.has_value()) << back.error().message;
  EXPECT_EQ(back->source, original.source);
}

TEST(ModelFile, SyntaxErrorNamesTheFileAndLine) {
  // Line 3 is broken.
  const std::string text = "schema = \"epa-model/1\"\nTs = 0.005\nmm_per_volt = = 50\n";
  const auto file = parse_model_toml(text, "name");
  ASSERT_FALSE(file.has_value());
  EXPECT_EQ(file.error().code, ErrorCode::kParse);
  EXPECT_EQ(file.error().message.rfind("name:3:", 0), 0u) << file.error().message;
}

TEST(ModelFile, MissingArxTableIsNamed) {
  std::string text = replaced(kValidText, "[arx]\nA = [1.0, -0.9094, -0.6110, 0.5204]\nB = [0.0, 1.024, -2.046, 1.029]\n", "");
  const auto file = parse_model_toml(text, "no-arx.toml");
  ASSERT_FALSE(file.has_value());
  EXPECT_TRUE(contains(file.error().message, "[arx]"));
  EXPECT_TRUE(contains(file.error().message, "missing"));
  EXPECT_TRUE(contains(file.error().message, "no-arx.toml"));
}

const std::string kStickSlipTable = R"(
[stick_slip]
break_right_v = 1.17
break_left_v = -1.67
speed_right_mm_s_per_v = 107.5
speed_left_mm_s_per_v = 101.0
spring_rad_s = 52.0
damping_ratio = 0.3
coulomb_mm = 5.0
static_mm = 7.25
spool_lag_s = 0.013
delay_samples = 2
)";

TEST(ModelFile, AFileWithoutAStickSlipTableHasNone) {
  const auto file = parse_model_toml(kValidText, "plain.toml");
  ASSERT_TRUE(file.has_value()) << file.error().message;
  EXPECT_FALSE(file->stick_slip.has_value());
  EXPECT_EQ(format_model_toml(*file).find("stick_slip"), std::string::npos);
}

TEST(ModelFile, TheStickSlipTableParsesToItsFieldsAndRoundTrips) {
  const auto file = parse_model_toml(kValidText + kStickSlipTable, "ss.toml");
  ASSERT_TRUE(file.has_value()) << file.error().message;
  ASSERT_TRUE(file->stick_slip.has_value());
  const auto& p = *file->stick_slip;
  EXPECT_EQ(p.break_right_v, 1.17);
  EXPECT_EQ(p.break_left_v, -1.67);
  EXPECT_EQ(p.speed_right_mm_s_per_v, 107.5);
  EXPECT_EQ(p.speed_left_mm_s_per_v, 101.0);
  EXPECT_EQ(p.spring_rad_s, 52.0);
  EXPECT_EQ(p.damping_ratio, 0.3);
  EXPECT_EQ(p.coulomb_mm, 5.0);
  EXPECT_EQ(p.static_mm, 7.25);
  EXPECT_EQ(p.spool_lag_s, 0.013);
  EXPECT_EQ(p.delay_samples, 2);
  const auto back = parse_model_toml(format_model_toml(*file), "formatted");
  ASSERT_TRUE(back.has_value()) << back.error().message;
  ASSERT_TRUE(back->stick_slip.has_value());
  EXPECT_EQ(back->stick_slip->static_mm, 7.25);
  EXPECT_EQ(back->stick_slip->spool_lag_s, 0.013);
  EXPECT_EQ(back->stick_slip->delay_samples, 2);
}

TEST(ModelFile, AStickSlipTableWithAMissingOrWrongFieldIsRefusedByName) {
  const std::string text = kValidText + kStickSlipTable;
  auto file = parse_model_toml(replaced(text, "coulomb_mm = 5.0\n", ""), "ss.toml");
  ASSERT_FALSE(file.has_value());
  EXPECT_TRUE(contains(file.error().message, "[stick_slip] coulomb_mm is missing"));
  file = parse_model_toml(replaced(text, "delay_samples = 2", "delay_samples = 1.5"), "ss.toml");
  ASSERT_FALSE(file.has_value());
  EXPECT_TRUE(contains(file.error().message, "delay_samples must be a whole number"));
  file = parse_model_toml(replaced(text, "delay_samples = 2", "delay_samples = 20"), "ss.toml");
  ASSERT_FALSE(file.has_value());
  EXPECT_TRUE(contains(file.error().message, "delay_samples 20 is outside 0..8"));
  file = parse_model_toml(replaced(text, "static_mm = 7.25", "static_mm = 4.0"), "ss.toml");
  ASSERT_FALSE(file.has_value());
  EXPECT_TRUE(contains(file.error().message, "static_mm must be >= coulomb_mm"));
  file = parse_model_toml(replaced(kValidText, "[arx]", "stick_slip = 3\n\n[arx]"), "ss.toml");
  ASSERT_FALSE(file.has_value());
  EXPECT_TRUE(contains(file.error().message, "stick_slip must be a table"));
}

// The valve commands the model was identified on: read, written back, and refused by name when
// they are not a range around the centred valve.
TEST(ModelFile, TheIdentifiedDriveRangeParsesRoundTripsAndIsCheckedByName) {
  const auto file = parse_model_toml(replaced(kValidText, "Ts = 0.005", "Ts = 0.005\nidentified_drive_v = [-3.0, 2.5]"), "d.toml");
  ASSERT_TRUE(file.has_value()) << file.error().message;
  ASSERT_TRUE(file->identified_drive_v.has_value());
  EXPECT_EQ((*file->identified_drive_v)[0], -3.0);
  EXPECT_EQ((*file->identified_drive_v)[1], 2.5);
  const auto back = parse_model_toml(format_model_toml(*file), "formatted");
  ASSERT_TRUE(back.has_value()) << back.error().message;
  EXPECT_EQ(back->identified_drive_v, file->identified_drive_v);
  EXPECT_FALSE(parse_model_toml(kValidText, "plain.toml")->identified_drive_v.has_value());
  for (const char* bad : {"[1.0, 3.0]", "[-3.0]", "[-3.0, 0.0, 3.0]", "[-11.0, 3.0]"}) {
    const auto r = parse_model_toml(replaced(kValidText, "Ts = 0.005", std::string("Ts = 0.005\nidentified_drive_v = ") + bad), "d.toml");
    ASSERT_FALSE(r.has_value()) << bad;
    EXPECT_TRUE(contains(r.error().message, "identified_drive_v must be [lowest, highest]")) << r.error().message;
  }
}

// The stick-slip model's spread: every field read and written back; it needs the model it is the
// spread of, and a negative or missing field is refused by name.
TEST(ModelFile, TheStickSlipSpreadParsesRoundTripsAndNeedsItsModel) {
  const std::string spread =
      "\n[stick_slip_spread]\nfriction_log_ratio = 0.33\nflow_gain_log_ratio = 0.08\nbreak_v = 0.1\nspool_lag_s = 0.012\n"
      "delay_samples = 1.0\n";
  const auto file = parse_model_toml(kValidText + kStickSlipTable + spread, "s.toml");
  ASSERT_TRUE(file.has_value()) << file.error().message;
  ASSERT_TRUE(file->stick_slip_spread.has_value());
  EXPECT_EQ(file->stick_slip_spread->friction_log_ratio, 0.33);
  EXPECT_EQ(file->stick_slip_spread->spool_lag_s, 0.012);
  const auto back = parse_model_toml(format_model_toml(*file), "formatted");
  ASSERT_TRUE(back.has_value()) << back.error().message;
  ASSERT_TRUE(back->stick_slip_spread.has_value());
  EXPECT_EQ(back->stick_slip_spread->break_v, 0.1);
  EXPECT_EQ(back->stick_slip_spread->delay_samples, 1.0);

  auto r = parse_model_toml(kValidText + spread, "s.toml");
  ASSERT_FALSE(r.has_value());
  EXPECT_TRUE(contains(r.error().message, "[stick_slip_spread] needs a [stick_slip] table")) << r.error().message;
  r = parse_model_toml(kValidText + kStickSlipTable + replaced(spread, "break_v = 0.1", "break_v = -0.1"), "s.toml");
  ASSERT_FALSE(r.has_value());
  EXPECT_TRUE(contains(r.error().message, "break_v must be finite and >= 0")) << r.error().message;
  r = parse_model_toml(kValidText + kStickSlipTable + replaced(spread, "spool_lag_s = 0.012\n", ""), "s.toml");
  ASSERT_FALSE(r.has_value());
  EXPECT_TRUE(contains(r.error().message, "spool_lag_s")) << r.error().message;
}

TEST(ModelFile, TheAxisModelIsHammersteinUnlessTheFileSaysStickSlipAndRoundTrips) {
  auto file = parse_model_toml(kValidText + kStickSlipTable, "ss.toml");
  ASSERT_TRUE(file.has_value()) << file.error().message;
  EXPECT_EQ(file->axis_model, AxisModel::kHammerstein);
  EXPECT_TRUE(contains(format_model_toml(*file), "[stick_slip]"));
  EXPECT_EQ(format_model_toml(*file).find("axis_model"), std::string::npos);
  file = parse_model_toml(replaced(kValidText, "[arx]", "axis_model = \"stick-slip\"\n\n[arx]") + kStickSlipTable, "ss.toml");
  ASSERT_TRUE(file.has_value()) << file.error().message;
  EXPECT_EQ(file->axis_model, AxisModel::kStickSlip);
  const auto back = parse_model_toml(format_model_toml(*file), "formatted");
  ASSERT_TRUE(back.has_value()) << back.error().message;
  EXPECT_EQ(back->axis_model, AxisModel::kStickSlip);
  file = parse_model_toml(replaced(kValidText, "[arx]", "axis_model = \"hammerstein\"\n\n[arx]"), "h.toml");
  ASSERT_TRUE(file.has_value()) << file.error().message;
  EXPECT_EQ(file->axis_model, AxisModel::kHammerstein);
}

TEST(ModelFile, AStickSlipAxisWithoutItsTableOrAnUnknownAxisModelIsRefusedByName) {
  auto file = parse_model_toml(replaced(kValidText, "[arx]", "axis_model = \"stick-slip\"\n\n[arx]"), "ss.toml");
  ASSERT_FALSE(file.has_value());
  EXPECT_TRUE(contains(file.error().message, "needs a [stick_slip] table"));
  EXPECT_TRUE(contains(file.error().message, "ss.toml"));
  file = parse_model_toml(replaced(kValidText, "[arx]", "axis_model = \"linear\"\n\n[arx]") + kStickSlipTable, "ss.toml");
  ASSERT_FALSE(file.has_value());
  EXPECT_TRUE(contains(file.error().message, "axis_model must be"));
  file = parse_model_toml(replaced(kValidText, "[arx]", "axis_model = 2\n\n[arx]"), "ss.toml");
  ASSERT_FALSE(file.has_value());
  EXPECT_TRUE(contains(file.error().message, "axis_model must be"));
}

TEST(ModelFile, MissingDeadZoneKeyIsNamed) {
  const auto file = parse_model_toml(replaced(kValidText, "b_l = -1.722\n", ""), "dz.toml");
  ASSERT_FALSE(file.has_value());
  EXPECT_TRUE(contains(file.error().message, "b_l"));
  EXPECT_TRUE(contains(file.error().message, "missing"));
  EXPECT_TRUE(contains(file.error().message, "dz.toml"));
}

TEST(ModelFile, MissingDeadZoneTableIsNamed) {
  const auto file =
      parse_model_toml(replaced(kValidText, "[dead_zone]\nm_r = 1.7627\nm_l = 1.0707\nb_r = 1.232\nb_l = -1.722\n", ""),
                       "dz.toml");
  ASSERT_FALSE(file.has_value());
  EXPECT_TRUE(contains(file.error().message, "dead_zone"));
}

TEST(ModelFile, WrongSchemaIsRefused) {
  const auto file = parse_model_toml(replaced(kValidText, "epa-model/1", "epa-model/2"), "v2.toml");
  ASSERT_FALSE(file.has_value());
  EXPECT_TRUE(contains(file.error().message, "schema"));
  EXPECT_TRUE(contains(file.error().message, "epa-model/2"));
}

TEST(ModelFile, MissingSchemaIsRefused) {
  const auto file = parse_model_toml(replaced(kValidText, "schema = \"epa-model/1\"\n", ""), "old.toml");
  ASSERT_FALSE(file.has_value());
  EXPECT_TRUE(contains(file.error().message, "schema"));
}

TEST(ModelFile, NonMonicAIsRefused) {
  const auto file = parse_model_toml(replaced(kValidText, "A = [1.0,", "A = [2.0,"), "a.toml");
  ASSERT_FALSE(file.has_value());
  EXPECT_TRUE(contains(file.error().message, "monic"));
}

TEST(ModelFile, NonNumberInBIsNamedByIndex) {
  const auto file = parse_model_toml(replaced(kValidText, "B = [0.0, 1.024,", "B = [0.0, \"x\","), "b.toml");
  ASSERT_FALSE(file.has_value());
  EXPECT_TRUE(contains(file.error().message, "B[1]"));
}

TEST(ModelFile, NonNumberTsIsRefused) {
  const auto file = parse_model_toml(replaced(kValidText, "Ts = 0.005", "Ts = \"fast\""), "ts.toml");
  ASSERT_FALSE(file.has_value());
  EXPECT_TRUE(contains(file.error().message, "Ts"));
}

TEST(ModelFile, InvalidDeadZoneIsRefusedNamingTheField) {
  const auto file = parse_model_toml(replaced(kValidText, "m_l = 1.0707", "m_l = -1.0707"), "slope.toml");
  ASSERT_FALSE(file.has_value());
  EXPECT_TRUE(contains(file.error().message, "m_l"));
}

TEST(ModelFile, WriteThenReadGivesTheSameModel) {
  const std::string path = epa::test::unique_temp_path("epa-model-test.toml").string();
  const ModelFile original{paper::model(), "written by model_file_test"};
  const Status written = write_model_file(path, original);
  ASSERT_TRUE(written.has_value()) << written.error().message;
  const auto back = read_model_file(path);
  std::filesystem::remove(path);
  ASSERT_TRUE(back.has_value()) << back.error().message;
  expect_same_model(back->model, original.model);
  EXPECT_EQ(back->source, original.source);
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
}

TEST(ModelFile, WriteReplacesAnExistingFile) {
  const std::string path = epa::test::unique_temp_path("epa-model-replace.toml").string();
  ModelFile first{paper::model(), "first"};
  ASSERT_TRUE(write_model_file(path, first).has_value());
  ModelFile second = first;
  second.source = "second";
  second.model.Ts = 0.01;
  ASSERT_TRUE(write_model_file(path, second).has_value());
  const auto back = read_model_file(path);
  std::filesystem::remove(path);
  ASSERT_TRUE(back.has_value()) << back.error().message;
  EXPECT_EQ(back->source, "second");
  EXPECT_EQ(back->model.Ts, 0.01);
}

TEST(ModelFile, ReadingAMissingFileNamesThePath) {
  const std::string path = "/nonexistent-epa-dir/model.toml";
  const auto file = read_model_file(path);
  ASSERT_FALSE(file.has_value());
  EXPECT_EQ(file.error().code, ErrorCode::kIo);
  EXPECT_TRUE(contains(file.error().message, path));
}

TEST(ModelFile, WritingIntoAMissingDirectoryIsAnError) {
  const std::string path = "/nonexistent-epa-dir/model.toml";
  const Status s = write_model_file(path, ModelFile{paper::model(), ""});
  ASSERT_FALSE(s.has_value());
  EXPECT_TRUE(contains(s.error().message, path));
}

// Two fits within the margin are equal, and then the axis is the Hammerstein model's: the verdict
// changes pp-traj's arrival, which takes evidence (identify and commission both ask this).
TEST(AxisModelVerdict, TheStickSlipModelMustFollowTheRunsBetterByMoreThanTheMargin) {
  EXPECT_EQ(axis_model_from_fits(67.4, 67.3), AxisModel::kHammerstein);
  EXPECT_EQ(axis_model_from_fits(70.0, 70.0), AxisModel::kHammerstein);
  EXPECT_EQ(axis_model_from_fits(67.3 + kAxisModelMarginPct, 67.3), AxisModel::kHammerstein);
  EXPECT_EQ(axis_model_from_fits(67.3 + kAxisModelMarginPct + 0.01, 67.3), AxisModel::kStickSlip);
  EXPECT_EQ(axis_model_from_fits(92.5, 69.4), AxisModel::kStickSlip);
  EXPECT_EQ(axis_model_from_fits(66.3, 99.7), AxisModel::kHammerstein);
  EXPECT_EQ(axis_model_from_fits(NAN, 60.0), AxisModel::kHammerstein);  // no stick-slip figure: no evidence
}

}  // namespace
}  // namespace epa::core
