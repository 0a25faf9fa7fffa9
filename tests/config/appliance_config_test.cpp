#include "config/appliance_config.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <iostream>
#include <random>
#include <regex>

#include "core/secret_strength.hpp"
#include "modbus/unlock_guard.hpp"

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
  EXPECT_EQ(c->runtime.controller, defaults.controller);
  EXPECT_EQ(c->runtime.controller, control::ControllerKind::kPpTraj);
  EXPECT_EQ(c->runtime.start_mode, runtime::Mode::kStop);
  EXPECT_EQ(c->backend, HalBackend::kSim);
  EXPECT_EQ(c->modbus_io.port, 1502);
  EXPECT_DOUBLE_EQ(c->modbus_io.layout.sensor.volts_per_count, hal::default_remote_io_layout().sensor.volts_per_count);
  EXPECT_EQ(c->comedi.device, "/dev/comedi0");
  EXPECT_EQ(c->register_map_path, std::string(EPA_SOURCE_DIR) + "/registers/epa.csv");  // next to the config
  EXPECT_TRUE(c->modbus.plain_enabled);
  EXPECT_FALSE(c->modbus.secure.enabled);
  EXPECT_EQ(c->modbus.port, 502);
  EXPECT_EQ(c->modbus.alias_unit_ids, (std::vector<int>{0, 255}));  // 0 and 0xFF also mean this device
  EXPECT_FALSE(c->modbus.policy.unlock_key.has_value());  // no default key: tuning stays locked until one is set
  EXPECT_EQ(c->store_path, "epa.db");          // the appliance's data: relative to the working directory
  EXPECT_EQ(c->sim_plant, "hammerstein");
  EXPECT_EQ(c->physics_config, "");
  // [health] as shipped is the estimator's own default, the one its benchmark measured.
  const diag::HealthConfig health;
  EXPECT_TRUE(c->health.enabled);
  EXPECT_EQ(c->health.stroke_mm, 500.0);
  EXPECT_EQ(c->health.estimator.baseline_moves, health.baseline_moves);
  EXPECT_EQ(c->health.estimator.window_moves, health.window_moves);
  EXPECT_EQ(c->health.estimator.confirm_windows, health.confirm_windows);
  EXPECT_EQ(c->health.estimator.min_reduction, health.min_reduction);
  EXPECT_EQ(c->health.estimator.spread_margin, health.spread_margin);
  EXPECT_EQ(c->health.estimator.unexplained_gap_ratio, health.unexplained_gap_ratio);
}

TEST(ApplianceConfig, AHealthWindowLongerThanItsBaselineIsRefusedNamingBoth) {
  const auto e = error_of("[health]\nbaseline_moves = 8\nwindow_moves = 12\n");
  EXPECT_NE(e.find("[health] baseline_moves must be at least window_moves"), std::string::npos) << e;
  EXPECT_NE(error_of("[health]\nmin_reduction = 1.5\n").find("health.min_reduction"), std::string::npos);
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

TEST(ApplianceConfig, ModbusTlsTakesItsFilesAndARoleTableThatReplacesTheDefaults) {
  auto c = parse_appliance_config("[modbus]\nenabled = false\n[modbus_tls]\nenabled = true\nport = 8802\nca = \"ca.pem\"\n"
                                  "cert = \"device.pem\"\nkey = \"device.key\"\n[modbus_tls.roles]\nhmi = \"operate\"\nscada = \"read\"\n",
                                  "x.toml");
  ASSERT_TRUE(c.has_value()) << c.error().message;
  EXPECT_FALSE(c->modbus.plain_enabled);
  EXPECT_TRUE(serves_modbus(*c));
  EXPECT_EQ(c->modbus.secure.port, 8802);
  EXPECT_EQ(c->modbus.secure.files.key, "device.key");
  ASSERT_EQ(c->modbus.secure.roles.size(), 2u);
  EXPECT_EQ(c->modbus.secure.roles[0].role, "hmi");
  EXPECT_EQ(c->modbus.secure.roles[0].rights, points::Rights::kOperate);
  EXPECT_FALSE(any_address_may_command(*c)) << "the secure port's writers are known by their certificates";
  auto defaults = parse_appliance_config("", "empty.toml");
  ASSERT_TRUE(defaults.has_value());
  EXPECT_FALSE(defaults->modbus.secure.enabled);
  EXPECT_EQ(defaults->modbus.secure.port, 802);
  ASSERT_EQ(defaults->modbus.secure.roles.size(), 3u);
  EXPECT_EQ(defaults->modbus.secure.roles[2].role, "engineer");
  EXPECT_EQ(defaults->modbus.secure.roles[2].rights, points::Rights::kTune);
}

TEST(ApplianceConfig, ModbusTlsMistakesAreNamed) {
  const std::string files = "ca = \"ca.pem\"\ncert = \"d.pem\"\nkey = \"d.key\"\n";
  EXPECT_NE(error_of("[modbus_tls]\nenabled = true\n").find("[modbus_tls] enabled needs ca"), std::string::npos);
  EXPECT_NE(error_of("[modbus_tls]\n" + files + "[modbus_tls.roles]\nhmi = \"write\"\n").find("test.toml:6: modbus_tls.roles.hmi = \"write\": must be"),
            std::string::npos)
      << error_of("[modbus_tls]\n" + files + "[modbus_tls.roles]\nhmi = \"write\"\n");
  EXPECT_NE(error_of("[modbus_tls]\nenabled = true\n" + files + "roles = {}\n").find("roles is empty"), std::string::npos);
  EXPECT_NE(error_of("[modbus]\nport = 802\n[modbus_tls]\nenabled = true\n" + files).find("port 802 is [modbus] port too"), std::string::npos);
  EXPECT_NE(error_of("[modbus_tls]\nhandshake_timeout_s = 0\n").find("modbus_tls.handshake_timeout_s"), std::string::npos);
  EXPECT_NE(error_of("[modbus_tls]\ncertificate = \"x\"\n").find("unknown key 'certificate' in [modbus_tls]"), std::string::npos);
}

// [web] tls: HTTPS with [modbus_tls]'s files, which may be set with Modbus/TCP Security off.
TEST(ApplianceConfig, WebTlsTakesTheModbusTlsFilesAndAClientCertificateMode) {
  const std::string files = "[modbus_tls]\nca = \"ca.pem\"\ncert = \"d.pem\"\nkey = \"d.key\"\n";
  auto c = parse_appliance_config(files + "[web]\ntls = true\n", "x.toml");
  ASSERT_TRUE(c.has_value()) << c.error().message;
  EXPECT_TRUE(c->web.tls);
  EXPECT_FALSE(c->modbus.secure.enabled);
  EXPECT_EQ(c->web.client_certificates, web::ClientCertificates::kOptional);
  auto off = parse_appliance_config(files + "[web]\ntls = true\nclient_certificates = \"off\"\n", "x.toml");
  ASSERT_TRUE(off.has_value()) << off.error().message;
  EXPECT_EQ(off->web.client_certificates, web::ClientCertificates::kOff);
  auto defaults = parse_appliance_config("", "empty.toml");
  ASSERT_TRUE(defaults.has_value());
  EXPECT_FALSE(defaults->web.tls);

  EXPECT_NE(error_of("[web]\ntls = true\n").find("test.toml: [web] tls needs [modbus_tls] ca"), std::string::npos) << error_of("[web]\ntls = true\n");
  EXPECT_TRUE(parse_appliance_config("[web]\nenabled = false\ntls = true\n", "x.toml").has_value()) << "no web server, no files needed";
  EXPECT_NE(error_of("[web]\nclient_certificates = \"required\"\n").find("web.client_certificates"), std::string::npos);
  EXPECT_NE(error_of("[web]\ntls = \"yes\"\n").find("web.tls"), std::string::npos);
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

// A listen address is an IP address, exactly: a typo is refused naming the key and the value
// (999.1.1.1 once bound 255.255.255.255), and IPv6 is taken (the listener binds it).
TEST(ApplianceConfig, ListenAddressesAreIpv4OrIpv6AndATypoIsRefused) {
  for (const char* key : {"modbus", "web"}) {
    for (const char* bad : {"999.1.1.1", "1.2.3", "1.2.3.4.5", "01.2.3.4", " 127.0.0.1", "127.0.0.1 ", "localhost", "0x7f.0.0.1", "::g",
                            "fe80::1%eth0", ""}) {
      const auto e = error_of(std::string("[") + key + "]\naddress = \"" + bad + "\"\n");
      EXPECT_NE(e.find(std::string("test.toml:2: ") + key + ".address '" + bad + "' is not an IP address"), std::string::npos) << e;
    }
    for (const char* good : {"0.0.0.0", "127.0.0.1", "255.255.255.255", "::", "::1", "fe80::1", "2001:db8::5"}) {
      auto c = parse_appliance_config(std::string("[") + key + "]\naddress = \"" + good + "\"\n", "test.toml");
      ASSERT_TRUE(c.has_value()) << good << ": " << c.error().message;
      EXPECT_EQ(std::string(key) == "modbus" ? c->modbus.address : c->web.address, good);
    }
  }
  // The I/O module's host is a client address for libmodbus' IPv4-only TCP client.
  EXPECT_NE(error_of("[hal.modbus_io]\nhost = \"300.1.1.1\"\n").find("hal.modbus_io.host '300.1.1.1' is not an IPv4 address"),
            std::string::npos);
  EXPECT_NE(error_of("[hal.modbus_io]\nhost = \"::1\"\n").find("hal.modbus_io.host"), std::string::npos);
}

TEST(ApplianceConfig, WriteClientsAreIpAddressesInTheFormPeersAreComparedIn) {
  auto c = parse_appliance_config("[modbus]\nwrite_clients = [\"10.0.0.5\", \"0:0:0:0:0:0:0:1\", \"::ffff:10.0.0.6\"]\n", "t.toml");
  ASSERT_TRUE(c.has_value()) << c.error().message;
  EXPECT_EQ(c->modbus.policy.write_clients, (std::vector<std::string>{"10.0.0.5", "::1", "10.0.0.6"}));
  const auto e = error_of("[modbus]\nwrite_clients = [\"10.0.0.300\"]\n");
  EXPECT_NE(e.find("[modbus] write_clients: '10.0.0.300' is not an IP address"), std::string::npos) << e;
}

// A tiny value that passed "above zero" was as harmful as a wrong one: sensor_gain = 1e-300 blinded
// the sensor (the piston drove into the end stop), idle_timeout_s = 1e-300 dropped every client.
// Each such key has a physical lower bound, and the message says the range.
TEST(ApplianceConfig, ATinyValueWhereItHarmsIsRefusedSayingTheRange) {
  EXPECT_EQ(error_of("[modbus]\nidle_timeout_s = 1e-300\n"), "test.toml:2: modbus.idle_timeout_s = 1e-300: must be between 1 and 86400 s");
  EXPECT_EQ(error_of("[calibration]\nsensor_gain = 1e-300\n"),
            "test.toml:2: calibration.sensor_gain = 1e-300: must be between 0.1 and 10 (model volts per sensor volt)");
  EXPECT_EQ(error_of("[limits]\nheartbeat_timeout_s = 1e-300\n"),
            "test.toml:2: limits.heartbeat_timeout_s = 1e-300: must be 0 (off) or between 0.05 and 3600 s");
  const std::vector<std::pair<std::string, std::string>> harmful = {
      {"controller", "valve_limit_v"},        {"limits", "manual_valve_limit_v"},  {"limits", "following_error_mm"},
      {"limits", "following_error_time_s"},   {"limits", "sensor_frozen_time_s"},  {"limits", "sensor_frozen_drive_v"},
      {"recorder", "buffer_s"},               {"recorder", "move_window_s"},       {"motion", "in_position_window_mm"},
      {"motion", "standstill_time_s"},        {"motion", "halt_decel_mm_s2"},      {"motion", "jog_speed_mm_s"},
      {"motion", "jog_accel_mm_s2"},          {"motion", "jog_keepalive_s"},       {"excite", "amplitude_min_v"},
      {"excite", "guard_mm"},                 {"log", "status_interval_s"},        {"modbus", "frame_timeout_s"},
      {"modbus", "unlock_timeout_s"}};
  for (const auto& [table, key] : harmful) {
    const auto e = error_of("[" + table + "]\n" + key + " = 1e-300\n");
    EXPECT_NE(e.find(table + "." + key + " = 1e-300: must be "), std::string::npos) << e;
    EXPECT_NE(e.find("between"), std::string::npos) << e;
  }
  EXPECT_NE(error_of("[hal.modbus_io]\nsensor = { full_scale_v = 1e-300 }\n").find("full_scale_v = 1e-300: must be between 0.1"),
            std::string::npos);
  // 0 still switches off what has an "off".
  auto off = parse_appliance_config("[limits]\nheartbeat_timeout_s = 0\nfollowing_error_time_s = 0\n[log]\nstatus_interval_s = 0\n", "t.toml");
  ASSERT_TRUE(off.has_value()) << off.error().message;
}

TEST(ApplianceConfig, AWeakTokenIsRefusedSayingHowToMakeAGoodOne) {
  for (const char* weak : {"1", "aaaaaaaaaaaaaaaa", "password12345678", "                ", "P4ssw0rd-Qz81x7!", "Adm1n-9Zq!x7Lk2v",
                           "abcabcabcabcabca", "Xy7!Xy7!Xy7!Xy7!", "abcdefghijklmnopqrstuvwxyz", "xkqpwmzrtvbnhjlf", "My-Epa-9Zq!x7Lk2v",
                           "Zq81x-records-token", "Qz81xAAAAAAq7!kp"}) {
    const auto e = error_of(std::string("[web]\ntoken = \"") + weak + "\"\n");
    EXPECT_NE(e.find("test.toml:2: web.token "), std::string::npos) << weak << ": " << e;
    EXPECT_NE(e.find("head -c 18 /dev/urandom | base64"), std::string::npos) << weak << ": " << e;
    if (std::string(weak).size() >= 16) {
      EXPECT_EQ(e.find(weak), std::string::npos) << "the message repeats the secret: " << e;
    }
  }
  EXPECT_NE(error_of("[web]\ntoken = \"1\"\n").find("at least 16 characters"), std::string::npos);
  EXPECT_NE(error_of("[web]\ntoken = \"password12345678\"\n").find("common word 'password'"), std::string::npos);
  // The last: what the advice makes, with a short word in it by chance.
  for (const char* strong : {"q7Kx2vR9mZp4Lw8n", "Df4-cZmm1ss-Qz81x", "3f9c1a7e5b2d8064c9e1f7a3b5d20c86e4a19f73", "Gx0/3J5qkVbN8tR+Wm2eLd7Y",
                             "k2VqepaZ8x/Lr4TnW0c+Jm5u"}) {
    auto c = parse_appliance_config(std::string("[web]\ntoken = \"") + strong + "\"\n", "t.toml");
    ASSERT_TRUE(c.has_value()) << strong << ": " << c.error().message;
    EXPECT_EQ(c->web.token, strong);
  }
  EXPECT_TRUE(parse_appliance_config("[web]\ntoken = \"\"\n", "t.toml").has_value());  // no commands
}

TEST(ApplianceConfig, AnUnlockKeyOfHexWordsIsRefused) {
  for (const char* weak : {"deadbeefcafebabe", "c0ffee00f00d1234", "5e3ad00dfeedface"}) {
    const auto e = error_of(std::string("[modbus]\nunlock_key = \"") + weak + "\"\n");
    EXPECT_NE(e.find("modbus.unlock_key is mostly well-known hex words"), std::string::npos) << weak << ": " << e;
    EXPECT_NE(e.find("/dev/urandom"), std::string::npos) << e;
  }
  auto c = parse_appliance_config("[modbus]\nunlock_key = \"5e3a9c17d24b086f\"\n", "t.toml");
  ASSERT_TRUE(c.has_value()) << c.error().message;
}

// The rules refuse what is guessed first, not what a generator gives: random secrets of the shapes
// the messages advise pass (nearly) always. Counted over a fixed pseudo-random sample.
TEST(ApplianceConfig, RandomSecretsPassTheStrengthRules) {
  std::mt19937_64 random(43);
  const std::string base64 = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/", hex = "0123456789abcdef";
  auto draw = [&](const std::string& alphabet, std::size_t n) {
    std::string s;
    for (std::size_t i = 0; i < n; ++i) s += alphabet[random() % alphabet.size()];
    return s;
  };
  int refused_base64 = 0, refused_hex = 0, refused_keys = 0;
  constexpr int kDraws = 5000;
  for (int i = 0; i < kDraws; ++i) {
    refused_base64 += !core::token_weakness(draw(base64, 24)).empty();  // head -c 18 /dev/urandom | base64
    refused_hex += !core::token_weakness(draw(hex, 40)).empty();        // secrets.token_hex(20)
    refused_keys += !modbus::parse_unlock_key(draw(hex, 16)).has_value();  // od -An -tx8 -N8 /dev/urandom
  }
  EXPECT_LE(refused_base64, kDraws / 200) << "of " << kDraws;
  EXPECT_LE(refused_hex, kDraws / 200) << "of " << kDraws;
  EXPECT_LE(refused_keys, kDraws / 100) << "of " << kDraws;
  std::cout << "refused of " << kDraws << " random: base64 tokens " << refused_base64 << ", hex tokens " << refused_hex << ", keys "
            << refused_keys << "\n";
}

TEST(ApplianceConfig, AnyAddressMayCommandUnlessWriteClientsOrReadOnlyRestrictIt) {
  auto shipped = read_appliance_config(kShipped);
  ASSERT_TRUE(shipped.has_value()) << shipped.error().message;
  EXPECT_TRUE(any_address_may_command(*shipped));
  EXPECT_NE(any_address_notice(*shipped).find("set [modbus] write_clients"), std::string::npos);
  auto listed = parse_appliance_config("[modbus]\nwrite_clients = [\"10.0.0.5\"]\n", "t.toml");
  ASSERT_TRUE(listed.has_value());
  EXPECT_FALSE(any_address_may_command(*listed));
  EXPECT_EQ(any_address_notice(*listed), "");
  EXPECT_FALSE(any_address_may_command(*parse_appliance_config("[modbus]\nread_only = true\n", "t.toml")));
  EXPECT_FALSE(any_address_may_command(*parse_appliance_config("[modbus]\nenabled = false\n", "t.toml")));
}

}  // namespace
}  // namespace epa::config
