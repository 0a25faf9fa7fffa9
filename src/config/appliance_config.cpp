#include "config/appliance_config.hpp"

#include "core/audit.hpp"
#include "core/format.hpp"
#include "core/ip_address.hpp"
#include "core/printable_name.hpp"
#include "core/secret_strength.hpp"
#include "core/toml_at_line.hpp"
#include "core/toml_document.hpp"
#include "core/toml_keys.hpp"
#include "core/text_file.hpp"
#include "modbus/unlock_guard.hpp"

#include "plant/effects.hpp"

#include <cmath>
#include <filesystem>
#include <functional>
#include <set>
#include <toml++/toml.h>

namespace epa::config {

namespace {

// The values a numeric key may take: [lo, hi] in `unit`, and 0 as well when `zero_is_off`. The lower
// bounds are physical, not just "above zero": a tiny value that passes is as harmful as a wrong one
// (sensor_gain = 1e-300 blinds the sensor, idle_timeout_s = 1e-300 drops every client).
struct Range {
  double lo, hi;
  const char* unit = "";
  bool zero_is_off = false;
  bool contains(double v) const { return (zero_is_off && v == 0.0) || (v >= lo && v <= hi); }
  std::string text() const {
    return std::string(zero_is_off ? "0 (off) or " : "") + "between " + core::format_number(lo) + " and " + core::format_number(hi) +
           (*unit ? std::string(" ") + unit : std::string());
  }
};
Range closed(double lo, double hi, const char* unit) { return {lo, hi, unit, false}; }
Range zero_or(double lo, double hi, const char* unit) { return {lo, hi, unit, true}; }

constexpr double kDay_s = 86400.0;

// Reads one TOML table: typed getters that remember which keys were used, and a final check
// that refuses keys nobody asked for. The first error wins; later calls are no-ops.
class TableReader {
 public:
  TableReader(const toml::table* table, std::string name, const std::string& file, std::optional<core::Error>& error)
      : table_(table), name_(std::move(name)), file_(file), error_(error) {}

  // Every number is bounded: a duration, size or limit far outside what an appliance can use is
  // a typo (1e300 s overflows a nanosecond clock, 1e12 s of buffer cannot be allocated).
  void number(const char* key, double& out, Range range) {
    const toml::node* n = find(key);
    if (!n) return;
    const auto v = n->value<double>();
    if (!v || !std::isfinite(*v)) return fail(*n, key, "must be a number " + range.text());
    if (!range.contains(*v)) return fail(*n, key, "= " + core::format_number(*v) + ": must be " + range.text());
    out = *v;
  }
  template <typename Int>
  void integer(const char* key, Int& out, std::int64_t lo, std::int64_t hi) {
    const toml::node* n = find(key);
    if (!n) return;
    // is_integer() first: toml++ converts a float such as 5e22 to int64 without a range check (UB).
    const auto v = n->is_integer() ? n->value<std::int64_t>() : std::nullopt;
    if (!v) return fail(*n, key, "must be a whole number");
    if (*v < lo || *v > hi) return fail(*n, key, "must be within " + std::to_string(lo) + ".." + std::to_string(hi));
    out = static_cast<Int>(*v);
  }
  void boolean(const char* key, bool& out) {
    const toml::node* n = find(key);
    if (!n) return;
    if (!n->is_boolean()) return fail(*n, key, "must be true or false");
    out = *n->value<bool>();
  }
  void text(const char* key, std::string& out) {
    const toml::node* n = find(key);
    if (!n) return;
    if (!n->is_string()) return fail(*n, key, "must be a string");
    out = *n->value<std::string>();
  }
  // A string that must parse into T; the parser's message says what was expected.
  template <typename T>
  void choice(const char* key, T& out, std::function<core::Result<T>(std::string_view)> parse) {
    const toml::node* n = find(key);
    if (!n) return;
    if (!n->is_string()) return fail(*n, key, "must be a string");
    auto r = parse(*n->value<std::string>());
    if (!r) return fail(*n, key, r.error().message);
    out = *r;
  }
  void text_list(const char* key, std::vector<std::string>& out) {
    const toml::node* n = find(key);
    if (!n) return;
    const auto* arr = n->as_array();
    if (!arr) return fail(*n, key, "must be an array of strings");
    out.clear();
    for (const auto& item : *arr) {
      if (!item.is_string()) return fail(item, key, "must contain strings only");
      out.push_back(*item.value<std::string>());
    }
  }
  void integer_list(const char* key, std::vector<int>& out, int lo, int hi) {
    const toml::node* n = find(key);
    if (!n) return;
    const auto* arr = n->as_array();
    if (!arr) return fail(*n, key, "must be an array of whole numbers within " + std::to_string(lo) + ".." + std::to_string(hi));
    out.clear();
    for (const auto& item : *arr) {
      const auto v = item.is_integer() ? item.value<std::int64_t>() : std::nullopt;
      if (!v || *v < lo || *v > hi)
        return fail(item, key, "must contain whole numbers within " + std::to_string(lo) + ".." + std::to_string(hi) + " only");
      out.push_back(static_cast<int>(*v));
    }
  }
  // A table of free names (its keys) to strings ([modbus_tls.roles]): each pair handed to `take`,
  // whose error is reported at the pair's line. Absent: `out_present` stays false.
  void name_table(const char* key, bool& out_present, const std::function<core::Status(const std::string&, const std::string&)>& take) {
    const toml::node* n = find(key);
    if (!n) return;
    const auto* table = n->as_table();
    if (!table) return fail(*n, key, "must be a table of names to strings");
    out_present = true;
    for (const auto& [name, value] : *table) {
      const std::string item = std::string(key) + "." + std::string(name.str());
      if (!value.is_string()) return fail(value, item.c_str(), "must be a string");
      if (auto s = take(std::string(name.str()), *value.value<std::string>()); !s) return fail(value, item.c_str(), s.error().message);
    }
  }
  const toml::table* subtable(const char* key) {
    used_.insert(key);
    return table_ ? (*table_)[key].as_table() : nullptr;
  }
  // The reader of the table `key` inside this one ([hal] -> [hal.sim]); its errors go where ours do.
  TableReader section(const char* key) { return TableReader(subtable(key), key_path(key), file_, error_); }
  // Every key the reader asked for is a known one; the message lists them (core/toml_keys.hpp).
  void refuse_unknown_keys() {
    if (!table_ || error_) return;
    for (const auto& [k, node] : *table_) {
      if (used_.count(std::string(k.str()))) continue;
      const std::vector<std::string_view> expected(used_.begin(), used_.end());
      error_ = core::unknown_key(file_, node.source(), k.str(), name_, expected);
      return;
    }
  }
  std::string key_path(const char* key) const { return name_.empty() ? key : name_ + "." + key; }

 private:
  const toml::node* find(const char* key) {
    used_.insert(key);
    if (error_ || !table_) return nullptr;
    return table_->get(key);
  }
  void fail(const toml::node& n, const char* key, const std::string& why) {
    if (error_) return;
    error_ = core::parse_error(core::at_line(file_, n.source()) + key_path(key) + " " + why);
  }

  const toml::table* table_;
  std::string name_;
  const std::string& file_;
  std::optional<core::Error>& error_;
  std::set<std::string> used_;
};


// [modbus] and [web] address: what the listener binds, so exactly an IP address (the log then says
// what was bound, and a typo such as 999.1.1.1 cannot turn into another address).
core::Result<std::string> listen_address(std::string_view v) {
  if (auto a = core::parse_ip_address(v, 0); !a) return a.error();
  return std::string(v);
}

// [hal.modbus_io] host: libmodbus' TCP client takes IPv4 only.
core::Result<std::string> module_host(std::string_view v) {
  if (!core::is_ipv4_address(v))
    return core::invalid_argument("'" + std::string(v) + "' is not an IPv4 address such as 192.168.0.10 (four numbers 0-255, no host names)");
  return std::string(v);
}

// [web] token: "" (commands off) or a secret that is not guessed (core/secret_strength.hpp).
core::Result<std::string> web_token(std::string_view v) {
  if (v.empty()) return std::string();
  if (const std::string why = core::token_weakness(v); !why.empty())
    return core::invalid_argument(why + " (or \"\" for no commands): a weak token is guessed; " + core::kTokenAdvice);
  return std::string(v);
}

core::Result<HalBackend> parse_backend(std::string_view s) {
  if (s == "sim") return HalBackend::kSim;
  if (s == "modbus-io") return HalBackend::kModbusIo;
  if (s == "comedi") return HalBackend::kComedi;
  return core::invalid_argument("'" + std::string(s) + "' is not one of sim, modbus-io, comedi");
}

core::Result<hal::RegisterTable> parse_table(std::string_view s) {
  if (s == "input") return hal::RegisterTable::kInput;
  if (s == "holding") return hal::RegisterTable::kHolding;
  return core::invalid_argument("'" + std::string(s) + "' is not one of input, holding");
}

core::Result<hal::AnalogEncoding> parse_encoding(std::string_view s) {
  if (s == "int16") return hal::AnalogEncoding::kInt16;
  if (s == "float32") return hal::AnalogEncoding::kFloat32;
  return core::invalid_argument("'" + std::string(s) + "' is not one of int16, float32");
}

core::Result<hal::AnalogReference> parse_aref(std::string_view s) {
  if (s == "ground") return hal::AnalogReference::kGround;
  if (s == "common") return hal::AnalogReference::kCommon;
  if (s == "diff") return hal::AnalogReference::kDiff;
  if (s == "other") return hal::AnalogReference::kOther;
  return core::invalid_argument("'" + std::string(s) + "' is not one of ground, common, diff, other");
}

void read_analog_point(TableReader& parent, const char* key, hal::AnalogPoint& p) {
  TableReader t = parent.section(key);
  t.choice<hal::RegisterTable>("table", p.table, parse_table);
  t.integer("address", p.address, 0, hal::kMaxRegisterAddress);
  t.choice<hal::AnalogEncoding>("encoding", p.encoding, parse_encoding);
  t.choice<core::WordOrder>("word_order", p.word_order, core::parse_word_order);
  double full_scale_v = p.volts_per_count * hal::kInt16FullScaleCounts;
  t.number("full_scale_v", full_scale_v, closed(0.1, 100, "V"));
  p.volts_per_count = full_scale_v / hal::kInt16FullScaleCounts;
  t.number("offset_v", p.offset_v, closed(-100, 100, "V"));
  t.refuse_unknown_keys();
}

void read_comedi_channel(TableReader& parent, const char* key, hal::ComediChannel& c) {
  TableReader t = parent.section(key);
  t.integer("subdevice", c.subdevice, -1, 255);
  t.integer("channel", c.channel, 0, 4095);
  t.number("range_min_v", c.range_min_v, closed(-100, 100, "V"));
  t.number("range_max_v", c.range_max_v, closed(-100, 100, "V"));
  t.choice<hal::AnalogReference>("aref", c.aref, parse_aref);
  t.refuse_unknown_keys();
}

// [startup] mode: the loop comes up stopped or running; manual and excite are entered by command.
core::Result<runtime::Mode> start_mode(std::string_view v) {
  auto m = runtime::parse_mode(v);
  if (m && (*m == runtime::Mode::kStop || *m == runtime::Mode::kRun)) return m;
  return core::invalid_argument("'" + std::string(v) + "' is not a start mode: stop or run (manual and excite are entered by command)");
}

// [modbus] unlock_key: "" never unlocks.
core::Result<std::optional<std::uint64_t>> unlock_key(std::string_view v) {
  if (v.empty()) return std::optional<std::uint64_t>{};
  auto key = modbus::parse_unlock_key(v);
  if (!key) return key.error();
  return std::optional<std::uint64_t>{*key};
}

core::Result<std::string> sim_plant(std::string_view v) {
  if (v == "hammerstein" || v == "physics") return std::string(v);
  return core::invalid_argument("'" + std::string(v) + "' is not hammerstein or physics");
}

// One function per section of the file: its keys, their bounds, and no key it does not know.

void read_loop(TableReader& top, ApplianceConfig& c) {
  TableReader loop = top.section("loop");
  loop.number("period_s", c.runtime.period_s, closed(0.0001, 1.0, "s"));
  loop.integer("realtime_priority", c.realtime.fifo_priority, 0, 99);
  loop.boolean("lock_memory", c.realtime.lock_memory);
  loop.integer("cpu_dma_latency_us", c.realtime.cpu_dma_latency_us, -1, 100000);
  loop.integer("max_consecutive_overruns", c.runtime.max_consecutive_overruns, 1, 1000000);
  loop.refuse_unknown_keys();
}

void read_controller(TableReader& top, ApplianceConfig& c) {
  TableReader ctl = top.section("controller");
  ctl.choice<control::ControllerKind>("kind", c.runtime.controller, control::parse_controller_kind);
  ctl.text("model", c.model_path);
  ctl.text("design", c.design_path);
  ctl.number("lc_mm", c.lc_mm, closed(0, 100, "mm"));
  ctl.number("valve_limit_v", c.valve_limit_v, closed(0.1, 10, "V"));
  ctl.refuse_unknown_keys();
}

void read_limits(TableReader& top, ApplianceConfig& c) {
  auto& r = c.runtime;
  TableReader lim = top.section("limits");
  lim.number("sensor_min_v", r.sensor_min_v, closed(-100, 100, "V"));
  lim.number("sensor_max_v", r.sensor_max_v, closed(-100, 100, "V"));
  lim.number("soft_min_mm", r.soft_min_mm, closed(-10000, 10000, "mm"));
  lim.number("soft_max_mm", r.soft_max_mm, closed(-10000, 10000, "mm"));
  lim.number("setpoint_min_mm", r.setpoint_min_mm, closed(-10000, 10000, "mm"));
  lim.number("setpoint_max_mm", r.setpoint_max_mm, closed(-10000, 10000, "mm"));
  lim.number("manual_valve_limit_v", r.manual_valve_limit_v, closed(0.1, 10, "V"));
  lim.number("safe_valve_v", r.safe_valve_v, closed(-10, 10, "V"));
  lim.number("following_error_mm", r.following_error_mm, closed(0.5, 10000, "mm"));
  lim.number("following_error_time_s", r.following_error_time_s, zero_or(0.01, 3600, "s"));
  lim.integer("max_consecutive_io_errors", r.max_consecutive_io_errors, 1, 1000000);
  lim.number("heartbeat_timeout_s", r.heartbeat_timeout_s, zero_or(0.05, 3600, "s"));
  lim.number("sensor_frozen_time_s", r.sensor_frozen_time_s, zero_or(0.05, 3600, "s"));
  lim.number("sensor_frozen_drive_v", r.sensor_frozen_drive_v, closed(0.1, 10, "V"));
  lim.refuse_unknown_keys();
}

void read_calibration(TableReader& top, ApplianceConfig& c) {
  TableReader cal = top.section("calibration");
  cal.number("sensor_offset_v", c.runtime.sensor_offset_v, closed(-100, 100, "V"));
  cal.number("sensor_gain", c.runtime.sensor_gain, closed(0.1, 10, "(model volts per sensor volt)"));
  cal.refuse_unknown_keys();
}

void read_startup(TableReader& top, ApplianceConfig& c) {
  TableReader start = top.section("startup");
  start.choice<runtime::Mode>("mode", c.runtime.start_mode, start_mode);
  start.number("setpoint_mm", c.runtime.start_setpoint_mm, closed(-10000, 10000, "mm"));
  start.refuse_unknown_keys();
}

void read_recorder(TableReader& top, ApplianceConfig& c) {
  TableReader rec = top.section("recorder");
  rec.text("directory", c.record_directory);
  rec.boolean("per_move", c.record_per_move);
  rec.number("buffer_s", c.runtime.record_buffer_s, closed(1, 600, "s"));
  rec.number("move_window_s", c.runtime.move_window_s, closed(0.1, 600, "s"));
  rec.number("min_interval_s", c.runtime.record_min_interval_s, closed(0.1, 3600, "s"));
  rec.number("quota_mb", c.record_quota_mb, closed(0.01, 1e7, "MiB"));  // tiny: only the newest file kept
  rec.number("move_files_per_minute", c.record_move_files_per_minute, closed(1, 12000, "files a minute"));
  rec.refuse_unknown_keys();
}

void read_motion(TableReader& top, ApplianceConfig& c) {
  auto& r = c.runtime;
  TableReader mo = top.section("motion");
  mo.number("in_position_window_mm", r.in_position_window_mm, closed(0.01, 100, "mm"));
  mo.number("in_position_time_s", r.in_position_time_s, closed(0, 60, "s"));
  mo.number("standstill_time_s", r.standstill_time_s, closed(0.05, 60, "s"));
  mo.number("halt_decel_mm_s2", r.halt_decel_mm_s2, closed(100, 1e6, "mm/s^2"));
  mo.number("jog_speed_mm_s", r.jog_speed_mm_s, closed(0.1, 10000, "mm/s"));
  mo.number("jog_accel_mm_s2", r.jog_accel_mm_s2, closed(100, 1e6, "mm/s^2"));
  mo.number("jog_keepalive_s", r.jog_keepalive_s, zero_or(0.05, 3600, "s"));
  mo.boolean("enable_holds_position", r.enable_holds_position);
  mo.refuse_unknown_keys();
}

void read_excite(TableReader& top, ApplianceConfig& c) {
  auto& x = c.runtime.excitation;
  TableReader ex = top.section("excite");
  ex.integer("seed", x.seed, 0, 4294967295);
  ex.number("amplitude_min_v", x.amplitude_min_v, closed(0.05, 10, "V"));
  ex.number("amplitude_max_v", x.amplitude_max_v, closed(0.05, 10, "V"));
  ex.number("duration_s", x.duration_s, closed(1, 600, "s"));
  ex.number("guard_mm", x.guard_mm, closed(1, 10000, "mm"));
  ex.boolean("sweep", x.sweep);
  ex.refuse_unknown_keys();
}

void read_health(TableReader& top, ApplianceConfig& c) {
  auto& h = c.health;
  auto& e = h.estimator;
  TableReader he = top.section("health");
  he.boolean("enabled", h.enabled);
  he.number("stroke_mm", h.stroke_mm, closed(1, 100000, "mm"));
  he.integer("baseline_moves", e.baseline_moves, 2, 100);
  he.integer("window_moves", e.window_moves, 2, 100);
  he.integer("confirm_windows", e.confirm_windows, 1, 20);
  he.number("min_reduction", e.min_reduction, closed(0.01, 0.99, ""));
  he.number("spread_margin", e.spread_margin, closed(1, 10, ""));
  he.number("unexplained_gap_ratio", e.unexplained_gap_ratio, closed(1.01, 100, ""));
  he.refuse_unknown_keys();
}

void read_store(TableReader& top, ApplianceConfig& c) {
  TableReader st = top.section("store");
  st.text("path", c.store_path);
  st.number("min_free_mb", c.store_min_free_mb, closed(1, 1e7, "MiB"));
  st.integer("audit_max_rows", c.audit_max_rows, core::kAuditMinRows, std::int64_t{1'000'000'000});
  st.refuse_unknown_keys();
}

void read_log(TableReader& top, ApplianceConfig& c) {
  TableReader log = top.section("log");
  log.number("status_interval_s", c.status_interval_s, zero_or(1, kDay_s, "s"));
  log.refuse_unknown_keys();
}

void read_modbus(TableReader& top, ApplianceConfig& c) {
  auto& m = c.modbus;
  TableReader mbs = top.section("modbus");
  mbs.boolean("enabled", m.plain_enabled);
  mbs.choice<std::string>("address", m.address, listen_address);
  mbs.integer("port", m.port, 0, 65535);
  mbs.integer("unit_id", m.unit_id, 0, 247);
  mbs.integer_list("alias_unit_ids", m.alias_unit_ids, 0, 255);
  mbs.integer("max_clients", m.max_clients, 1, 1000);
  mbs.integer("max_clients_per_address", m.max_clients_per_address, 1, 1000);
  mbs.number("idle_timeout_s", m.idle_timeout_s, closed(1, kDay_s, "s"));
  mbs.number("frame_timeout_s", m.frame_timeout_s, closed(0.1, 60, "s"));
  mbs.text("register_map", c.register_map_path);
  mbs.boolean("read_only", m.policy.read_only);
  mbs.choice<std::optional<std::uint64_t>>("unlock_key", m.policy.unlock_key, unlock_key);
  mbs.number("unlock_timeout_s", m.policy.unlock_timeout_s, closed(1, kDay_s, "s"));
  mbs.text_list("write_clients", m.policy.write_clients);
  mbs.refuse_unknown_keys();
}

// [modbus_tls.roles]: role name = "read" | "operate" | "tune"; when given, it replaces the defaults.
core::Status take_role(std::vector<modbus::RoleRights>& roles, const std::string& role, const std::string& rights_text) {
  if (auto ok = core::check_printable_name(role, "a role"); !ok) return ok;
  const auto rights = points::parse_rights(rights_text);
  if (!rights) return core::invalid_argument("= \"" + core::visible_text(rights_text) + "\": must be \"read\", \"operate\" or \"tune\"");
  roles.push_back({role, *rights});
  return core::ok();
}

void read_modbus_tls(TableReader& top, ApplianceConfig& c) {
  auto& s = c.modbus.secure;
  TableReader tls = top.section("modbus_tls");
  tls.boolean("enabled", s.enabled);
  tls.choice<std::string>("address", s.address, listen_address);
  tls.integer("port", s.port, 0, 65535);
  tls.text("ca", s.files.ca);
  tls.text("cert", s.files.cert);
  tls.text("key", s.files.key);
  tls.text("crl", s.files.crl);
  tls.number("handshake_timeout_s", s.handshake_timeout_s, closed(0.1, 60, "s"));
  std::vector<modbus::RoleRights> roles;
  bool given = false;
  tls.name_table("roles", given, [&roles](const std::string& role, const std::string& rights) { return take_role(roles, role, rights); });
  if (given) s.roles = std::move(roles);
  tls.refuse_unknown_keys();
}

void read_web(TableReader& top, ApplianceConfig& c) {
  TableReader web = top.section("web");
  web.boolean("enabled", c.web_enabled);
  web.choice<std::string>("address", c.web.address, listen_address);
  web.integer("port", c.web.port, 0, 65535);
  web.choice<std::string>("token", c.web.token, web_token);
  web.text("static_dir", c.web.static_dir);
  web.integer("max_connections_per_address", c.web.max_connections_per_address, 1, 4096);
  web.text_list("host_names", c.web.host_names);
  // HTTPS with [modbus_tls]'s files (check_web_tls); the appliance hands them and the roles over at start.
  web.boolean("tls", c.web.tls);
  const auto client_certificates = [](std::string_view v) -> core::Result<web::ClientCertificates> {
    if (v == "off") return web::ClientCertificates::kOff;
    if (v == "optional") return web::ClientCertificates::kOptional;
    return core::invalid_argument("'" + std::string(v) + "' is not off or optional");
  };
  web.choice<web::ClientCertificates>("client_certificates", c.web.client_certificates, client_certificates);
  web.refuse_unknown_keys();
}

void read_hal_sim(TableReader& hal, ApplianceConfig& c) {
  TableReader sim = hal.section("sim");
  sim.number("initial_position_mm", c.sim.initial_position_mm, closed(-10000, 10000, "mm"));
  sim.number("noise_mm", c.sim.noise_std_mm, closed(0, 100, "mm"));
  int seed = static_cast<int>(c.sim.seed);
  sim.integer("seed", seed, 0, 2147483647);
  c.sim.seed = static_cast<std::uint64_t>(seed);
  sim.choice<std::string>("plant", c.sim_plant, sim_plant);
  sim.text("physics_config", c.physics_config);
  sim.integer("sensor_bits", c.sim_sensor_bits, 0, 24);
  sim.number("initial_pressure_bar", c.sim_initial_pressure_bar, closed(0, 100, "bar"));
  sim.text_list("effects", c.sim_effects);
  sim.refuse_unknown_keys();
}

void read_hal_modbus_io(TableReader& hal, ApplianceConfig& c) {
  TableReader mb = hal.section("modbus_io");
  mb.choice<std::string>("host", c.modbus_io.host, module_host);
  mb.integer("port", c.modbus_io.port, 1, 65535);
  mb.integer("unit_id", c.modbus_io.unit_id, 0, 247);
  mb.integer("response_timeout_ms", c.modbus_io.response_timeout_ms, 1, 1000);
  read_analog_point(mb, "sensor", c.modbus_io.layout.sensor);
  read_analog_point(mb, "valve", c.modbus_io.layout.valve);
  mb.refuse_unknown_keys();
}

void read_hal_comedi(TableReader& hal, ApplianceConfig& c) {
  TableReader cm = hal.section("comedi");
  cm.text("device", c.comedi.device);
  read_comedi_channel(cm, "sensor", c.comedi.sensor);
  read_comedi_channel(cm, "valve", c.comedi.valve);
  cm.refuse_unknown_keys();
}

void read_hal(TableReader& top, ApplianceConfig& c) {
  TableReader hal = top.section("hal");
  hal.choice<HalBackend>("backend", c.backend, parse_backend);
  read_hal_sim(hal, c);
  read_hal_modbus_io(hal, c);
  read_hal_comedi(hal, c);
  hal.refuse_unknown_keys();
}

// Modbus/TCP Security needs its files and at least one role, and a port of its own.
core::Status check_modbus_tls(const ApplianceConfig& c) {
  const auto& s = c.modbus.secure;
  if (!s.enabled) return core::ok();
  for (const auto& [key, value] : {std::pair{"ca", &s.files.ca}, {"cert", &s.files.cert}, {"key", &s.files.key}})
    if (value->empty()) return core::invalid_argument(std::string("enabled needs ") + key + ": the PEM file (epa certs init makes them)");
  if (s.roles.empty()) return core::invalid_argument("roles is empty: no certificate could have any rights");
  if (c.modbus.plain_enabled && s.port != 0 && s.port == c.modbus.port)
    return core::invalid_argument("port " + std::to_string(s.port) + " is [modbus] port too: give each its own");
  return core::ok();
}

// HTTPS on the web port uses the certificate files of [modbus_tls], even with Modbus/TCP Security off.
core::Status check_web_tls(const ApplianceConfig& c) {
  if (!c.web_enabled || !c.web.tls) return core::ok();
  const auto& files = c.modbus.secure.files;
  for (const auto& [key, value] : {std::pair{"ca", &files.ca}, {"cert", &files.cert}, {"key", &files.key}})
    if (value->empty()) return core::invalid_argument(std::string("tls needs [modbus_tls] ") + key + ": the PEM file (epa certs init makes them)");
  return core::ok();
}

// Rules across keys and sections, in the runtime's and backends' own validators; write_clients
// are rewritten into the form a peer's address is compared in.
core::Status check_across_sections(ApplianceConfig& c, const std::string& file) {
  if (!c.sim_effects.empty()) {
    if (c.sim_plant != "hammerstein") return core::invalid_argument(file + ": [hal.sim] effects apply to the hammerstein plant only");
    if (auto e = plant::parse_effect_specs(c.sim_effects); !e) return core::invalid_argument(file + ": [hal.sim] effects: " + e.error().message);
  }
  for (std::string& client : c.modbus.policy.write_clients) {
    auto ip = core::parse_ip_address(client, 0);
    if (!ip) return core::invalid_argument(file + ": [modbus] write_clients: " + ip.error().message);
    client = core::ip_text(ip->storage);  // ::0:1 is ::1
  }
  if (auto s = check_modbus_tls(c); !s) return core::invalid_argument(file + ": [modbus_tls] " + s.error().message);
  if (auto s = check_web_tls(c); !s) return core::invalid_argument(file + ": [web] " + s.error().message);
  if (auto s = runtime::validate(c.runtime); !s) return core::invalid_argument(file + ": " + s.error().message);
  if (const auto p = c.health.estimator.problem(); !p.empty()) return core::invalid_argument(file + ": [health] " + p);
  if (c.backend == HalBackend::kModbusIo)
    if (auto s = hal::validate(c.modbus_io); !s) return core::invalid_argument(file + ": [hal.modbus_io] " + s.error().message);
  if (c.backend == HalBackend::kComedi)
    if (auto s = hal::validate(c.comedi); !s) return core::invalid_argument(file + ": [hal.comedi] " + s.error().message);
  return core::ok();
}

}  // namespace

const char* to_string(HalBackend b) {
  switch (b) {
    case HalBackend::kSim: return "sim";
    case HalBackend::kModbusIo: return "modbus-io";
    case HalBackend::kComedi: return "comedi";
  }
  return "?";
}

bool any_address_may_command(const ApplianceConfig& c) {
  return c.modbus.plain_enabled && !c.modbus.policy.read_only && c.modbus.policy.write_clients.empty();
}

std::string any_address_notice(const ApplianceConfig& c) {
  if (!any_address_may_command(c)) return "";
  return "any address may command motion over Modbus: set [modbus] write_clients to restrict it "
         "(docs/modbus.md, \"Who may command the axis\")";
}

core::Result<ApplianceConfig> parse_appliance_config(const std::string& text, const std::string& file) {
  auto document = core::parse_toml(text, file);
  if (!document) return document.error();
  ApplianceConfig c;
  std::optional<core::Error> error;
  // In the file's order of concerns; the first error wins, so the order is the order of the messages.
  TableReader top(&*document, "", file, error);
  read_loop(top, c);
  read_controller(top, c);
  read_limits(top, c);
  read_calibration(top, c);
  read_startup(top, c);
  read_recorder(top, c);
  read_motion(top, c);
  read_excite(top, c);
  read_health(top, c);
  read_store(top, c);
  read_log(top, c);
  read_modbus(top, c);
  read_modbus_tls(top, c);
  read_web(top, c);
  read_hal(top, c);
  top.refuse_unknown_keys();
  if (error) return *error;
  if (auto s = check_across_sections(c, file); !s) return s.error();
  return c;
}

core::Result<ApplianceConfig> read_appliance_config(const std::string& path) {
  auto text = core::read_text_file(path, "configuration file", core::kSmallFileCapBytes);
  if (!text) return text.error();
  auto c = parse_appliance_config(*text, path);
  if (!c) return c;
  // Files the configuration names are found next to it, wherever the appliance is started from.
  const auto folder = std::filesystem::path(path).parent_path();
  auto& tls_files = c->modbus.secure.files;
  for (std::string* p : {&c->model_path, &c->design_path, &c->register_map_path, &c->web.static_dir, &c->physics_config, &tls_files.ca,
                         &tls_files.cert, &tls_files.key, &tls_files.crl})
    if (!p->empty() && std::filesystem::path(*p).is_relative()) *p = (folder / *p).lexically_normal().string();
  return c;
}

}  // namespace epa::config
