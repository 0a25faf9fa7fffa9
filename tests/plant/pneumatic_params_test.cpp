// PneumaticParams: the validator, and the epa-pneumatic/1 file (reader, writer, config file).
#include "plant/pneumatic_params.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>

#include "../support/temp_path.hpp"

namespace epa::plant {
namespace {

std::string validation_message(const PneumaticParams& p) {
  const auto s = p.validate();
  return s ? std::string("(valid)") : s.error().message;
}

std::string parse_message(const std::string& text) {
  const auto r = parse_pneumatic_toml(text, "rig.toml");
  return r ? std::string("(parsed)") : r.error().message;
}

TEST(PneumaticParams, DefaultsAreValid) { EXPECT_EQ(validation_message({}), "(valid)"); }

TEST(PneumaticParams, ValidationNamesTheFieldAndTheValue) {
  struct Case {
    double PneumaticParams::*field;
    double value;
    const char* expected;
  };
  const Case cases[] = {
      {&PneumaticParams::bore_mm, std::numeric_limits<double>::quiet_NaN(), "[cylinder] bore_mm = nan"},
      {&PneumaticParams::piston_mass_kg, 0.0, "[cylinder] piston_mass_kg = 0"},
      {&PneumaticParams::supply_pressure_bar, 40.0, "[supply] supply_pressure_bar = 40"},
      {&PneumaticParams::discharge_coefficient, 0.0, "[valve] discharge_coefficient = 0"},
      {&PneumaticParams::orifice_area_mm2, -1.0, "[valve] orifice_area_mm2 = -1"},
      {&PneumaticParams::overlap_neg_v, 0.5, "[valve] overlap_neg_v = 0.5"},
      {&PneumaticParams::stribeck_velocity_mps, std::numeric_limits<double>::infinity(),
       "[friction] stribeck_velocity_mps = inf"},
      {&PneumaticParams::rod_mm, 32.0, "[cylinder] rod_mm = 32 must be smaller than bore_mm = 32"},
      {&PneumaticParams::coulomb_friction_n, 50.0, "[friction] coulomb_friction_n = 50 must not exceed static_friction_n = 40"},
  };
  for (const Case& c : cases) {
    PneumaticParams p;
    p.*c.field = c.value;
    EXPECT_NE(validation_message(p).find(c.expected), std::string::npos) << validation_message(p);
  }
}

TEST(PneumaticParams, TomlRoundTripIsExact) {
  PneumaticParams p;
  p.bore_mm = 25.0;
  p.piston_mass_kg = 0.1 + 0.2;  // not short in decimal: must still read back bit-identically
  p.overlap_neg_v = -1.722;
  p.viscous_friction_n_per_mps = 0.0;
  const std::string text = format_pneumatic_toml(p);
  auto back = parse_pneumatic_toml(text, "written.toml");
  ASSERT_TRUE(back.has_value()) << back.error().message << "\n" << text;
  EXPECT_EQ(*back, p);
  EXPECT_NE(*back, PneumaticParams{});
}

TEST(PneumaticParams, FileRoundTripThroughTheWriter) {
  const test::TempDir dir("pneumatic");
  const std::string path = (dir.path / "rig.toml").string();
  PneumaticParams p;
  p.static_friction_n = 55.5;
  ASSERT_TRUE(write_pneumatic_file(path, p).has_value());
  auto back = read_pneumatic_file(path);
  ASSERT_TRUE(back.has_value()) << back.error().message;
  EXPECT_EQ(*back, p);
  std::filesystem::remove_all(dir.path);
  EXPECT_NE(read_pneumatic_file(path).error().message.find(path), std::string::npos);
}

// The shipped config file holds exactly the defaults, so the two cannot drift apart.
TEST(PneumaticParams, ConfigFileHoldsTheDefaults) {
  auto p = read_pneumatic_file(EPA_SOURCE_DIR "/config/pneumatic-plant.toml");
  ASSERT_TRUE(p.has_value()) << p.error().message;
  EXPECT_EQ(*p, PneumaticParams{});
}

TEST(PneumaticParams, MissingKeysKeepTheirDefaults) {
  auto p = parse_pneumatic_toml("schema = \"epa-pneumatic/1\"\n[cylinder]\nbore_mm = 40\n", "rig.toml");
  ASSERT_TRUE(p.has_value()) << p.error().message;
  PneumaticParams expected;
  expected.bore_mm = 40.0;  // an integer is read as a number
  EXPECT_EQ(*p, expected);
}

TEST(PneumaticParams, UnknownKeysAreRefusedWithTheirNameAndLine) {
  EXPECT_EQ(parse_message("schema = \"epa-pneumatic/1\"\n[valve]\norifice_area_mm2 = 3.0\norifice_area = 3.0\n"),
            "rig.toml:4: unknown key 'orifice_area' in [valve] (expected one of: orifice_area_mm2, discharge_coefficient, "
            "spool_time_constant_s, overlap_pos_v, overlap_neg_v)");
  EXPECT_EQ(parse_message("schema = \"epa-pneumatic/1\"\n\n[sensor]\nbits = 12\n"),
            "rig.toml:3: unknown key 'sensor' (expected one of: schema, source, supply, cylinder, friction, valve)");
  EXPECT_EQ(parse_message("schema = \"epa-pneumatic/1\"\nbore_mm = 32.0\n"),
            "rig.toml:2: unknown key 'bore_mm' (expected one of: schema, source, supply, cylinder, friction, valve)");
}

TEST(PneumaticParams, BadValuesNameFileLineAndKey) {
  const std::string type = parse_message("schema = \"epa-pneumatic/1\"\n[friction]\nstatic_friction_n = \"forty\"\n");
  EXPECT_NE(type.find("rig.toml:3: [friction] static_friction_n must be a number"), std::string::npos) << type;
  const std::string range = parse_message("schema = \"epa-pneumatic/1\"\n[supply]\n\nsupply_pressure_bar = -1.0\n");
  EXPECT_NE(range.find("rig.toml:4:"), std::string::npos) << range;
  EXPECT_NE(range.find("[supply] supply_pressure_bar = -1"), std::string::npos) << range;
  const std::string syntax = parse_message("schema = \"epa-pneumatic/1\"\n[valve\n");
  EXPECT_NE(syntax.find("rig.toml:2:"), std::string::npos) << syntax;
  EXPECT_NE(parse_message("[valve]\n").find("schema is missing"), std::string::npos);
  EXPECT_NE(parse_message("schema = \"epa-model/1\"\n").find("not supported"), std::string::npos);
}

// `epa plant-server`'s `physics KEY VALUE` line: one key at a time, bare or with its table.
TEST(PneumaticParams, OneKeyIsSetBareOrWithItsTable) {
  PneumaticParams p;
  ASSERT_TRUE(set_pneumatic_key(p, "supply_pressure_bar", 4.5));
  EXPECT_EQ(p.supply_pressure_bar, 4.5);
  ASSERT_TRUE(set_pneumatic_key(p, "friction.static_friction_n", 80.0));
  EXPECT_EQ(p.static_friction_n, 80.0);
  PneumaticParams expected;
  expected.supply_pressure_bar = 4.5, expected.static_friction_n = 80.0;
  EXPECT_EQ(p, expected);  // nothing else moved
}

TEST(PneumaticParams, ABadKeyOrValueIsRefusedNamingItAndChangesNothing) {
  PneumaticParams p;
  const PneumaticParams before = p;
  auto s = set_pneumatic_key(p, "supply_presure_bar", 4.5);
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("unknown key 'supply_presure_bar'"), std::string::npos) << s.error().message;
  EXPECT_NE(s.error().message.find("supply_pressure_bar"), std::string::npos);  // the known keys are listed
  s = set_pneumatic_key(p, "valve.supply_pressure_bar", 4.5);                   // a key in another table
  EXPECT_FALSE(s);
  s = set_pneumatic_key(p, "coulomb_friction_n", 60.0);  // above the breakaway force of 40 N
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("coulomb_friction_n = 60"), std::string::npos) << s.error().message;
  s = set_pneumatic_key(p, "spool_time_constant_s", std::numeric_limits<double>::quiet_NaN());
  EXPECT_FALSE(s);
  EXPECT_EQ(p, before);
}

}  // namespace
}  // namespace epa::plant
