#include "config/appliance_config.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <regex>

namespace epa::config {
namespace {

const std::string kShipped = std::string(EPA_SOURCE_DIR) + "/config/epa.toml";

std::string error_of(const std::string& text) {
  auto c = parse_appliance_config(text, "test.toml");
  return c.has_value() ? "(accepted)" : c.error().message;
}

TEST(ApplianceConfig, ShippedFileParsesToTheDocumentedDefaults) {
  auto c = read_appliance_config(kShipped);
  ASSERT_TRUE(c.has_value()) << c.error().message;
  const runtime::RuntimeConfig defaults;
  EXPECT_EQ(c->runtime.period_s, defaults.period_s);
  EXPECT_EQ(c->runtime.sensor_min_v, defaults.sensor_min_v);
  EXPECT_EQ(c->runtime.soft_max_mm, defaults.soft_max_mm);
  EXPECT_EQ(c->runtime.following_error_time_s, defaults.following_error_time_s);
  EXPECT_EQ(c->runtime.move_window_s, defaults.move_window_s);
  EXPECT_EQ(c->runtime.controller, control::ControllerKind::kPpFfidz);
  EXPECT_EQ(c->runtime.start_mode, runtime::Mode::kStop);
  EXPECT_EQ(c->backend, HalBackend::kSim);
  EXPECT_EQ(c->modbus_io.port, 1502);
  EXPECT_DOUBLE_EQ(c->modbus_io.layout.sensor.volts_per_count, hal::default_remote_io_layout().sensor.volts_per_count);
  EXPECT_EQ(c->comedi.device, "/dev/comedi0");
  EXPECT_EQ(c->register_map_path, std::string(EPA_SOURCE_DIR) + "/registers/epa.csv");  // next to the config
  EXPECT_TRUE(c->modbus_enabled);
  EXPECT_EQ(c->modbus.port, 502);
  EXPECT_EQ(c->modbus.alias_unit_ids, (std::vector<int>{0, 255}));  // 0 and 0xFF also mean this device
  EXPECT_FALSE(c->modbus.policy.unlock_key.has_value());  // no default key: tuning stays locked until one is set
  EXPECT_EQ(c->store_path, "epa.db");          // the appliance's data: relative to the working directory
  EXPECT_EQ(c->sim_plant, "hammerstein");
  EXPECT_EQ(c->physics_config, "");
}

TEST(ApplianceConfig, ThePhysicsPlantIsChosenWithItsParameterFileNextToTheConfiguration) {
  auto c = parse_appliance_config("[hal.sim]\nplant = \"physics\"\nsensor_bits = 12\ninitial_pressure_bar = 2.5\n", "x.toml");
  ASSERT_TRUE(c.has_value()) << c.error().message;
  EXPECT_EQ(c->sim_plant, "physics");
  EXPECT_EQ(c->sim_sensor_bits, 12);
  EXPECT_EQ(c->sim_initial_pressure_bar, 2.5);
  EXPECT_NE(error_of("[hal.sim]\nplant = \"cfd\"\n").find("hal.sim.plant"), std::string::npos);
  EXPECT_NE(error_of("[hal.sim]\nsensor_bits = 40\n").find("hal.sim.sensor_bits"), std::string::npos);
  EXPECT_NE(error_of("[store]\nfile = \"x.db\"\n").find("unknown key 'file' in [store]"), std::string::npos);
}

TEST(ApplianceConfig, EmptyFileGivesTheDefaults) {
  auto c = parse_appliance_config("", "empty.toml");
  ASSERT_TRUE(c.has_value());
  EXPECT_EQ(c->runtime.period_s, 0.005);
}

TEST(ApplianceConfig, UnknownKeyIsRefusedWithFileLineAndKey) {
  const auto e = error_of("[loop]\nperiod_s = 0.005\nperoid_s = 0.001\n");
  // Every key [loop] takes is listed, in the wording of every TOML reader (core/toml_keys.hpp).
  EXPECT_EQ(e, "test.toml:3: unknown key 'peroid_s' in [loop] (expected one of: cpu_dma_latency_us, lock_memory, "
               "max_consecutive_overruns, period_s, realtime_priority)");
}

TEST(ApplianceConfig, WrongTypeAndOutOfRangeNameTheKey) {
  EXPECT_NE(error_of("[loop]\nperiod_s = \"fast\"\n").find("loop.period_s must be a number"), std::string::npos);
  EXPECT_NE(error_of("[hal.modbus_io]\nport = 70000\n").find("hal.modbus_io.port must be within 1..65535"), std::string::npos);
  EXPECT_NE(error_of("[controller]\nkind = \"pid\"\n").find("controller.kind"), std::string::npos);
  EXPECT_NE(error_of("[hal]\nbackend = \"ni\"\n").find("not one of sim, modbus-io, comedi"), std::string::npos);
  EXPECT_NE(error_of("[startup]\nmode = \"fault\"\n").find("startup.mode"), std::string::npos);
}

// Found by fuzz_config: a float given for an integer key went through toml++'s unchecked
// float-to-int64 conversion (undefined behaviour for 5e22) before the type was checked.
TEST(ApplianceConfig, AFloatForAWholeNumberIsRefusedWhateverItsSize) {
  EXPECT_NE(error_of("[modbus]\nport = 5e22\n").find("modbus.port must be a whole number"), std::string::npos);
  EXPECT_NE(error_of("[modbus]\nport = 502.0\n").find("modbus.port must be a whole number"), std::string::npos);
}

TEST(ApplianceConfig, AliasUnitIdsAreAListOfUnitIds) {
  auto none = parse_appliance_config("[modbus]\nunit_id = 17\nalias_unit_ids = []\n", "test.toml");
  ASSERT_TRUE(none.has_value()) << none.error().message;
  EXPECT_EQ(none->modbus.unit_id, 17);
  EXPECT_TRUE(none->modbus.alias_unit_ids.empty());  // unit 17 only
  auto ff = parse_appliance_config("[modbus]\nalias_unit_ids = [255]\n", "test.toml");
  ASSERT_TRUE(ff.has_value()) << ff.error().message;
  EXPECT_EQ(ff->modbus.alias_unit_ids, std::vector<int>{255});
  EXPECT_NE(error_of("[modbus]\nalias_unit_ids = [0, 256]\n").find("modbus.alias_unit_ids must contain whole numbers within 0..255"),
            std::string::npos);
  EXPECT_NE(error_of("[modbus]\nalias_unit_ids = 0\n").find("modbus.alias_unit_ids must be an array"), std::string::npos);
  EXPECT_NE(error_of("[modbus]\nalias_unit_ids = [\"0\"]\n").find("test.toml:2: modbus.alias_unit_ids"), std::string::npos);
}

TEST(ApplianceConfig, SyntaxErrorNamesTheLine) {
  EXPECT_NE(error_of("[loop]\nperiod_s = = 1\n").find("test.toml:2:"), std::string::npos);
}

TEST(ApplianceConfig, CrossFieldRulesAreChecked) {
  EXPECT_NE(error_of("[limits]\nsoft_min_mm = 10.0\n").find("inside the soft limits"), std::string::npos);
  const auto overlap = error_of(
      "[hal]\nbackend = \"modbus-io\"\n[hal.modbus_io]\n"
      "sensor = { table = \"holding\", address = 0 }\nvalve = { table = \"holding\", address = 0 }\n");
  EXPECT_NE(overlap.find("[hal.modbus_io]"), std::string::npos) << overlap;
  EXPECT_NE(error_of("[hal.modbus_io]\nsensor = { tabel = \"input\" }\n").find("unknown key 'tabel' in [hal.modbus_io.sensor]"), std::string::npos);
}

TEST(ApplianceConfig, TheExcitationSettingsAreReadAndTheirRulesNameTheKey) {
  auto shipped = read_appliance_config(kShipped);
  ASSERT_TRUE(shipped.has_value()) << shipped.error().message;
  const runtime::ExcitationSettings defaults;
  EXPECT_EQ(shipped->runtime.excitation.seed, defaults.seed);
  EXPECT_EQ(shipped->runtime.excitation.amplitude_min_v, defaults.amplitude_min_v);
  EXPECT_EQ(shipped->runtime.excitation.amplitude_max_v, defaults.amplitude_max_v);
  EXPECT_EQ(shipped->runtime.excitation.duration_s, defaults.duration_s);
  EXPECT_EQ(shipped->runtime.excitation.guard_mm, defaults.guard_mm);

  auto c = parse_appliance_config("[excite]\nseed = 4000000000\namplitude_min_v = 0.5\namplitude_max_v = 2.5\n"
                                  "duration_s = 120.0\nguard_mm = 80.0\n", "x.toml");
  ASSERT_TRUE(c.has_value()) << c.error().message;
  EXPECT_EQ(c->runtime.excitation.seed, 4000000000u);
  EXPECT_EQ(c->runtime.excitation.amplitude_max_v, 2.5);
  EXPECT_EQ(c->runtime.excitation.guard_mm, 80.0);
  // The recorder keeps the whole experiment, even beyond [recorder] buffer_s (60 s).
  EXPECT_GE(runtime::record_capacity_samples(c->runtime), static_cast<std::size_t>(121.0 / 0.005));

  const auto range = error_of("[excite]\namplitude_max_v = 12.0\n");
  EXPECT_NE(range.find("test.toml:2:"), std::string::npos) << range;
  EXPECT_NE(range.find("excite.amplitude_max_v"), std::string::npos) << range;
  EXPECT_NE(error_of("[excite]\nseed = -1\n").find("excite.seed"), std::string::npos);
  EXPECT_NE(error_of("[excite]\nduration = 10.0\n").find("unknown key 'duration' in [excite]"), std::string::npos);  // misspelt: refused
  const auto crossed = error_of("[excite]\namplitude_min_v = 2.0\namplitude_max_v = 1.0\n");
  EXPECT_NE(crossed.find("[excite]"), std::string::npos) << crossed;
  EXPECT_NE(crossed.find("amplitude_min_v"), std::string::npos) << crossed;
  const auto guard = error_of("[excite]\nguard_mm = 300.0\n");  // the soft limits span 504 mm
  EXPECT_NE(guard.find("guard_mm"), std::string::npos) << guard;
  EXPECT_NE(error_of("[startup]\nmode = \"excite\"\n").find("startup.mode"), std::string::npos);  // by command only
}

TEST(ApplianceConfig, ScalingIsGivenAsFullScaleVolts) {
  auto c = parse_appliance_config("[hal.modbus_io]\nsensor = { full_scale_v = 5.0 }\n", "t.toml");
  ASSERT_TRUE(c.has_value()) << c.error().message;
  EXPECT_DOUBLE_EQ(c->modbus_io.layout.sensor.volts_per_count, 5.0 / 32767);
}

// Every numeric key of the shipped configuration, one at a time, set to values a typo or an
// attacker could write: 1e300 is refused for every key (each is bounded), and whatever is refused
// names the file, the key's line and the key. A float never reaches an integer unchecked.
TEST(ApplianceConfig, EveryNumericKeyIsBoundedAndARefusalNamesFileLineAndKey) {
  std::ifstream in(std::string(EPA_SOURCE_DIR) + "/config/epa.toml");
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  const std::regex number_key(R"((\b[a-z_]+) = (-?[0-9][0-9.e+-]*))");
  int keys = 0;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string code = lines[i].substr(0, lines[i].find('#'));
    for (std::sregex_iterator it(code.begin(), code.end(), number_key), end; it != end; ++it) {
      const std::string key = (*it)[1].str();
      ++keys;
      for (const char* value : {"1e300", "-1e300", "nan", "inf", "-1", "0", "0.5"}) {
        std::vector<std::string> edited = lines;
        edited[i] = code.substr(0, static_cast<std::size_t>(it->position(2))) + value +
                    code.substr(static_cast<std::size_t>(it->position(2) + it->length(2)));
        std::string text;
        for (const auto& l : edited) text += l + "\n";
        const auto c = parse_appliance_config(text, "epa.toml");
        const bool must_refuse = std::string(value).find("e300") != std::string::npos || std::string(value).find("n") != std::string::npos;
        if (must_refuse) {
          EXPECT_FALSE(c.has_value()) << key << " = " << value << " was accepted";
        }
        if (!c.has_value()) {
          const std::string& m = c.error().message;
          const bool names_line = m.find("epa.toml:" + std::to_string(i + 1) + ":") != std::string::npos;
          const bool cross_field = m.find("epa.toml: ") != std::string::npos;  // a rule between keys, named in words
          EXPECT_TRUE(names_line || cross_field) << key << " = " << value << ": " << m;
          if (names_line) {
            EXPECT_NE(m.find(key), std::string::npos) << key << " = " << value << ": " << m;
          }
        }
      }
    }
  }
  EXPECT_GE(keys, 40);
}

}  // namespace
}  // namespace epa::config
