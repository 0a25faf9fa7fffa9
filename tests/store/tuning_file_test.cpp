#include "store/tuning_file.hpp"

#include <gtest/gtest.h>

#include "store_fixture.hpp"

namespace epa::store {
namespace {

using testing::paper_seed;

TuningFile example() {
  const StoreSeed seed = paper_seed();
  TuningFile f{seed.tuning, seed.model};
  f.set.name = "rig 2 \"after service\"";
  f.set.source = "epa design --poles 0.9";
  f.set.design_json = R"({"poles":[0.9,0.9]})";
  f.set.controller = control::ControllerKind::kPpNgidz;
  f.set.dead_zone.m_r = 1.0 / 3.0;  // not representable in few digits: must still round-trip exactly
  f.model.fit_json = R"({"fit_pct":88.5})";
  f.model.model.B = core::Polynomial({0.0, 1.0 / 7.0, -2.046, 1.029});
  f.set.trajectory.speed_fraction = 0.55;
  f.set.trajectory.hold_band_mm = 1.0 / 30.0;
  return f;
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

TEST(TuningFile, ExportThenImportGivesTheSameSetAndModel) {
  const TuningFile f = example();
  const std::string text = format_tuning_toml(f.set, f.model);
  auto back = parse_tuning_toml(text, "x.toml");
  ASSERT_TRUE(back) << back.error().message << "\n" << text;
  EXPECT_EQ(back->set.name, f.set.name);
  EXPECT_EQ(back->set.source, f.set.source);
  EXPECT_EQ(back->set.design_json, f.set.design_json);
  EXPECT_EQ(back->set.controller, f.set.controller);
  EXPECT_EQ(back->set.F.coefficients(), f.set.F.coefficients());
  EXPECT_EQ(back->set.G.coefficients(), f.set.G.coefficients());
  EXPECT_EQ(back->set.H.coefficients(), f.set.H.coefficients());
  EXPECT_EQ(back->set.dead_zone.m_r, f.set.dead_zone.m_r);
  EXPECT_EQ(back->set.dead_zone.b_l, f.set.dead_zone.b_l);
  EXPECT_EQ(back->set.lc_mm, f.set.lc_mm);
  EXPECT_EQ(back->set.valve_limit_v, f.set.valve_limit_v);
  EXPECT_EQ(back->set.trajectory, f.set.trajectory);
  EXPECT_EQ(back->model.name, f.model.name);
  EXPECT_EQ(back->model.source, f.model.source);
  EXPECT_EQ(back->model.fit_json, f.model.fit_json);
  EXPECT_EQ(back->model.model.A.coefficients(), f.model.model.A.coefficients());
  EXPECT_EQ(back->model.model.B.coefficients(), f.model.model.B.coefficients());
  EXPECT_EQ(back->model.model.Ts, f.model.model.Ts);
  EXPECT_EQ(format_tuning_toml(back->set, back->model), text);  // and the text is stable
}

TEST(TuningFile, PpTrajSettingsAreOptionalAndAnUnknownOneIsRefusedByName) {
  const TuningFile f = example();
  const std::string text = format_tuning_toml(f.set, f.model);
  // A file from before pp-traj (no [trajectory]) imports with the defaults.
  const auto start = text.find("[trajectory]");
  const auto end = text.find("\n[", start + 1);
  ASSERT_NE(start, std::string::npos);
  auto old = parse_tuning_toml(text.substr(0, start) + text.substr(end + 1), "old.toml");
  ASSERT_TRUE(old) << old.error().message;
  EXPECT_EQ(old->set.trajectory, TrajectorySettings{});
  auto bad = parse_tuning_toml(replaced(text, "speed_fraction = ", "top_speed = "), "bad.toml");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("top_speed"), std::string::npos) << bad.error().message;
  // pp-traj on this example's model (B(1) < 0: more valve, less speed) is refused with why...
  auto pp_traj = parse_tuning_toml(replaced(text, "controller = \"pp-ngidz\"", "controller = \"pp-traj\""), "t.toml");
  ASSERT_FALSE(pp_traj);
  EXPECT_NE(pp_traj.error().message.find("speed gain"), std::string::npos) << pp_traj.error().message;
  // ...and accepted on the paper's model.
  const StoreSeed seed = paper_seed();
  TuningSet set = f.set;
  set.controller = control::ControllerKind::kPpTraj;
  auto paper = parse_tuning_toml(format_tuning_toml(set, seed.model), "p.toml");
  ASSERT_TRUE(paper) << paper.error().message;
  EXPECT_EQ(paper->set.controller, control::ControllerKind::kPpTraj);
}

TEST(TuningFile, ThePaperValuesAreWrittenAsPrinted) {
  const std::string text = format_tuning_toml(paper_seed().tuning, paper_seed().model);
  EXPECT_NE(text.find("F = [1.0, -1.778, 0.7828]"), std::string::npos) << text;
  EXPECT_NE(text.find("[model.arx]"), std::string::npos) << text;
}


// The embedded model carries the stick-slip model, its spread, the verdict and the drive range under
// the model file's own keys, and they come back exact; a file without them reads as before.
TEST(TuningFile, TheEmbeddedModelCarriesItsStickSlipModelExactly) {
  const TuningFile f = example();
  ModelRecord model = testing::stick_slip_model_record();
  model.model.B = f.model.model.B;
  const std::string text = format_tuning_toml(f.set, model);
  for (const char* expected : {"[model.stick_slip]\n", "[model.stick_slip_spread]\n", "axis_model = \"stick-slip\"\n",
                               "identified_drive_v = [", "delay_samples = 2\n", "friction_log_ratio = 0.33\n"})
    EXPECT_NE(text.find(expected), std::string::npos) << expected << " in\n" << text;
  auto back = parse_tuning_toml(text, "x.toml");
  ASSERT_TRUE(back) << back.error().message << "\n" << text;
  EXPECT_EQ(back->model.axis_model, core::AxisModel::kStickSlip);
  EXPECT_EQ(back->model.identified_drive_v, model.identified_drive_v);
  EXPECT_EQ(back->model.stick_slip, model.stick_slip);
  EXPECT_EQ(back->model.stick_slip_spread, model.stick_slip_spread);
  EXPECT_EQ(back->model.name, "rig-2");
  EXPECT_EQ(format_tuning_toml(back->set, back->model), text);

  auto plain = parse_tuning_toml(format_tuning_toml(f.set, f.model), "plain.toml");  // none of them
  ASSERT_TRUE(plain) << plain.error().message;
  EXPECT_FALSE(plain->model.stick_slip);
  EXPECT_FALSE(plain->model.stick_slip_spread);
  EXPECT_FALSE(plain->model.identified_drive_v);
  EXPECT_EQ(plain->model.axis_model, core::AxisModel::kHammerstein);

  struct Case {
    std::string text, expected;
  };
  const Case cases[] = {
      {replaced(text, "coulomb_mm = ", "coulomb = "), "unknown key 'coulomb' in [stick_slip]"},
      {replaced(text, "break_v = ", "break_volts = "), "unknown key 'break_volts' in [stick_slip_spread]"},
      {replaced(text, "[model.stick_slip]\n", "[model.stick_slip]\nmass_kg = 2.0\n"), "unknown key 'mass_kg' in [stick_slip]"},
      {replaced(text, "[model]\n", "[model]\naxis = 1.0\n"), "unknown key 'axis' in [model]"},
      {replaced(text, "delay_samples = 2", "delay_samples = 2.5"), "delay_samples must be a whole number"},
      {replaced(text, "axis_model = \"stick-slip\"", "axis_model = \"friction\""), "axis_model must be"},
  };
  for (const auto& c : cases) {
    auto r = parse_tuning_toml(c.text, "x.toml");
    ASSERT_FALSE(r) << c.expected;
    EXPECT_NE(r.error().message.find(c.expected), std::string::npos) << r.error().message;
  }
}

TEST(TuningFile, BadFilesAreRefusedNamingWhatIsWrong) {
  const TuningFile f = example();
  const std::string good = format_tuning_toml(f.set, f.model);
  struct Case {
    std::string text, expected;
  };
  const Case cases[] = {
      {replaced(good, "lc_mm = ", "lc_millimetres = "), "unknown key 'lc_millimetres' (expected one of: schema, name, "},
      {replaced(good, "schema = \"epa-tuning/1\"", "schema = \"epa-tuning/9\""), "epa-tuning/9"},
      {replaced(good, "controller = \"pp-ngidz\"", "controller = \"pid\""), "controller"},
      {replaced(good, "b_l = -1.722", "b_l = 3.0"), "b_l"},  // b_l > b_r: refused whole
      {replaced(good, "[rst]\n", "[rst]\nX = [1.0]\n"), "unknown key 'X' in [rst] (expected one of: F, G, H)"},
      {replaced(good, "[trajectory]  # pp-traj's parameters (docs/paper.md, \"Beyond the paper: pp-traj\")\n",
                "[trajectory]  # pp-traj's parameters (docs/paper.md, \"Beyond the paper: pp-traj\")\ncoast = 1.0\n"),
       "unknown key 'coast' in [trajectory] (expected one of: "},
      {replaced(good, "lc_mm = 5.0", "lc_mm = \"five\""), "lc_mm must be a number"},
      {replaced(good, "lc_mm = 5.0", "lc_mm = = 5"), "x.toml:"},
      {replaced(good, "lc_mm = 5.0", "lc_mm = 1e300"), "lc_mm 1e+300 is outside [-1e6, 1e6]"},
      {replaced(good, "lc_mm = 5.0", "lc_mm = nan"), "lc_mm nan is outside"},
      {replaced(good, "b_l = -1.722", "b_l = -inf"), "b_l -inf is outside"},
      {good.substr(0, good.find("[model]")), "[model] is missing"},
  };
  for (const auto& c : cases) {
    auto r = parse_tuning_toml(c.text, "x.toml");
    ASSERT_FALSE(r) << c.expected;
    EXPECT_NE(r.error().message.find(c.expected), std::string::npos) << r.error().message;
  }
}

}  // namespace
}  // namespace epa::store
