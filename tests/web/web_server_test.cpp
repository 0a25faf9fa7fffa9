// The status page's HTTP server in-process on 127.0.0.1 (port 0), against a LoopChannels whose
// snapshot the test publishes: every endpoint's JSON, /metrics, the token rule, validation, and
// that bad requests and idle connections are survived.
#include "web/web_server.hpp"

#include "control/paper_controller.hpp"
#include "core/version.hpp"
#include "points/point_catalog.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <thread>
#include <utility>
#include <filesystem>
#include <fstream>

#include "../support/temp_path.hpp"
#include "../support/wait_until.hpp"
#include "web/commission_port.hpp"
#include "web/recent_audit.hpp"

namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using epa::runtime::Command;
using epa::runtime::CommandKind;

class Collecting : public epa::core::AuditSink {
 public:
  void record(const std::vector<epa::core::AuditEntry>& change) override {
    entries.insert(entries.end(), change.begin(), change.end());
    ++changes;
  }
  epa::core::ChangeCounters counters() const override { return {changes, changes}; }
  std::vector<epa::core::AuditEntry> entries;
  std::uint64_t changes = 0;
};

// A commissioning service that records what it was asked and answers as told.
class FakeCommission final : public epa::web::CommissionPort {
 public:
  epa::points::CommissionStartResult start(const std::string& spec, const std::string& source) override {
    if (spec.find("bad") != std::string::npos) return {epa::points::CommissionStart::kBadSpec, "commission spec: unknown key 'bad'"};
    if (running) return {epa::points::CommissionStart::kBusy, "a commissioning run is under way"};
    running = true, last_spec = spec, last_source = source;
    return {};
  }
  bool abort(const std::string&) override { return std::exchange(running, false); }
  epa::points::CommissionView view() const override { return {true, running, running ? 1 : 7, 0, running ? 10.0 : 100.0}; }
  std::string status_json() const override { return running ? R"({"running":true})" : R"({"running":false})"; }
  std::optional<std::string> result_json() const override { return result; }
  std::optional<std::string> report_html() const override { return result ? std::optional<std::string>("<html></html>") : std::nullopt; }
  bool running = false;
  std::string last_spec, last_source;
  std::optional<std::string> result;
};

class WebServerTest : public ::testing::Test {
 protected:
  void start(const std::string& token = "") {
    snap_.cycle = 1234;
    snap_.time_s = 6.17;
    snap_.Ts = 0.005;
    snap_.mode = epa::runtime::Mode::kRun;
    snap_.setpoint_mm = 120.0;
    snap_.position_mm = 118.5;
    snap_.error_mm = 1.5;
    snap_.valve_v = 1.25;
    snap_.heartbeat = 42;
    snap_.moves = 3;
    snap_.loop.jitter_p99_us = 17.0;
    snap_.loop.overruns = 2;
    snap_.last_move = {3, 50.0, 120.0, 0.21, std::nan(""), 0.4, 12.5};
    snap_.tuning.F = {1.0, -1.778, 0.7828};
    snap_.tuning.nF = 2;
    snap_.tuning.b_l = -1.722;
    snap_.tuning.b_r = 1.232;
    snap_.tuning.lc_mm = 5.0;
    channels_.snapshot.publish(snap_);
    epa::web::WebConfig config;
    config.address = "127.0.0.1";
    config.port = 0;
    config.token = token;
    config.static_dir = std::string(EPA_SOURCE_DIR) + "/web";
    config.request_deadline_ms = request_deadline_ms_;
    config.host_names = host_names_;
    if (!static_dir_.empty()) config.static_dir = static_dir_;
    auto limits = epa::points::WriteLimits::from_config(limits_, "test.toml");
    ASSERT_TRUE(limits.has_value()) << limits.error().message;
    gate_ = std::make_unique<epa::points::WriteGate>(std::move(*limits), limits_,
                                                     epa::control::paper_controller_config(epa::control::ControllerKind::kPpFfidz),
                                                     channels_, &audit_);
    auto server = epa::web::WebServer::start(
        config, channels_, gate_.get(), &audit_, [] { return epa::web::ModbusStats{true, 2, 77, 1}; }, {}, commission_);
    ASSERT_TRUE(server.has_value()) << server.error().message;
    server_ = std::move(*server);
    client_ = std::make_unique<httplib::Client>("127.0.0.1", server_->port());
    client_->set_connection_timeout(2, 0);
    client_->set_read_timeout(2, 0);
  }
  json get_json(const std::string& path, int expected_status = 200) {
    auto res = client_->Get(path.c_str());
    EXPECT_TRUE(res) << path;
    if (!res) return {};
    EXPECT_EQ(res->status, expected_status) << path << ": " << res->body;
    EXPECT_EQ(res->get_header_value("Content-Type"), "application/json") << path;
    return json::parse(res->body);
  }
  httplib::Result post(const std::string& path, const std::string& body, const std::string& token = "") {
    httplib::Headers headers;
    if (!token.empty()) headers.emplace("Authorization", "Bearer " + token);
    return client_->Post(path.c_str(), headers, body, "application/json");
  }
  std::vector<Command> queued() {
    std::vector<Command> out;
    Command c;
    while (channels_.commands.try_pop(c)) out.push_back(c);
    return out;
  }

  int request_deadline_ms_ = 2000;
  std::vector<std::string> host_names_;
  std::string static_dir_;  // "": the source tree's web/
  epa::runtime::LoopChannels channels_{16};
  epa::runtime::RuntimeConfig limits_;  // setpoint range [0, 500] mm
  epa::runtime::Snapshot snap_;
  Collecting log_;
  epa::web::RecentAudit audit_{&log_};
  std::unique_ptr<epa::points::WriteGate> gate_;
  epa::web::CommissionPort* commission_ = nullptr;
  std::unique_ptr<epa::web::WebServer> server_;
  std::unique_ptr<httplib::Client> client_;
};

TEST_F(WebServerTest, StatusShowsThePublishedSnapshotWithNanAsNull) {
  start();
  const json s = get_json("/api/status");
  EXPECT_EQ(s["cycle"], 1234);
  EXPECT_EQ(s["mode"], "run");
  EXPECT_EQ(s["fault"], "none");
  EXPECT_TRUE(s["fault_text"].is_null());
  EXPECT_EQ(s["controller"], "pp-ffidz");
  EXPECT_EQ(s["controller_name"], "PP FF-IDZ");
  EXPECT_DOUBLE_EQ(s["setpoint_mm"].get<double>(), 120.0);
  EXPECT_DOUBLE_EQ(s["position_mm"].get<double>(), 118.5);
  EXPECT_DOUBLE_EQ(s["error_mm"].get<double>(), 1.5);
  EXPECT_DOUBLE_EQ(s["valve_v"].get<double>(), 1.25);
  EXPECT_EQ(s["heartbeat"], 42);
  EXPECT_EQ(s["counters"]["moves"], 3);
  EXPECT_DOUBLE_EQ(s["loop"]["jitter_p99_us"].get<double>(), 17.0);
  EXPECT_EQ(s["loop"]["overruns"], 2);
  EXPECT_EQ(s["last_move"]["number"], 3);
  EXPECT_DOUBLE_EQ(s["last_move"]["rise_s"].get<double>(), 0.21);
  EXPECT_TRUE(s["last_move"]["settling_s"].is_null());  // NaN: never settled
  EXPECT_EQ(s["modbus"]["clients"], 2);
  EXPECT_EQ(s["modbus"]["requests"], 77);
  EXPECT_FALSE(s["commands_enabled"].get<bool>());
  EXPECT_EQ(s["version"], std::string(epa::core::kVersion));  // project(... VERSION) in CMakeLists.txt
}

// The status word as the register map has it (points::status_word), packed and as named bits, and
// the control word as the loop applied it.
TEST_F(WebServerTest, StatusCarriesTheStatusWordPackedAndBitByBit) {
  snap_.axis.in_position = true;
  snap_.axis.target_reached = true;
  snap_.axis.control_word = epa::runtime::kControlStart;
  start();
  const json s = get_json("/api/status");
  // ready (bit 0), run_enabled (1), in_position (3), target_reached (4)
  EXPECT_EQ(s["status_word"], 0x1B);
  EXPECT_EQ(s["status_word"], epa::points::status_word(snap_, true, false));
  EXPECT_EQ(s["control_word"], 1);
  const std::map<std::string, bool> expected = {
      {"ready", true}, {"run_enabled", true}, {"moving", false}, {"in_position", true}, {"target_reached", true},
      {"following_error", false}, {"warning", false}, {"fault_latched", false}, {"ack", false}, {"halted", false},
      {"jogging", false}, {"manual_mode", false}, {"off_target", false}, {"hunting", false}, {"health_warning", false}};
  ASSERT_EQ(s["status_bits"].size(), expected.size()) << s["status_bits"];
  for (const auto& [bit, on] : expected) EXPECT_EQ(s["status_bits"][bit], on) << bit;

  snap_.mode = epa::runtime::Mode::kManual;
  snap_.axis = {};
  snap_.axis.jogging = snap_.axis.moving = true;
  channels_.snapshot.publish(snap_);
  const json m = get_json("/api/status");
  EXPECT_EQ(m["status_word"], (1 << 0) | (1 << 2) | (1 << 10) | (1 << 11));
  EXPECT_FALSE(m["status_bits"]["run_enabled"].get<bool>());
  EXPECT_TRUE(m["status_bits"]["jogging"].get<bool>());
  EXPECT_TRUE(m["status_bits"]["manual_mode"].get<bool>());

  snap_.mode = epa::runtime::Mode::kRun;
  snap_.axis = {};
  snap_.axis.hunting = true;  // the law holds the valve against a limit cycle: a warning too
  channels_.snapshot.publish(snap_);
  const json h = get_json("/api/status");
  EXPECT_EQ(h["status_word"], (1 << 0) | (1 << 1) | (1 << 6) | (1 << 13));
  EXPECT_TRUE(h["status_bits"]["hunting"].get<bool>());
  // No model-health monitor behind this server: off, and why, with every key of the object.
  EXPECT_EQ(h["health"]["state"], "off");
  EXPECT_FALSE(h["health"]["reason"].get<std::string>().empty());
  for (const char* key : {"effect", "size", "ratio", "value", "commissioned", "unit", "moves_since_onset", "moves_seen"})
    EXPECT_TRUE(h["health"].contains(key)) << key;
  EXPECT_TRUE(h["health"]["ratio"].is_null());
  const json detail = get_json("/api/health");
  EXPECT_EQ(detail["state"], "off");
  EXPECT_TRUE(detail["trend"].is_array());
  EXPECT_TRUE(detail["trend"].empty());
  EXPECT_TRUE(detail["window_gap_mm"].is_null());
}

TEST_F(WebServerTest, StatusNamesALatchedFaultInWords) {
  start();
  snap_.mode = epa::runtime::Mode::kFault;
  snap_.fault = epa::runtime::FaultCode::kFollowingError;
  channels_.snapshot.publish(snap_);
  const json s = get_json("/api/status");
  EXPECT_EQ(s["mode"], "fault");
  EXPECT_EQ(s["fault"], "following-error");
  EXPECT_EQ(s["fault_text"], std::string(epa::runtime::describe(epa::runtime::FaultCode::kFollowingError)));
}

TEST_F(WebServerTest, TrendMovesTuningAndAuditHaveTheirShapes) {
  start();
  // The sampler takes a point every 50 ms: wait for two (bounded), then judge a fresh answer.
  epa::test::wait_until([&] { return get_json("/api/trend")["t_s"].size() >= 2; });
  const json t = get_json("/api/trend");
  ASSERT_GE(t["t_s"].size(), 2u);
  EXPECT_EQ(t["t_s"].size(), t["position_mm"].size());
  EXPECT_EQ(t["t_s"].size(), t["setpoint_mm"].size());
  EXPECT_EQ(t["t_s"].size(), t["valve_v"].size());
  EXPECT_DOUBLE_EQ(t["position_mm"].back().get<double>(), 118.5);
  EXPECT_DOUBLE_EQ(t["dead_zone"]["b_l"].get<double>(), -1.722);
  EXPECT_DOUBLE_EQ(t["dead_zone"]["b_r"].get<double>(), 1.232);
  EXPECT_DOUBLE_EQ(t["window_s"].get<double>(), 30.0);

  const json m = get_json("/api/moves");
  ASSERT_EQ(m["moves"].size(), 1u);
  EXPECT_EQ(m["moves"][0]["number"], 3);
  EXPECT_EQ(m["moves"][0]["controller"], "pp-ffidz");
  EXPECT_TRUE(m["moves"][0]["settling_s"].is_null());
  snap_.last_move.number = 4;
  channels_.snapshot.publish(snap_);
  epa::test::wait_until([&] { return get_json("/api/moves")["moves"].size() >= 2; });  // the sampler's next point
  const json m2 = get_json("/api/moves");
  ASSERT_EQ(m2["moves"].size(), 2u);
  EXPECT_EQ(m2["moves"][0]["number"], 4);  // newest first

  const json u = get_json("/api/tuning");
  EXPECT_EQ(u["F"], json::array({1.0, -1.778, 0.7828}));
  EXPECT_DOUBLE_EQ(u["b_l"].get<double>(), -1.722);
  EXPECT_DOUBLE_EQ(u["lc_mm"].get<double>(), 5.0);
  EXPECT_DOUBLE_EQ(u["Ts"].get<double>(), 0.005);

  audit_.record({{1000, "modbus 127.0.0.1:5000", "setpoint_mm", 0.0, 50.0}});
  const json a = get_json("/api/audit");
  ASSERT_EQ(a["entries"].size(), 1u);
  EXPECT_EQ(a["entries"][0]["source"], "modbus 127.0.0.1:5000");
  EXPECT_DOUBLE_EQ(a["entries"][0]["new_value"].get<double>(), 50.0);
  EXPECT_EQ(log_.entries.size(), 1u);  // forwarded to the next sink
}

// GET /api/faults, no token needed; the supervisor adds to the history, the page reads it.
TEST_F(WebServerTest, FaultsListTheHistoryNewestFirstWithoutAToken) {
  start("a-token-that-is-long-enough");
  json f = get_json("/api/faults");
  EXPECT_EQ(f["count"], 0);
  EXPECT_TRUE(f["faults"].empty());
  EXPECT_EQ(f["dropped"], 0);

  epa::runtime::FaultRecord older;
  older.time_ms = 1'795'579'167'123;  // 2026-11-25T03:59:27.123Z
  older.code = epa::runtime::FaultCode::kFollowingError;
  older.mode = epa::runtime::Mode::kRun;
  older.position_mm = 113.5, older.setpoint_mm = 150.0, older.valve_v = 1.25, older.sensor_v = 2.27;
  older.name = "following-error";
  older.text = "the position did not follow the setpoint";
  epa::runtime::FaultRecord unread;  // latched before anything was read: NaN position and sensor
  unread.time_ms = 1'795'579'200'000;
  unread.code = epa::runtime::FaultCode::kStoreDamaged;
  unread.setpoint_mm = 0.0, unread.valve_v = 0.0;
  unread.name = "store-damaged";
  unread.text = "the tuning database was damaged";
  channels_.fault_history.load(std::vector<epa::runtime::FaultRecord>{older}, 5);
  channels_.fault_history.add(unread);
  snap_.fault_events_dropped = 2;
  channels_.snapshot.publish(snap_);

  f = get_json("/api/faults");
  EXPECT_EQ(f["count"], 6);
  EXPECT_EQ(f["dropped"], 2);
  ASSERT_EQ(f["faults"].size(), 2u);
  const json& newest = f["faults"][0];
  EXPECT_EQ(newest["name"], "store-damaged");
  EXPECT_EQ(newest["code"], 9);
  EXPECT_EQ(newest["mode"], "stop");
  EXPECT_TRUE(newest["position_mm"].is_null());
  EXPECT_TRUE(newest["sensor_v"].is_null());
  const json& e = f["faults"][1];
  EXPECT_EQ(e["time"], "2026-11-25T03:59:27.123Z");
  EXPECT_EQ(e["time_ms"], 1'795'579'167'123);
  EXPECT_EQ(e["code"], 6);
  EXPECT_EQ(e["name"], "following-error");
  EXPECT_EQ(e["text"], "the position did not follow the setpoint");
  EXPECT_EQ(e["mode"], "run");
  EXPECT_DOUBLE_EQ(e["position_mm"].get<double>(), 113.5);
  EXPECT_DOUBLE_EQ(e["setpoint_mm"].get<double>(), 150.0);
  EXPECT_DOUBLE_EQ(e["valve_v"].get<double>(), 1.25);
  EXPECT_DOUBLE_EQ(e["sensor_v"].get<double>(), 2.27);
}

// The server answers one request of its own before its workers start (deadline_http_server.cpp):
// it is no client's, and the count says so.
TEST_F(WebServerTest, TheRequestCountIsTheClientsAlone) {
  start();
  auto res = client_->Get("/metrics");
  ASSERT_TRUE(res);
  EXPECT_NE(res->body.find("\nepa_web_requests_total 1\n"), std::string::npos) << res->body.substr(0, 2000);
}

TEST_F(WebServerTest, MetricsAreValidPrometheusText) {
  start();
  auto res = client_->Get("/metrics");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  EXPECT_NE(res->get_header_value("Content-Type").find("text/plain"), std::string::npos);
  std::istringstream in(res->body);
  std::string line;
  std::map<std::string, double> samples;
  std::set<std::string> help, type, counters;
  while (std::getline(in, line)) {
    ASSERT_FALSE(line.empty());
    std::istringstream words(line);
    std::string a, b;
    if (line.rfind("# HELP ", 0) == 0) { words >> a >> a >> b; help.insert(b); continue; }
    if (line.rfind("# TYPE ", 0) == 0) {
      std::string kind;
      words >> a >> a >> b >> kind;
      EXPECT_TRUE(kind == "gauge" || kind == "counter") << line;
      type.insert(b);
      if (kind == "counter") counters.insert(b);
      continue;
    }
    std::string value, rest;
    words >> a >> value;
    EXPECT_FALSE(words >> rest) << "more than 'name value': " << line;
    char* end = nullptr;
    const double v = std::strtod(value.c_str(), &end);
    EXPECT_EQ(*end, '\0') << line;
    samples[a] = v;
  }
  for (const char* name : {"epa_position_meters", "epa_error_meters", "epa_valve_volts", "epa_loop_jitter_p99_seconds",
                           "epa_loop_overruns_total", "epa_faults_total", "epa_moves_total", "epa_modbus_requests_total", "epa_mode",
                           "epa_uptime_seconds", "epa_build_info"}) {
    EXPECT_TRUE(help.count(name)) << name;
    EXPECT_TRUE(type.count(name)) << name;
  }
  // Every sample has its HELP and TYPE; base units only; counters and only counters end in _total.
  for (const auto& [sample, v] : samples) {
    const std::string name = sample.substr(0, sample.find('{'));
    EXPECT_TRUE(help.count(name) && type.count(name)) << name;
    for (const char* non_base : {"_mm", "_us", "_ms", "micro", "milli"}) EXPECT_EQ(name.find(non_base), std::string::npos) << name;
  }
  for (const auto& name : type) EXPECT_EQ(name.ends_with("_total"), counters.count(name) == 1) << name;
  EXPECT_DOUBLE_EQ(samples["epa_position_meters"], 0.1185);  // 118.5 mm
  EXPECT_DOUBLE_EQ(samples["epa_loop_jitter_p99_seconds"], 17e-6);
  EXPECT_DOUBLE_EQ(samples["epa_modbus_requests_total"], 77);
  EXPECT_DOUBLE_EQ(samples["epa_loop_overruns_total"], 2);
  EXPECT_DOUBLE_EQ(samples["epa_moves_total"], 3);
  EXPECT_DOUBLE_EQ(samples["epa_mode"], 1);
  EXPECT_DOUBLE_EQ(samples["epa_build_info{version=\"" + std::string(epa::core::kVersion) + "\"}"], 1);
  // The help says what the catalog says the point means (moves finished, not started).
  EXPECT_NE(res->body.find("# HELP epa_moves_total " + std::string(epa::points::point(epa::points::PointId::kMoves).description)),
            std::string::npos);
}

TEST_F(WebServerTest, WithoutATokenEveryPostIsForbidden) {
  start();
  for (const char* path : {"/api/setpoint", "/api/mode", "/api/reset", "/api/points", "/api/records"}) {
    auto res = post(path, "{}", "anything");
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 403) << path;
    EXPECT_NE(json::parse(res->body)["error"].get<std::string>().find("token"), std::string::npos);
  }
  EXPECT_TRUE(queued().empty());
  EXPECT_TRUE(audit_.entries().empty());
}

TEST_F(WebServerTest, WithATokenOnlyTheRightBearerIsObeyedAndAudited) {
  start("s3cret-token");
  auto missing = post("/api/setpoint", R"({"setpoint_mm": 150})");
  ASSERT_TRUE(missing);
  EXPECT_EQ(missing->status, 401);
  auto wrong = post("/api/setpoint", R"({"setpoint_mm": 150})", "s3cret-tokeN");
  ASSERT_TRUE(wrong);
  EXPECT_EQ(wrong->status, 401);
  EXPECT_TRUE(json::parse(wrong->body).contains("error"));
  EXPECT_TRUE(queued().empty());

  auto right = post("/api/setpoint", R"({"setpoint_mm": 150})", "s3cret-token");
  ASSERT_TRUE(right);
  EXPECT_EQ(right->status, 200) << right->body;
  auto q = queued();
  ASSERT_EQ(q.size(), 1u);
  EXPECT_EQ(q[0].kind, CommandKind::kSetpoint);
  EXPECT_DOUBLE_EQ(q[0].value, 150.0);
  const auto entries = audit_.entries();
  ASSERT_EQ(entries.size(), 1u);
  EXPECT_EQ(entries[0].source, "web 127.0.0.1");
  EXPECT_EQ(entries[0].point, "setpoint_mm");
  EXPECT_DOUBLE_EQ(entries[0].old_value, 120.0);
  EXPECT_DOUBLE_EQ(entries[0].new_value, 150.0);

  auto mode = post("/api/mode", R"({"mode": "stop"})", "s3cret-token");
  ASSERT_TRUE(mode);
  EXPECT_EQ(mode->status, 200);
  auto reset = post("/api/reset", "{}", "s3cret-token");
  ASSERT_TRUE(reset);
  EXPECT_EQ(reset->status, 200);
  q = queued();
  ASSERT_EQ(q.size(), 2u);
  EXPECT_EQ(q[0].kind, CommandKind::kMode);
  EXPECT_EQ(q[0].mode, epa::runtime::Mode::kStop);
  EXPECT_EQ(q[1].kind, CommandKind::kReset);
  EXPECT_EQ(get_json("/api/audit")["entries"].size(), 3u);
  EXPECT_TRUE(get_json("/api/status")["commands_enabled"].get<bool>());
}

TEST_F(WebServerTest, CommissioningIsStartedAndAbortedWithTheTokenAndReadLikeTheStatus) {
  FakeCommission fake;
  commission_ = &fake;
  start("s3cret-token");
  EXPECT_EQ(get_json("/api/commission/result", 404)["error"], "no commissioning run has ended yet");
  auto anonymous = post("/api/commission", "{}");
  ASSERT_TRUE(anonymous);
  EXPECT_EQ(anonymous->status, 401);
  EXPECT_FALSE(fake.running);
  auto bad = post("/api/commission", R"({"bad": 1})", "s3cret-token");
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->status, 400);
  EXPECT_NE(json::parse(bad->body)["error"].get<std::string>().find("'bad'"), std::string::npos);
  auto started = post("/api/commission", R"({"excitation_s": 30})", "s3cret-token");
  ASSERT_TRUE(started);
  EXPECT_EQ(started->status, 202) << started->body;
  EXPECT_EQ(fake.last_spec, R"({"excitation_s": 30})");
  EXPECT_EQ(fake.last_source, "web 127.0.0.1");
  EXPECT_TRUE(get_json("/api/commission")["running"].get<bool>());
  auto again = post("/api/commission", "", "s3cret-token");
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, 409);
  auto abort = post("/api/commission/abort", "", "s3cret-token");
  ASSERT_TRUE(abort);
  EXPECT_EQ(abort->status, 200);
  auto nothing = post("/api/commission/abort", "", "s3cret-token");
  ASSERT_TRUE(nothing);
  EXPECT_EQ(nothing->status, 409);
  fake.result = R"({"schema":"epa-commission/1"})";
  EXPECT_EQ(get_json("/api/commission/result")["schema"], "epa-commission/1");
  auto report = client_->Get("/api/commission/report");
  ASSERT_TRUE(report);
  EXPECT_EQ(report->status, 200);
  EXPECT_EQ(report->get_header_value("Content-Type"), "text/html; charset=utf-8");
}

TEST_F(WebServerTest, WithoutACommissioningServiceItsPathsAre404) {
  start("t");
  EXPECT_EQ(get_json("/api/commission", 404)["error"], "this appliance runs no commissioning service");
  auto post_start = post("/api/commission", "{}", "t");
  ASSERT_TRUE(post_start);
  EXPECT_EQ(post_start->status, 404);
}

TEST_F(WebServerTest, CommandsAreValidatedLikeModbusWrites) {
  start("t");
  auto far = post("/api/setpoint", R"({"setpoint_mm": 600})", "t");
  ASSERT_TRUE(far);
  EXPECT_EQ(far->status, 400);
  EXPECT_NE(json::parse(far->body)["error"].get<std::string>().find("[0, 500]"), std::string::npos) << far->body;
  for (const char* body : {"{\"setpoint_mm\": ", "not json", "[1,2]", R"({"setpoint_mm": "100"})", R"({"setpoint": 100})"}) {
    auto res = post("/api/setpoint", body, "t");
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 400) << body;
    EXPECT_TRUE(json::parse(res->body).contains("error")) << body;
  }
  auto bad_mode = post("/api/mode", R"({"mode": "fault"})", "t");
  ASSERT_TRUE(bad_mode);
  EXPECT_EQ(bad_mode->status, 400);

  snap_.mode = epa::runtime::Mode::kFault;
  snap_.fault = epa::runtime::FaultCode::kSoftLimit;
  channels_.snapshot.publish(snap_);
  auto refused = post("/api/mode", R"({"mode": "run"})", "t");
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 409);
  EXPECT_NE(json::parse(refused->body)["error"].get<std::string>().find("fault"), std::string::npos);
  EXPECT_TRUE(queued().empty());
  EXPECT_TRUE(audit_.entries().empty());
  auto reset = post("/api/reset", "", "t");  // reset is what a latched fault needs
  ASSERT_TRUE(reset);
  EXPECT_EQ(reset->status, 200);
}

// GET /api/records: the table as the gate holds it, read without a token; a write through
// /api/points shows at once (read after write, before the loop took it).
TEST_F(WebServerTest, RecordsListTheTableAsTheGateHoldsIt) {
  start("t");
  const json empty = get_json("/api/records");
  ASSERT_EQ(empty["records"].size(), epa::points::kPositionRecords);
  EXPECT_EQ(empty["record_select"], 0);
  for (std::size_t i = 0; i < epa::points::kPositionRecords; ++i) {
    const json& r = empty["records"][i];
    EXPECT_EQ(r["record"], i + 1);
    EXPECT_EQ(r["target_mm"], 0.0);
    EXPECT_EQ(r["speed_mm_s"], 0.0);
    EXPECT_EQ(r["window_mm"], 0.0);
    EXPECT_EQ(r["controller"], "running");
    EXPECT_EQ(r["approach"], "near");
  }
  auto res = post("/api/points",
                  R"({"record3_target_mm": 120.5, "record3_speed_mm_s": 50, "record3_window_mm": 0.5,
                      "record3_controller": "pp-traj", "record_select": 3, "record4_controller": 1, "record3_approach": 2})", "t");
  ASSERT_TRUE(res);
  ASSERT_EQ(res->status, 200) << res->body;
  const json after = get_json("/api/records");
  EXPECT_EQ(after["record_select"], 3);
  const json& r3 = after["records"][2];
  EXPECT_EQ(r3["record"], 3);
  EXPECT_DOUBLE_EQ(r3["target_mm"].get<double>(), 120.5);
  EXPECT_DOUBLE_EQ(r3["speed_mm_s"].get<double>(), 50.0);
  EXPECT_DOUBLE_EQ(r3["window_mm"].get<double>(), 0.5);
  EXPECT_EQ(r3["controller"], "pp-traj");
  EXPECT_EQ(r3["approach"], "from-above");
  EXPECT_EQ(after["records"][3]["controller"], "pp-ngidz");
  EXPECT_EQ(after["records"][1]["target_mm"], 0.0);  // its neighbours untouched
  EXPECT_EQ(after["records"][3]["target_mm"], 0.0);
}

// POST /api/records: one record's fields as its record<N>_* points in one gate group, all or
// nothing; a malformed body is 400 naming what was wrong, before the gate sees it.
TEST_F(WebServerTest, ARecordIsWrittenAsOneGroupAllOrNothing) {
  start("t");
  auto ok = post("/api/records", R"({"record": 5, "target_mm": 200, "speed_mm_s": 10, "window_mm": 2, "controller": "pp", "approach": "from-below"})", "t");
  ASSERT_TRUE(ok);
  ASSERT_EQ(ok->status, 200) << ok->body;
  auto record5 = [this] { return get_json("/api/records")["records"][4]; };
  EXPECT_DOUBLE_EQ(record5()["target_mm"].get<double>(), 200.0);
  EXPECT_DOUBLE_EQ(record5()["speed_mm_s"].get<double>(), 10.0);
  EXPECT_DOUBLE_EQ(record5()["window_mm"].get<double>(), 2.0);
  EXPECT_EQ(record5()["controller"], "pp");
  EXPECT_EQ(record5()["approach"], "from-below");
  std::set<std::string> audited;
  for (const auto& e : audit_.entries()) audited.insert(e.point);
  EXPECT_EQ(audited, (std::set<std::string>{"record5_target_mm", "record5_speed_mm_s", "record5_window_mm", "record5_controller",
                                            "record5_approach"}));
  auto some = post("/api/records", R"({"record": 5, "controller": "running"})", "t");  // the others kept
  ASSERT_TRUE(some);
  ASSERT_EQ(some->status, 200) << some->body;
  EXPECT_EQ(record5()["controller"], "running");
  EXPECT_DOUBLE_EQ(record5()["target_mm"].get<double>(), 200.0);

  // Refused by the gate: the whole group, with the gate's reason.
  const std::pair<const char*, const char*> refused[] = {
      {R"({"record": 5, "target_mm": 300, "window_mm": 1000})", "record5_window_mm"},
      {R"({"record": 5, "target_mm": 600, "window_mm": 1})", "setpoint range [0, 500]"},
      {R"({"record": 5, "target_mm": 300, "controller": 7})", "record5_controller"},
      {R"({"record": 5, "target_mm": 300, "approach": 3})", "record5_approach"},
  };
  for (const auto& [body, named] : refused) {
    auto res = post("/api/records", body, "t");
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 400) << body;
    EXPECT_NE(json::parse(res->body)["error"].get<std::string>().find(named), std::string::npos) << body << ": " << res->body;
    EXPECT_DOUBLE_EQ(record5()["target_mm"].get<double>(), 200.0) << body;
    EXPECT_DOUBLE_EQ(record5()["window_mm"].get<double>(), 2.0) << body;
  }
  // Malformed: named before the gate sees it.
  const std::pair<const char*, const char*> malformed[] = {
      {R"({"record": 5, "target_mm": 300, "speed": 3})", "unknown field 'speed'"},
      {R"({"target_mm": 300})", "name the record"},
      {R"({"record": 0, "target_mm": 300})", "record must be a whole number 1..32, not 0"},
      {R"({"record": 33, "target_mm": 300})", "not 33"},
      {R"({"record": "5", "target_mm": 300})", "not \"5\""},
      {R"({"record": 2.5, "target_mm": 300})", "not 2.5"},
      {R"({"record": 5})", "give at least one of"},
      {R"({"record": 5, "target_mm": "far"})", "record5_target_mm must be a number"},
      {R"({"record": 5, "controller": "pp-fast"})", "unknown controller 'pp-fast'"},
      {R"({"record": 5, "approach": "sideways"})", "unknown approach 'sideways'"},
      {R"([5])", "JSON object"},
  };
  const auto entries_before = audit_.entries().size();
  for (const auto& [body, named] : malformed) {
    auto res = post("/api/records", body, "t");
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 400) << body;
    EXPECT_NE(json::parse(res->body)["error"].get<std::string>().find(named), std::string::npos) << body << ": " << res->body;
  }
  EXPECT_EQ(audit_.entries().size(), entries_before);
  EXPECT_DOUBLE_EQ(record5()["target_mm"].get<double>(), 200.0);
  auto wrong = post("/api/records", R"({"record": 5, "target_mm": 300})", "T");
  ASSERT_TRUE(wrong);
  EXPECT_EQ(wrong->status, 401);
  EXPECT_DOUBLE_EQ(record5()["target_mm"].get<double>(), 200.0);
}

// Mode EXCITE over HTTP: by its name, from STOP only (409 otherwise, naming why); its time left in the status.
TEST_F(WebServerTest, ExciteIsAModeByNameEnteredFromStopOnly) {
  start("t");
  auto from_run = post("/api/mode", R"({"mode": "excite"})", "t");  // the fixture's snapshot: RUN
  ASSERT_TRUE(from_run);
  EXPECT_EQ(from_run->status, 409);
  EXPECT_NE(json::parse(from_run->body)["error"].get<std::string>().find("STOP"), std::string::npos) << from_run->body;
  EXPECT_TRUE(queued().empty());

  snap_.mode = epa::runtime::Mode::kStop;
  snap_.position_mm = 250.0;
  channels_.snapshot.publish(snap_);
  auto from_stop = post("/api/mode", R"({"mode": "excite"})", "t");
  ASSERT_TRUE(from_stop);
  EXPECT_EQ(from_stop->status, 200) << from_stop->body;
  const auto q = queued();
  ASSERT_EQ(q.size(), 1u);
  EXPECT_EQ(q[0].mode, epa::runtime::Mode::kExcite);

  snap_.mode = epa::runtime::Mode::kExcite;
  snap_.excitation_left_s = 12.5;
  channels_.snapshot.publish(snap_);
  const json s = get_json("/api/status");
  EXPECT_EQ(s["mode"], "excite");
  EXPECT_DOUBLE_EQ(s["excite_left_s"].get<double>(), 12.5);
}

// The catalog over HTTP: GET /api/points lists every point with the gate's ranges, and
// POST /api/points with any writable point beyond its range is 400 naming the limit, with
// nothing queued or audited; within range (and in a state that allows it) it is taken.
TEST_F(WebServerTest, EveryWritablePointBeyondItsLimitsIs400NamingTheLimit) {
  limits_.setpoint_max_mm = 300;  // the configuration narrows the catalog's 0..500
  start("t");
  snap_.mode = epa::runtime::Mode::kManual;  // so only the range can refuse the manual valve
  channels_.snapshot.publish(snap_);
  const json catalog = get_json("/api/points");
  int checked = 0;
  for (const auto& p : catalog["points"]) {
    if (!p.contains("max")) continue;  // read-only, or the Modbus key
    const std::string name = p["name"];
    for (double v : {p["max"].get<double>() + std::max(1.0, std::abs(p["max"].get<double>()) * 1e-3),
                     p["min"].get<double>() - std::max(1.0, std::abs(p["min"].get<double>()) * 1e-3)}) {
      auto res = post("/api/points", json{{name, v}}.dump(), "t");
      ASSERT_TRUE(res);
      EXPECT_EQ(res->status, 400) << name << " = " << v << ": " << res->body;
      const std::string error = json::parse(res->body)["error"];
      EXPECT_NE(error.find(name), std::string::npos) << error;
      EXPECT_NE(error.find("outside"), std::string::npos) << error;
      ++checked;
    }
  }
  EXPECT_GE(checked, 24);
  auto far = post("/api/setpoint", R"({"setpoint_mm": 400})", "t");
  ASSERT_TRUE(far);
  EXPECT_EQ(far->status, 400);
  EXPECT_NE(json::parse(far->body)["error"].get<std::string>().find("setpoint_max_mm"), std::string::npos) << far->body;
  EXPECT_TRUE(queued().empty());
  EXPECT_TRUE(audit_.entries().empty());

  auto group = post("/api/points", R"({"manual_valve_v": 1.5, "m_r": 2.0, "controller": "pp"})", "t");
  ASSERT_TRUE(group);
  EXPECT_EQ(group->status, 200) << group->body;
  EXPECT_EQ(queued().size(), 3u);  // manual valve, controller, tuning
  EXPECT_EQ(audit_.entries().size(), 3u);
  auto unknown = post("/api/points", R"({"setpoint": 100})", "t");
  ASSERT_TRUE(unknown);
  EXPECT_EQ(unknown->status, 400);
  auto read_only = post("/api/points", R"({"position_mm": 100})", "t");
  ASSERT_TRUE(read_only);
  EXPECT_EQ(read_only->status, 400);
}

TEST_F(WebServerTest, UnknownPathsAndOversizedBodiesGetJsonErrors) {
  start("t");
  const json e = get_json("/api/nothing", 404);
  EXPECT_TRUE(e.contains("error"));
  auto wrong_method = client_->Delete("/api/status");
  ASSERT_TRUE(wrong_method);
  EXPECT_GE(wrong_method->status, 400);
  EXPECT_LT(wrong_method->status, 500);
  EXPECT_TRUE(json::parse(wrong_method->body).contains("error"));
  auto big = post("/api/setpoint", "{\"setpoint_mm\": 1" + std::string(100000, '0') + "}", "t");
  ASSERT_TRUE(big);
  EXPECT_EQ(big->status, 413);
  EXPECT_TRUE(json::parse(big->body).contains("error"));
  // Still serving afterwards.
  httplib::Client again("127.0.0.1", server_->port());
  auto ok = again.Get("/api/status");
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 200);
}

TEST_F(WebServerTest, ServesThePageAndChartJs) {
  start();
  auto page = client_->Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("data-trend-points"), std::string::npos);
  auto js = client_->Get("/app.js");
  ASSERT_TRUE(js);
  EXPECT_EQ(js->status, 200);
  auto chart = client_->Get("/vendor/chart.js");
  ASSERT_TRUE(chart);
  EXPECT_EQ(chart->status, 200);  // Debian's libjs-chart.js
  EXPECT_NE(chart->body.find("Chart.js"), std::string::npos);
}

// A connected loopback socket to the server, with a 10 s receive timeout; -1 on failure.
int connect_to(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  timeval tv{10, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// One raw HTTP exchange: what the server answers to `request` (first line), and how long it took.
std::pair<std::string, std::chrono::milliseconds> raw_exchange(int port, const std::string& request) {
  const auto t0 = std::chrono::steady_clock::now();
  const int fd = connect_to(port);
  if (fd < 0) return {"connect failed", {}};
  for (std::size_t sent = 0; sent < request.size();) {
    const auto n = ::send(fd, request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
    if (n <= 0) break;
    sent += static_cast<std::size_t>(n);
  }
  char buf[256] = {};
  const auto n = ::recv(fd, buf, sizeof buf - 1, 0);
  const auto took = std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - t0);
  ::close(fd);
  const std::string answer(buf, n > 0 ? static_cast<std::size_t>(n) : 0);
  return {answer.substr(0, answer.find("\r\n")), took};
}

// A second appliance on the same web port is refused with the port named, not let in beside the
// first (SO_REUSEPORT would share the connections between the two pages).
TEST_F(WebServerTest, ASecondServerOnTheSamePortIsRefused) {
  start();
  epa::web::WebConfig config;
  config.address = "127.0.0.1";
  config.port = server_->port();
  config.static_dir = std::string(EPA_SOURCE_DIR) + "/web";
  auto second = epa::web::WebServer::start(config, channels_, gate_.get(), &audit_,
                                           [] { return epa::web::ModbusStats{true, 2, 77, 1}; }, {}, nullptr);
  ASSERT_FALSE(second.has_value()) << "a second server bound 127.0.0.1:" << server_->port();
  EXPECT_NE(second.error().message.find(":" + std::to_string(server_->port())), std::string::npos) << second.error().message;
  EXPECT_NE(second.error().message.find("in use"), std::string::npos) << second.error().message;
  EXPECT_EQ(get_json("/api/status")["setpoint_mm"], 120.0);  // the first still answers
}

TEST_F(WebServerTest, OversizedHeadsAndDeclaredBodiesAreRefusedAtOnce) {
  start("a-token-of-sixteen-chars");
  std::string many = "GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\n";
  for (int i = 0; i < 100; ++i) many += "X-Filler-" + std::to_string(i) + ": y\r\n";
  EXPECT_EQ(raw_exchange(server_->port(), many + "\r\n").first, "HTTP/1.1 431 Request Header Fields Too Large");
  std::string big = "GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\n";  // 40 fields of 300 bytes: 12 KB
  for (int i = 0; i < 40; ++i) big += "X-Big-" + std::to_string(i) + ": " + std::string(300, 'a') + "\r\n";
  EXPECT_EQ(raw_exchange(server_->port(), big + "\r\n").first, "HTTP/1.1 431 Request Header Fields Too Large");
  const auto [answer, took] = raw_exchange(server_->port(), "POST /api/setpoint HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 1000000000000\r\n"
                                                            "Content-Type: application/json\r\n\r\n{");
  EXPECT_EQ(answer, "HTTP/1.1 413 Payload Too Large");
  EXPECT_LT(took, std::chrono::milliseconds(1000));  // not after holding a worker for the read timeout
  EXPECT_TRUE(queued().empty());
}

TEST_F(WebServerTest, WrongTokensFromAnAddressAreRefusedUnseenForABackOff) {
  start("a-token-of-sixteen-chars");
  for (int i = 1; i <= 5; ++i) {
    auto r = post("/api/setpoint", R"({"setpoint_mm": 150})", "guess-" + std::to_string(i));
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 401) << i;
  }
  auto locked = post("/api/setpoint", R"({"setpoint_mm": 150})", "a-token-of-sixteen-chars");  // right, but too late
  ASSERT_TRUE(locked);
  EXPECT_EQ(locked->status, 429);
  EXPECT_FALSE(locked->get_header_value("Retry-After").empty());
  EXPECT_TRUE(queued().empty());
  EXPECT_EQ(get_json("/api/status")["mode"], "run");  // reading goes on
}

// A drifting verdict in JSON: the effect by the diagnosis's name, its numbers, each judgement's estimates.
TEST(HealthJson, ADriftCarriesItsEffectSizeAndTrend) {
  epa::points::HealthReport r;
  r.view = {epa::points::HealthStateCode::kDrifting, epa::points::HealthEffectCode::kStaticFriction, 14.2, 7.9, 14.2 / 7.9, 61, 6};
  r.size = "friction up 80 %";
  r.unit = "mm";
  r.window_gap_mm = 3.1;
  r.trend = {{60, {{epa::points::HealthEffectCode::kStaticFriction, 1.7, 0.6}, {epa::points::HealthEffectCode::kGainChange, 0.9, 0.2}}}};
  const json status = json::parse(epa::web::status_json({}, {}, false, {}, r));
  EXPECT_EQ(status["health"]["state"], "drifting");
  EXPECT_EQ(status["health"]["effect"], "static_friction");
  EXPECT_EQ(status["health"]["size"], "friction up 80 %");
  EXPECT_NEAR(status["health"]["ratio"].get<double>(), 14.2 / 7.9, 1e-12);
  EXPECT_EQ(status["health"]["moves_since_onset"], 6);
  EXPECT_EQ(status["health"]["moves_seen"], 61);
  EXPECT_TRUE(status["status_bits"]["health_warning"].get<bool>());
  EXPECT_TRUE(status["status_bits"]["warning"].get<bool>());
  const json detail = json::parse(epa::web::health_json(r));
  ASSERT_EQ(detail["trend"].size(), 1u);
  EXPECT_EQ(detail["trend"][0]["move"], 60);
  EXPECT_EQ(detail["trend"][0]["estimates"][1]["effect"], "gain_change");
  EXPECT_NEAR(detail["trend"][0]["estimates"][0]["reduction"].get<double>(), 0.6, 1e-12);
  EXPECT_NEAR(detail["window_gap_mm"].get<double>(), 3.1, 1e-12);
}

TEST(WebServerStatic, NothingOutsideStaticDirIsServedAndTheFolderMustHoldThePage) {
  namespace fs = std::filesystem;
  const epa::test::TempDir temp("web-static");
  const fs::path& dir = temp.path;
  for (const char* f : {"index.html", "app.js", "style.css"}) fs::copy_file(fs::path(EPA_SOURCE_DIR) / "web" / f, dir / f);
  fs::create_symlink("/etc/passwd", dir / "passwd");  // a link that leaves the folder
  fs::create_directory_symlink("/etc", dir / "etc");
  epa::runtime::LoopChannels channels{16};
  epa::web::WebConfig config;
  config.address = "127.0.0.1";
  config.port = 0;
  config.static_dir = dir.string();
  auto server = epa::web::WebServer::start(config, channels, nullptr, nullptr);
  ASSERT_TRUE(server.has_value()) << server.error().message;
  httplib::Client c("127.0.0.1", (*server)->port());
  for (const char* path : {"/passwd", "/etc/passwd", "/../../etc/passwd", "/%2e%2e/%2e%2e/etc/passwd"}) {
    auto r = c.Get(path);
    ASSERT_TRUE(r) << path;
    EXPECT_EQ(r->status, 404) << path;
    EXPECT_EQ(r->body.find("root:"), std::string::npos) << path;
  }
  auto page = c.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  (*server)->stop();
  config.static_dir = "/";  // a folder, but not the page's
  auto root = epa::web::WebServer::start(config, channels, nullptr, nullptr);
  ASSERT_FALSE(root.has_value());
  EXPECT_NE(root.error().message.find("index.html"), std::string::npos) << root.error().message;
}

TEST_F(WebServerTest, FiftyIdleConnectionsDoNotStopANormalRequest) {
  start();
  std::vector<int> idle;
  for (int i = 0; i < 50; ++i) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    ASSERT_GE(fd, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<std::uint16_t>(server_->port()));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    sockaddr_in from{};  // 127.0.0.2-6: ten each, under the per-address cap
    from.sin_family = AF_INET;
    from.sin_addr.s_addr = htonl(INADDR_LOOPBACK + 1 + static_cast<std::uint32_t>(i % 5));
    ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&from), sizeof from), 0);
    ASSERT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
    if (i % 2) {
      ASSERT_GT(::send(fd, "GET /api/sta", 12, 0), 0);  // half of them stop mid-request
    }
    idle.push_back(fd);
  }
  // The server has accepted them all: its listening socket's accept queue is empty (bounded).
  epa::test::wait_until([&] { return epa::test::accept_queue_length(server_->port()) == 0; });
  const auto t0 = std::chrono::steady_clock::now();
  auto res = client_->Get("/api/status");
  const auto took = std::chrono::steady_clock::now() - t0;
  for (int fd : idle) ::close(fd);
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  EXPECT_LT(took, 200ms);
}

// Everything the server sends until it closes the connection (or 10 s pass).
std::string read_to_close(int fd) {
  std::string all;
  char buf[4096];
  for (ssize_t n; (n = ::recv(fd, buf, sizeof buf, 0)) > 0;) all.append(buf, static_cast<std::size_t>(n));
  return all;
}

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST_F(WebServerTest, PipelinedRequestsOnOneConnectionAreEachAnswered) {
  start();
  const int fd = connect_to(server_->port());
  ASSERT_GE(fd, 0);
  const std::string get = "GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
  const std::string last = "GET /api/points HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n";
  const std::string three = get + get + last;  // in one segment: the second and third wait in the buffer
  ASSERT_EQ(::send(fd, three.data(), three.size(), MSG_NOSIGNAL), static_cast<ssize_t>(three.size()));
  const std::string answers = read_to_close(fd);
  ::close(fd);
  EXPECT_EQ(count_of(answers, "HTTP/1.1 200 OK"), 3u) << answers.substr(0, 300);
  EXPECT_EQ(count_of(answers, "\"mode\":\"run\""), 2u);
}

// Clients that pipeline requests, do not read, and then reset their connections while the front end
// is writing their answers: each such connection is closed and erased where it was found, and the
// server serves on (it once used the erased entry: a crash under such a crowd, a report under ASan).
TEST_F(WebServerTest, ClientsThatResetWhileTheirAnswersAreWrittenAreClosedAndTheServerServesOn) {
  start();
  std::string pipelined;
  for (int i = 0; i < 200; ++i) pipelined += "GET /api/trend HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
  for (int round = 0; round < 3; ++round) {
    std::vector<int> fds;
    for (int i = 0; i < 24; ++i) {
      const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
      const int small = 4096;
      setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);  // before connect: a small window
      sockaddr_in addr{};
      addr.sin_family = AF_INET;
      addr.sin_port = htons(static_cast<std::uint16_t>(server_->port()));
      addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
      ASSERT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
      (void)::send(fd, pipelined.data(), pipelined.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
      fds.push_back(fd);
    }
    // Until each client holds answers it has not read: the rest, far more than its window, waits
    // at the server's front end.
    for (int fd : fds) {
      int unread = 0;
      for (int k = 0; k < 200 && unread == 0; ++k) {
        if (::ioctl(fd, FIONREAD, &unread) != 0) break;
        if (unread == 0) std::this_thread::sleep_for(10ms);
      }
      ASSERT_GT(unread, 0) << "no answer came within 2 s";
    }
    for (int fd : fds) {
      const linger reset{1, 0};  // close with RST: the server's next send fails
      setsockopt(fd, SOL_SOCKET, SO_LINGER, &reset, sizeof reset);
      ::close(fd);
    }
  }
  EXPECT_EQ(get_json("/api/status")["mode"], "run");
}

TEST_F(WebServerTest, ARequestNotCompleteWithinItsDeadlineIs408AndClosed) {
  request_deadline_ms_ = 400;
  start();
  const int fd = connect_to(server_->port());
  ASSERT_GE(fd, 0);
  const std::string head = "GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: aaaaaaaaaaaaaaaaaaaa\r\n\r\n";
  const auto t0 = std::chrono::steady_clock::now();
  std::size_t sent = 0;
  for (; sent < head.size(); ++sent) {  // a byte every 50 ms: each one in time for a per-read timeout
    if (::send(fd, head.data() + sent, 1, MSG_NOSIGNAL) != 1) break;
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 50) > 0) break;  // answered (or closed) before the head was complete
  }
  const std::string answer = read_to_close(fd);
  const auto took = std::chrono::steady_clock::now() - t0;
  ::close(fd);
  EXPECT_LT(sent, head.size());
  EXPECT_EQ(answer.substr(0, answer.find("\r\n")), "HTTP/1.1 408 Request Timeout");
  EXPECT_NE(answer.find("deadline"), std::string::npos) << answer;
  EXPECT_GE(took, 350ms);
  EXPECT_LT(took, 1500ms);
  EXPECT_EQ(get_json("/api/status")["mode"], "run");  // the others are served as before
}

// The front end takes a chunked body as whole once its end marker has come. A marker inside a
// chunk's data fools it: the worker then finds the body short, and waits for the rest only briefly,
// not for the request's whole deadline, so such requests cannot hold the workers.
TEST_F(WebServerTest, AChunkedBodyShorterThanItsFramingHoldsAWorkerOnlyBriefly) {
  request_deadline_ms_ = 3000;
  start();
  const std::string head = "POST /api/setpoint HTTP/1.1\r\nHost: 127.0.0.1\r\nTransfer-Encoding: chunked\r\n\r\n";
  const auto [status, took] = raw_exchange(server_->port(), head + "20\r\nab\r\n0\r\n\r\n");  // 0x20 bytes declared, 9 sent
  EXPECT_EQ(status, "HTTP/1.1 408 Request Timeout");
  EXPECT_LT(took, 1000ms);
  const auto [whole, _] = raw_exchange(server_->port(), head + "2\r\n{}\r\n0\r\n\r\n");  // a whole chunked body
  EXPECT_NE(whole, "HTTP/1.1 408 Request Timeout");
  EXPECT_NE(whole, "connect failed");
}

TEST_F(WebServerTest, ARequestFarBeyondTheHeadCapIsCutUnreadWith431) {
  start();
  const int fd = connect_to(server_->port());
  ASSERT_GE(fd, 0);
  std::string huge = "GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Huge: " + std::string(200 * 1024, 'a') + "\r\n\r\n";
  (void)::send(fd, huge.data(), huge.size(), MSG_NOSIGNAL);  // the server may close before it has all
  const std::string answer = read_to_close(fd);
  ::close(fd);
  EXPECT_EQ(answer.substr(0, answer.find("\r\n")), "HTTP/1.1 431 Request Header Fields Too Large");
}

// The whole answer to `request` sent on a new connection from `from` (an address of 127/8).
std::string raw_answer(int port, const std::string& request, const char* from = "127.0.0.1") {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return "";
  sockaddr_in src{}, dst{};
  src.sin_family = dst.sin_family = AF_INET;
  ::inet_pton(AF_INET, from, &src.sin_addr);
  dst.sin_port = htons(static_cast<std::uint16_t>(port));
  dst.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  timeval tv{5, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&src), sizeof src) != 0 ||
      ::connect(fd, reinterpret_cast<sockaddr*>(&dst), sizeof dst) != 0) {
    ::close(fd);
    return "";
  }
  (void)::send(fd, request.data(), request.size(), MSG_NOSIGNAL);
  std::string all = read_to_close(fd);
  ::close(fd);
  return all;
}

std::string status_line(const std::string& answer) { return answer.substr(0, answer.find("\r\n")); }

bool has_header(const std::string& answer, const std::string& line) {
  return answer.substr(0, answer.find("\r\n\r\n") + 2).find("\r\n" + line + "\r\n") != std::string::npos;
}

// Every answer, the page's, the API's, an error and a refusal the server gives before httplib parses,
// says: not in a frame, no type sniffing, no referrer, and a content policy with no inline script.
TEST_F(WebServerTest, EveryAnswerCarriesTheSecurityHeaders) {
  start();
  const std::string connection_close = "Connection: close\r\n\r\n";
  std::string too_many = "GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\n";
  for (int i = 0; i < 80; ++i) too_many += "X-" + std::to_string(i) + ": y\r\n";
  for (const std::string& request :
       {"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n" + connection_close, "GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\n" + connection_close,
        "GET /nothing-here HTTP/1.1\r\nHost: 127.0.0.1\r\n" + connection_close,
        "GET /api/status HTTP/1.1\r\nHost: evil.example\r\n" + connection_close, too_many + "\r\n"}) {
    const std::string answer = raw_answer(server_->port(), request);
    ASSERT_FALSE(answer.empty()) << request;
    EXPECT_TRUE(has_header(answer, "X-Frame-Options: DENY")) << answer;
    EXPECT_TRUE(has_header(answer, "X-Content-Type-Options: nosniff")) << answer;
    EXPECT_TRUE(has_header(answer, "Referrer-Policy: no-referrer")) << answer;
    EXPECT_NE(answer.find("Content-Security-Policy: default-src 'self'; script-src 'self';"), std::string::npos) << answer;
    EXPECT_EQ(answer.find("unsafe-inline"), std::string::npos) << answer;
  }
}

// The page has no inline script or handler the content policy would block.
TEST_F(WebServerTest, ThePageHasNoInlineScript) {
  start();
  auto res = client_->Get("/");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->body.find("<script>"), std::string::npos);
  for (const char* handler : {" onsubmit=", " onclick=", " onload=", " onchange=", " oninput=", " style="})
    EXPECT_EQ(res->body.find(handler), std::string::npos) << handler;
}

// DNS rebinding: a page whose name resolves to the appliance sends its own name as Host.
TEST_F(WebServerTest, AHostThatIsNotThisMachineIsRefused421) {
  host_names_ = {"PLC-7.plant.example."};
  start();
  const auto status_for = [this](const std::string& host) {
    return status_line(raw_answer(server_->port(), "GET /api/status HTTP/1.1\r\nHost: " + host + "\r\nConnection: close\r\n\r\n"));
  };
  const std::string port = std::to_string(server_->port());
  for (const std::string& host : std::vector<std::string>{"127.0.0.1", "127.0.0.1:" + port, "127.9.9.9", "localhost", "LOCALHOST:" + port, "[::1]:" + port,
                                  "plc-7.plant.example", "plc-7.plant.example:" + port})
    EXPECT_EQ(status_for(host), "HTTP/1.1 200 OK") << host;
  for (const std::string& host : std::vector<std::string>{"evil.example", "evil.example:" + port, "plc-7", "8.8.8.8", "127.0.0.1.evil.example"})
    EXPECT_EQ(status_for(host), "HTTP/1.1 421 Misdirected Request") << host;
  const std::string refused =
      raw_answer(server_->port(), "GET /api/status HTTP/1.1\r\nHost: evil.example\r\nConnection: close\r\n\r\n");
  EXPECT_NE(refused.find("host_names"), std::string::npos) << refused;
  EXPECT_EQ(refused.find("\"mode\""), std::string::npos) << refused;
}

// The README's rule: more than 64 header fields are refused, 64 are not (Host counts as one).
TEST_F(WebServerTest, SixtyFourHeaderFieldsAreServedAndSixtyFiveRefused) {
  start();
  const auto head_with = [](int fields) {
    std::string h = "GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n";
    for (int i = 2; i < fields; ++i) h += "X-F" + std::to_string(i) + ": y\r\n";
    return h + "\r\n";
  };
  EXPECT_EQ(status_line(raw_answer(server_->port(), head_with(63))), "HTTP/1.1 200 OK");
  EXPECT_EQ(status_line(raw_answer(server_->port(), head_with(64))), "HTTP/1.1 200 OK");
  const std::string refused = raw_answer(server_->port(), head_with(65));
  EXPECT_EQ(status_line(refused), "HTTP/1.1 431 Request Header Fields Too Large");
  EXPECT_NE(refused.find("more than 64 header fields"), std::string::npos) << refused;
}

// The right token followed by a NUL and junk is not the token.
TEST_F(WebServerTest, TheTokenFollowedByNulAndJunkIsRefused) {
  start("a-token-of-sixteen-chars");
  const std::string body = R"({"setpoint_mm": 150})";
  const auto post_with = [&](const std::string& authorization) {
    return raw_answer(server_->port(), "POST /api/setpoint HTTP/1.1\r\nHost: 127.0.0.1\r\nAuthorization: " + authorization +
                                           "\r\nContent-Type: application/json\r\nContent-Length: " + std::to_string(body.size()) +
                                           "\r\nConnection: close\r\n\r\n" + body);
  };
  EXPECT_EQ(status_line(post_with(std::string("Bearer a-token-of-sixteen-chars\0junk", 37))), "HTTP/1.1 400 Bad Request");
  EXPECT_EQ(status_line(post_with(std::string("Bearer a-token-of-sixteen-chars\0", 32))), "HTTP/1.1 400 Bad Request");
  EXPECT_TRUE(queued().empty());
  EXPECT_EQ(status_line(post_with("Bearer a-token-of-sixteen-chars")), "HTTP/1.1 200 OK");
  EXPECT_EQ(status_line(post_with("bearer a-token-of-sixteen-chars")), "HTTP/1.1 200 OK");  // the scheme's case is free
  EXPECT_EQ(status_line(post_with("Basic a-token-of-sixteen-chars")), "HTTP/1.1 401 Unauthorized");
}

// One address holds at most 32 connections (the default): the 33rd is closed at once with 503,
// while another address is served as before.
TEST_F(WebServerTest, AnAddressPastItsConnectionCapIsRefusedAtOnce) {
  start();
  std::vector<int> held;
  for (int i = 0; i < 32; ++i) {
    const int fd = connect_to(server_->port());
    ASSERT_GE(fd, 0);
    held.push_back(fd);
  }
  epa::test::wait_until([&] { return epa::test::accept_queue_length(server_->port()) == 0; });  // accepted
  const auto t0 = std::chrono::steady_clock::now();
  const std::string refused = raw_answer(server_->port(), "GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 500ms);
  EXPECT_EQ(status_line(refused), "HTTP/1.1 503 Service Unavailable");
  EXPECT_NE(refused.find("too many connections from 127.0.0.1"), std::string::npos) << refused;
  EXPECT_EQ(status_line(raw_answer(server_->port(), "GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n",
                                   "127.0.0.2")),
            "HTTP/1.1 200 OK");
  for (int fd : held) ::close(fd);
}

// The page's files are read once, below static_dir, with no symlink followed and no hard link
// served: a link to the configuration placed there, before start or after, is never served.
TEST_F(WebServerTest, StaticFilesRefuseSymlinksAndHardLinksAndIgnoreLaterSwaps) {
  const epa::test::TempDir dir("static");
  const auto web = std::filesystem::path(EPA_SOURCE_DIR) / "web";
  for (const char* f : {"index.html", "app.js", "commands.js", "style.css"}) std::filesystem::copy_file(web / f, dir.path / f);
  const auto secret = dir.path.parent_path() / (dir.path.filename().string() + "-secret.toml");
  { std::ofstream(secret) << "token = \"the-secret-token-value\"\n"; }
  std::filesystem::create_symlink(secret, dir.path / "leak.js");
  const auto hard_target = dir.path / "hard-target.txt";  // not a page extension: never served itself
  { std::ofstream(hard_target) << "token = \"the-secret-token-value\"\n"; }
  std::filesystem::create_hard_link(hard_target, dir.path / "hard.js");
  static_dir_ = dir.path.string();
  start();
  for (const char* path : {"/leak.js", "/hard.js", "/hard-target.txt", "/../web/app.js", "/%2e%2e/web/app.js", "/sub/app.js"}) {
    auto res = client_->Get(path);
    ASSERT_TRUE(res) << path;
    EXPECT_EQ(res->status, 404) << path;
    EXPECT_EQ(res->body.find("the-secret-token-value"), std::string::npos) << path;
  }
  // Swapped for a symlink to the secret while serving: the page's own file is still what is served.
  std::filesystem::remove(dir.path / "app.js");
  std::filesystem::create_symlink(secret, dir.path / "app.js");
  for (int i = 0; i < 20; ++i) {
    auto res = client_->Get("/app.js");
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 200);
    EXPECT_EQ(res->body.find("the-secret-token-value"), std::string::npos);
  }
  std::filesystem::remove(secret);
}

TEST_F(WebServerTest, APageFileThatIsASymlinkStopsTheStartNamingIt) {
  const epa::test::TempDir dir("static");
  const auto web = std::filesystem::path(EPA_SOURCE_DIR) / "web";
  for (const char* f : {"index.html", "style.css"}) std::filesystem::copy_file(web / f, dir.path / f);
  std::filesystem::create_symlink(web / "app.js", dir.path / "app.js");
  epa::web::WebConfig config;
  config.address = "127.0.0.1";
  config.port = 0;
  config.static_dir = dir.path.string();
  auto server = epa::web::WebServer::start(config, channels_, nullptr, nullptr);
  ASSERT_FALSE(server.has_value());
  EXPECT_NE(server.error().message.find("app.js (a symbolic link"), std::string::npos) << server.error().message;
}

}  // namespace
