// The modbus-io backend against a real RemoteIoSimulator over 127.0.0.1 (free ports, bounded
// polling loops only), plus the register layout it shares with the simulator.
#include "hal/modbus_io_daq.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <new>
#include <thread>
#include <vector>

#include "core/paper_reference.hpp"
#include "plant/plant_adapter.hpp"
#include "rig/remote_io_simulator.hpp"

#include "../support/counting_new.hpp"  // the cycle calls must allocate nothing

namespace epa::hal {
namespace {

using rig::RemoteIoSimulator;
using rig::RemoteIoSimulatorConfig;

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;
constexpr double kCountV = kDefaultVoltsPerCount;  // one int16 count, V

double elapsed_ms(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// Bounded polling: true as soon as done() holds, false after max_wait.
template <typename F>
bool poll_until(F done, std::chrono::milliseconds max_wait = 2000ms) {
  const auto deadline = Clock::now() + max_wait;
  while (Clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(1ms);
  }
  return done();
}

RemoteIoSimulatorConfig sim_config(int port = 0, RemoteIoLayout layout = default_remote_io_layout()) {
  RemoteIoSimulatorConfig c;
  c.port = port;
  c.layout = layout;
  c.model = core::paper::model();
  c.plant.initial_position_mm = 100.0;  // 2.0 V
  return c;
}

std::unique_ptr<RemoteIoSimulator> start_sim(const RemoteIoSimulatorConfig& c) {
  auto sim = RemoteIoSimulator::start(c);
  EXPECT_TRUE(sim.has_value()) << sim.error().message;
  return sim ? std::move(*sim) : nullptr;
}

ModbusIoConfig daq_config(int port, RemoteIoLayout layout = default_remote_io_layout()) {
  ModbusIoConfig c;
  c.port = port;
  c.layout = layout;
  c.response_timeout_ms = 250;  // functional tests: generous for a loaded CI machine; bound tests set their own
  return c;
}

// ---- layout --------------------------------------------------------------------------------

TEST(RemoteIoLayout, Int16RoundTripsWithinHalfACount) {
  const AnalogPoint p = default_remote_io_layout().sensor;
  for (double v : {-9.99, -2.0, 0.0, 1.234, 2.0, 5.0, 9.99}) {
    const auto back = decode_volts(p, encode_volts(p, v));
    ASSERT_TRUE(back.has_value());
    EXPECT_NEAR(*back, v, kCountV / 2 + 1e-12) << v;
  }
}

TEST(RemoteIoLayout, Int16RoundsToTheNearestCountAndAppliesTheOffset) {
  AnalogPoint p{.volts_per_count = 0.5, .offset_v = 0.0};
  EXPECT_EQ(encode_volts(p, 0.74)[0], 1);       // 1.48 counts
  EXPECT_EQ(encode_volts(p, 0.76)[0], 2);       // 1.52 counts
  EXPECT_EQ(encode_volts(p, -0.76)[0], 0xFFFE); // -2 counts, two's complement
  p.offset_v = 1.0;
  EXPECT_EQ(encode_volts(p, 2.0)[0], 2);        // (2 - 1) / 0.5
  EXPECT_DOUBLE_EQ(*decode_volts(p, {0xFFFE, 0}), 0.0);  // -2 * 0.5 + 1
}

TEST(RemoteIoLayout, Int16ClampsAtFullScaleAndNeverWritesMinus32768) {
  const AnalogPoint p = default_remote_io_layout().valve;
  EXPECT_EQ(encode_volts(p, 10.0)[0], 0x7FFF);   // exactly full scale
  EXPECT_EQ(encode_volts(p, 12.5)[0], 0x7FFF);   // clamped
  EXPECT_EQ(encode_volts(p, -10.0)[0], 0x8001);  // -32767
  EXPECT_EQ(encode_volts(p, -99.0)[0], 0x8001);  // clamped to -32767, not -32768
  EXPECT_EQ(encode_volts(p, std::nan(""))[0], 0);  // non-finite: the centred valve
  EXPECT_DOUBLE_EQ(*decode_volts(p, {0x7FFF, 0}), 10.0);
  EXPECT_NEAR(*decode_volts(p, {0x8000, 0}), -32768 * kCountV, 1e-12);  // read as it comes
}

TEST(RemoteIoLayout, Float32FollowsTheWordOrderTestVectors) {
  AnalogPoint p{.table = RegisterTable::kHolding, .encoding = AnalogEncoding::kFloat32};
  p.word_order = core::WordOrder::kABCD;
  EXPECT_EQ(encode_volts(p, 123456.0), (PointWords{0x47F1, 0x2000}));
  EXPECT_DOUBLE_EQ(*decode_volts(p, {0x47F1, 0x2000}), 123456.0);
  p.word_order = core::WordOrder::kCDAB;
  EXPECT_EQ(encode_volts(p, 123456.0), (PointWords{0x2000, 0x47F1}));
  EXPECT_DOUBLE_EQ(*decode_volts(p, {0x2000, 0x47F1}), 123456.0);
  EXPECT_DOUBLE_EQ(*decode_volts(p, encode_volts(p, 2.5)), 2.5);
  EXPECT_NEAR(*decode_volts(p, encode_volts(p, 1.234)), 1.234, 1e-6);  // float precision
}

TEST(RemoteIoLayout, DecodingANonFiniteFloatIsAnError) {
  const AnalogPoint p{.encoding = AnalogEncoding::kFloat32, .word_order = core::WordOrder::kABCD};
  EXPECT_FALSE(decode_volts(p, {0x7FC0, 0x0000}).has_value());  // NaN
  EXPECT_FALSE(decode_volts(p, {0x7F80, 0x0000}).has_value());  // +inf
  EXPECT_FALSE(decode_volts(p, {0xFF80, 0x0000}).has_value());  // -inf
  EXPECT_EQ(encode_volts(p, std::nan("")), (PointWords{0, 0}));  // never NaN on the wire
}

TEST(RemoteIoLayout, DefaultIsValidInputAndHoldingRegisterZero) {
  const RemoteIoLayout l = default_remote_io_layout();
  EXPECT_TRUE(validate(l).has_value());
  EXPECT_EQ(l.sensor.table, RegisterTable::kInput);
  EXPECT_EQ(l.valve.table, RegisterTable::kHolding);
  EXPECT_EQ(l.sensor.address, 0);
  EXPECT_EQ(l.valve.address, 0);
  EXPECT_DOUBLE_EQ(l.sensor.volts_per_count, 10.0 / 32767);
}

TEST(RemoteIoLayout, ValidateNamesTheField) {
  struct Case {
    const char* field;
    void (*spoil)(RemoteIoLayout&);
  };
  const Case cases[] = {
      {"sensor.address", [](RemoteIoLayout& l) { l.sensor.address = -1; }},
      {"valve.address", [](RemoteIoLayout& l) { l.valve.address = 65536; }},
      {"valve.address", [](RemoteIoLayout& l) { l.valve.encoding = AnalogEncoding::kFloat32, l.valve.address = 65535; }},
      {"sensor.volts_per_count", [](RemoteIoLayout& l) { l.sensor.volts_per_count = 0.0; }},
      {"valve.volts_per_count", [](RemoteIoLayout& l) { l.valve.volts_per_count = std::nan(""); }},
      {"sensor.offset_v", [](RemoteIoLayout& l) { l.sensor.offset_v = INFINITY; }},
      {"valve.table", [](RemoteIoLayout& l) { l.valve.table = RegisterTable::kInput, l.sensor.address = 5; }},
      {"overlap", [](RemoteIoLayout& l) {  // float32 sensor in holding 0-1, valve in holding 1
         l.sensor.table = RegisterTable::kHolding, l.sensor.encoding = AnalogEncoding::kFloat32, l.valve.address = 1;
       }},
  };
  for (const Case& c : cases) {
    RemoteIoLayout l = default_remote_io_layout();
    c.spoil(l);
    const auto s = validate(l);
    ASSERT_FALSE(s.has_value()) << "expected an error naming " << c.field;
    EXPECT_NE(s.error().message.find(c.field), std::string::npos) << s.error().message;
  }
  RemoteIoLayout adjacent = default_remote_io_layout();  // holding 0-1 and 2: no overlap
  adjacent.sensor.table = RegisterTable::kHolding, adjacent.sensor.encoding = AnalogEncoding::kFloat32;
  adjacent.valve.address = 2;
  EXPECT_TRUE(validate(adjacent).has_value());
}

TEST(ModbusIoConfig, ValidateNamesTheField) {
  struct Case {
    const char* expected;
    void (*spoil)(ModbusIoConfig&);
  };
  const Case cases[] = {
      {"port 0", [](ModbusIoConfig& c) { c.port = 0; }},
      {"unit id 248", [](ModbusIoConfig& c) { c.unit_id = 248; }},
      {"response timeout 0 ms", [](ModbusIoConfig& c) { c.response_timeout_ms = 0; }},
      {"host 'io-module.local'", [](ModbusIoConfig& c) { c.host = "io-module.local"; }},
      {"valve.table", [](ModbusIoConfig& c) { c.layout.valve.table = RegisterTable::kInput, c.layout.valve.address = 4; }},
  };
  EXPECT_TRUE(validate(ModbusIoConfig{}).has_value());
  for (const Case& c : cases) {
    ModbusIoConfig config;
    c.spoil(config);
    const auto s = validate(config);
    ASSERT_FALSE(s.has_value()) << "expected " << c.expected;
    EXPECT_NE(s.error().message.find(c.expected), std::string::npos) << s.error().message;
  }
}

// ---- the client against the simulator ----------------------------------------------------------

TEST(ModbusIoDaq, OpenToAClosedPortFailsNamingHostAndPort) {
  int port = 0;
  {
    auto sim = start_sim(sim_config());
    ASSERT_NE(sim, nullptr);
    port = sim->port();
  }  // stopped: nothing listens there any more
  ModbusIoDaq daq(daq_config(port));
  const auto s = daq.open();
  ASSERT_FALSE(s.has_value());
  EXPECT_NE(s.error().message.find("127.0.0.1:" + std::to_string(port)), std::string::npos) << s.error().message;
  EXPECT_NE(s.error().message.find("Connection refused"), std::string::npos) << s.error().message;
  EXPECT_FALSE(daq.connected());
  EXPECT_EQ(daq.read_sensor().status, IoStatus::kError);  // never opened: an error, not a crash
}

// libmodbus 3.1.6 connects on a non-blocking socket and waits for the handshake at most the
// response timeout. A listener whose accept queue is full drops our SYN, so the handshake never
// completes; open() must still come back within a few timeouts.
TEST(ModbusIoDaq, OpenGivesUpWithinTheResponseTimeoutWhenNobodyCompletesTheHandshake) {
  const int listener = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(listener, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  ASSERT_EQ(listen(listener, 0), 0);
  socklen_t len = sizeof addr;
  ASSERT_EQ(getsockname(listener, reinterpret_cast<sockaddr*>(&addr), &len), 0);
  std::vector<int> fillers;  // fill the accept queue until a connect stays pending
  for (int i = 0; i < 8; ++i) {
    const int fd = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK, 0);
    fillers.push_back(fd);
    connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
    pollfd p{fd, POLLOUT, 0};
    if (poll(&p, 1, 20) == 0) break;  // this one is stuck: the queue is full
  }
  ModbusIoConfig c = daq_config(ntohs(addr.sin_port));
  c.response_timeout_ms = 2;
  ModbusIoDaq daq(c);
  const auto t0 = Clock::now();
  const auto s = daq.open();
  const double took_ms = elapsed_ms(t0);
  for (int fd : fillers) close(fd);
  close(listener);
  ASSERT_FALSE(s.has_value());
  EXPECT_LT(took_ms, 100.0);
  EXPECT_NE(s.error().message.find("no answer within 2 ms"), std::string::npos) << s.error().message;
  RecordProperty("open_ms", std::to_string(took_ms));
}

TEST(ModbusIoDaq, ReadsTheSimulatedPositionInSensorVolts) {
  auto sim = start_sim(sim_config());
  ASSERT_NE(sim, nullptr);
  ModbusIoDaq daq(daq_config(sim->port()));
  ASSERT_TRUE(daq.open().has_value());
  EXPECT_NE(daq.describe().find("127.0.0.1:" + std::to_string(sim->port())), std::string::npos) << daq.describe();
  for (int k = 0; k < 10; ++k) {
    const SensorReading r = daq.read_sensor();
    ASSERT_EQ(r.status, IoStatus::kOk);
    EXPECT_NEAR(r.sensor_v, 2.0, kCountV);  // 100 mm at 50 mm/V, within one count
  }
  EXPECT_EQ(daq.failed_requests(), 0u);
}

TEST(ModbusIoDaq, WritingThreeVoltsMovesTheSimulatedPistonUp) {
  auto sim = start_sim(sim_config());
  ASSERT_NE(sim, nullptr);
  ModbusIoDaq daq(daq_config(sim->port()));
  ASSERT_TRUE(daq.open().has_value());
  ASSERT_EQ(daq.write_valve(3.0), IoStatus::kOk);
  EXPECT_TRUE(poll_until([&] { return sim->position_mm() > 110.0; })) << sim->position_mm();
  EXPECT_TRUE(poll_until([&] { auto r = daq.read_sensor(); return r.status == IoStatus::kOk && r.sensor_v > 2.2; }));

  modbus_t* raw = modbus_new_tcp("127.0.0.1", sim->port());  // the register holds the scaled command
  ASSERT_NE(raw, nullptr);
  ASSERT_EQ(modbus_connect(raw), 0);
  std::uint16_t reg = 0;
  ASSERT_EQ(modbus_read_registers(raw, 0, 1, &reg), 1);
  EXPECT_EQ(reg, static_cast<std::uint16_t>(std::lround(3.0 / kCountV)));
  EXPECT_EQ(daq.write_valve(std::nan("")), IoStatus::kError);  // written as 0 V, reported
  ASSERT_EQ(modbus_read_registers(raw, 0, 1, &reg), 1);
  EXPECT_EQ(reg, 0);
  modbus_close(raw);
  modbus_free(raw);
}

// A physics plant's parameters changed from another thread while the plant thread steps (TSan
// runs this): friction no drive can overcome stops the piston; the Hammerstein plant refuses.
TEST(RemoteIoSimulator, PhysicsChangedWhileRunningTakeEffectAndTheHammersteinPlantRefuses) {
  auto physics = plant::make_pneumatic_simulator({}, {.initial_position_mm = 100.0});
  ASSERT_TRUE(physics);
  auto started = RemoteIoSimulator::start(sim_config(), std::move(*physics));
  ASSERT_TRUE(started) << started.error().message;
  auto& sim = **started;
  ModbusIoDaq daq(daq_config(sim.port()));
  ASSERT_TRUE(daq.open().has_value());
  ASSERT_EQ(daq.write_valve(5.0), IoStatus::kOk);
  EXPECT_TRUE(poll_until([&] { return sim.position_mm() > 110.0; })) << sim.position_mm();
  ASSERT_EQ(daq.write_valve(0.0), IoStatus::kOk);
  for (const auto& [key, value] : {std::pair{"stribeck_velocity_mps", 0.2}, {"static_friction_n", 2000.0}, {"coulomb_friction_n", 2000.0}}) {
    const auto s = sim.change_physics(key, value);
    ASSERT_TRUE(s) << key << ": " << s.error().message;
  }
  EXPECT_FALSE(sim.change_physics("supply_pressure_bar", 40.0));  // out of range: refused, nothing changes
  const std::uint64_t steps_then = sim.steps();
  ASSERT_TRUE(poll_until([&] { return sim.steps() >= steps_then + 2; }));  // taken at the next step
  const double held_mm = sim.position_mm();
  ASSERT_EQ(daq.write_valve(-5.0), IoStatus::kOk);
  EXPECT_FALSE(poll_until([&] { return std::abs(sim.position_mm() - held_mm) > 0.5; }, 300ms)) << sim.position_mm();

  auto hammerstein = start_sim(sim_config());
  ASSERT_NE(hammerstein, nullptr);
  const auto refused = hammerstein->change_physics("supply_pressure_bar", 4.5);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("Hammerstein"), std::string::npos) << refused.error().message;
}

TEST(ModbusIoDaq, FailsFastWhenTheModuleGoesAwayAndReconnectsWithinTheInterval) {
  auto sim = start_sim(sim_config());
  ASSERT_NE(sim, nullptr);
  const int port = sim->port();
  ModbusIoDaq daq(daq_config(port));
  const int interval = daq.config().reconnect_interval_cycles;
  ASSERT_EQ(interval, 200);
  ASSERT_TRUE(daq.open().has_value());
  ASSERT_EQ(daq.read_sensor().status, IoStatus::kOk);

  sim->stop();
  auto t0 = Clock::now();
  const SensorReading lost = daq.read_sensor();
  EXPECT_LT(elapsed_ms(t0), 100.0);
  EXPECT_NE(lost.status, IoStatus::kOk);
  EXPECT_EQ(daq.failed_requests(), 1u);
  EXPECT_FALSE(daq.connected());
  EXPECT_EQ(daq.write_valve(1.0), IoStatus::kError);  // no request while disconnected

  // 600 calls to a dead module. Attempts after waits of 1, 2, 4, ..., 128, 200 calls: at the
  // cumulative calls 1, 3, 7, 15, 31, 63, 127, 255, 455 (the next, 655, is past the end): 9.
  t0 = Clock::now();
  for (int k = 0; k < 3 * interval; ++k) ASSERT_EQ(daq.read_sensor().status, IoStatus::kError);
  EXPECT_EQ(daq.connect_attempts(), 9u);
  EXPECT_LT(elapsed_ms(t0), 100.0);

  sim = start_sim(sim_config(port));  // the module comes back on the same port
  ASSERT_NE(sim, nullptr);
  int calls = 0;
  bool ok = false;
  while (!ok && calls < 3 * interval) {
    ++calls;
    ok = daq.read_sensor().status == IoStatus::kOk;
  }
  EXPECT_TRUE(ok);
  EXPECT_LE(calls, interval + 1);  // the reconnecting call itself does not read
  EXPECT_EQ(daq.reconnects(), 1u);
  EXPECT_EQ(daq.write_valve(0.0), IoStatus::kOk);
}

TEST(ModbusIoDaq, CycleCallsAllocateNothingConnectedLostOrReconnecting) {
  auto sim = start_sim(sim_config());
  ASSERT_NE(sim, nullptr);
  const int port = sim->port();
  ModbusIoConfig c = daq_config(port);
  c.reconnect_interval_cycles = 10;
  ModbusIoDaq daq(c);
  ASSERT_TRUE(daq.open().has_value());
  int ok = 0;
  long before = epa::testing::allocation_count();
  for (int k = 0; k < 100; ++k) {
    ok += daq.read_sensor().status == IoStatus::kOk;
    ok += daq.write_valve(0.5 * std::sin(0.1 * k)) == IoStatus::kOk;
  }
  EXPECT_EQ(epa::testing::allocation_count() - before, 0) << "connected";
  EXPECT_EQ(ok, 200);
  sim->stop();
  before = epa::testing::allocation_count();
  for (int k = 0; k < 50; ++k) {  // the loss, then a connect attempt every 10 calls to a closed port
    daq.read_sensor();
    daq.write_valve(0.0);
  }
  EXPECT_EQ(epa::testing::allocation_count() - before, 0) << "disconnected";
  // After the loss (call 1), waits of 1, 2, 4, 8, 10, 10, ...: attempts at the 1st, 3rd, 7th,
  // 15th, 25th, 35th and 45th of the 49 calls that follow.
  EXPECT_EQ(daq.connect_attempts(), 7u);
  sim = start_sim(sim_config(port));
  ASSERT_NE(sim, nullptr);
  before = epa::testing::allocation_count();
  ok = 0;
  for (int k = 0; k < 20; ++k) ok += daq.read_sensor().status == IoStatus::kOk;
  EXPECT_EQ(epa::testing::allocation_count() - before, 0) << "reconnecting";
  EXPECT_GE(ok, 9);  // reconnected within the interval of 10 cycles
}

// A one-client Modbus module on a free loopback port whose answers the test scripts: before
// request n (from 1) is answered, `script(n)` runs (it may sleep, as a slow module would) and
// returns false to leave that request unanswered. Input register 0 holds `input0`.
class ScriptedModule {
 public:
  ScriptedModule(std::function<bool(int)> script, std::uint16_t input0) : script_(std::move(script)) {
    server_ = modbus_new_tcp("127.0.0.1", 0);
    listener_ = server_ ? modbus_tcp_listen(server_, 1) : -1;
    sockaddr_in addr{};
    socklen_t len = sizeof addr;
    if (listener_ >= 0 && getsockname(listener_, reinterpret_cast<sockaddr*>(&addr), &len) == 0) port_ = ntohs(addr.sin_port);
    mapping_ = modbus_mapping_new(0, 0, 1, 1);
    mapping_->tab_input_registers[0] = input0;
    if (port_ > 0) thread_ = std::thread([this] { serve(); });
  }
  ~ScriptedModule() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    if (server_) modbus_close(server_);
    if (listener_ >= 0) close(listener_);
    modbus_mapping_free(mapping_);
    if (server_) modbus_free(server_);
  }
  int port() const { return port_; }  // 0: could not listen

 private:
  void serve() {
    for (pollfd p{listener_, POLLIN, 0}; poll(&p, 1, 20) <= 0;)
      if (stop_.load()) return;
    if (modbus_tcp_accept(server_, &listener_) < 0) return;
    // Like the simulator and real modules: answers leave at once. Without this, Nagle's algorithm
    // holds each small answer until the previous one is acknowledged, and a lag never clears.
    const int one = 1;
    setsockopt(modbus_get_socket(server_), IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    std::uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
    for (int request = 1; !stop_.load();) {
      pollfd p{modbus_get_socket(server_), POLLIN, 0};
      if (poll(&p, 1, 20) <= 0) continue;
      const int n = modbus_receive(server_, query);
      if (n < 0) break;
      if (script_(request++)) modbus_reply(server_, query, n, mapping_);
    }
  }

  std::function<bool(int)> script_;
  modbus_t* server_ = nullptr;
  int listener_ = -1, port_ = 0;
  modbus_mapping_t* mapping_ = nullptr;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// A module that answers open()'s first request and then stays silent: the next read must give
// kTimeout after about the response timeout, not block.
TEST(ModbusIoDaq, ReadReportsTimeoutWithinTheResponseTimeoutWhenTheModuleFallsSilent) {
  ScriptedModule module([](int request) { return request == 1; }, 0);
  ASSERT_GT(module.port(), 0);
  ModbusIoConfig c = daq_config(module.port());
  c.response_timeout_ms = 50;  // not 2 ms: open()'s first answer needs this test's thread to wake up
  ModbusIoDaq daq(c);
  const auto opened = daq.open();
  const auto t0 = Clock::now();
  const SensorReading r = opened ? daq.read_sensor() : SensorReading{};
  const double took_ms = elapsed_ms(t0);
  ASSERT_TRUE(opened.has_value()) << opened.error().message;
  EXPECT_EQ(r.status, IoStatus::kTimeout);
  EXPECT_TRUE(daq.connected());  // one late answer costs a sample, not the link
  EXPECT_EQ(daq.connect_attempts(), 0u);
  EXPECT_GE(took_ms, 49.0);
  EXPECT_LT(took_ms, 150.0);
  EXPECT_EQ(daq.failed_requests(), 1u);
  RecordProperty("timeout_read_ms", std::to_string(took_ms));
}

// A module that answers one request late (after the DAQ gave up on it) and then normally: the
// late answer must not cascade into the following requests. At most the late request and the
// one after it fail; the link stays up; then every request succeeds again. (Flushing right at
// the failure would miss the next answer, still 1 ms away, and every later request would read
// its predecessor's answer.)
TEST(ModbusIoDaq, OneLateAnswerCostsAtMostTwoRequestsAndKeepsTheLink) {
  // 1 ms to answer, as a module's firmware takes; request 3 is answered late, past the timeout.
  ScriptedModule module(
      [](int request) {
        std::this_thread::sleep_for(std::chrono::milliseconds(request == 3 ? 30 : 1));
        return true;
      },
      6553);  // 2.0 V
  ASSERT_GT(module.port(), 0);
  ModbusIoConfig c = daq_config(module.port());
  c.response_timeout_ms = 20;
  ModbusIoDaq daq(c);
  const auto opened = daq.open();  // request 1
  std::vector<IoStatus> statuses;
  for (int k = 0; k < 12 && opened; ++k) {
    statuses.push_back(daq.read_sensor().status);  // request 2, 3 (late), 4, ...
    std::this_thread::sleep_for(std::chrono::milliseconds(5));  // the scan period between requests
  }
  ASSERT_TRUE(opened.has_value()) << opened.error().message;
  ASSERT_EQ(statuses.size(), 12u);
  EXPECT_EQ(statuses[0], IoStatus::kOk);
  EXPECT_EQ(statuses[1], IoStatus::kTimeout);
  EXPECT_LE(daq.failed_requests(), 2u);
  for (std::size_t k = 3; k < statuses.size(); ++k) EXPECT_EQ(statuses[k], IoStatus::kOk) << "request " << k + 2;
  EXPECT_EQ(daq.connect_attempts(), 0u);
}

TEST(ModbusIoDaq, ASecondClientIsServedAtTheSameTime) {
  auto sim = start_sim(sim_config());
  ASSERT_NE(sim, nullptr);
  ModbusIoDaq first(daq_config(sim->port())), second(daq_config(sim->port()));
  ASSERT_TRUE(first.open().has_value());
  ASSERT_TRUE(second.open().has_value());
  EXPECT_EQ(sim->clients(), 2);
  for (int k = 0; k < 20; ++k) {
    EXPECT_EQ(first.read_sensor().status, IoStatus::kOk);
    const SensorReading r = second.read_sensor();
    EXPECT_EQ(r.status, IoStatus::kOk);
    EXPECT_NEAR(r.sensor_v, 2.0, kCountV);
  }
}

TEST(ModbusIoDaq, AnotherUnitIdGetsGatewayTargetException) {
  auto sim = start_sim(sim_config());
  ASSERT_NE(sim, nullptr);
  modbus_t* raw = modbus_new_tcp("127.0.0.1", sim->port());
  ASSERT_NE(raw, nullptr);
  ASSERT_EQ(modbus_connect(raw), 0);
  modbus_set_response_timeout(raw, 0, 500'000);
  std::uint16_t reg = 0;
  EXPECT_EQ(modbus_read_input_registers(raw, 0, 1, &reg), 1);  // libmodbus' default unit 0xFF: served
  modbus_set_slave(raw, 7);
  EXPECT_EQ(modbus_read_input_registers(raw, 0, 1, &reg), -1);
  EXPECT_EQ(errno, EMBXGTAR);
  modbus_set_slave(raw, 1);  // same connection, right unit: answered
  EXPECT_EQ(modbus_read_input_registers(raw, 0, 1, &reg), 1);
  EXPECT_EQ(reg, static_cast<std::uint16_t>(std::lround(2.0 / kCountV)));
  modbus_close(raw);
  modbus_free(raw);

  ModbusIoConfig c = daq_config(sim->port());
  c.unit_id = 7;
  ModbusIoDaq daq(c);
  const auto s = daq.open();  // open() reads once, so the wrong unit id shows here
  ASSERT_FALSE(s.has_value());
  EXPECT_NE(s.error().message.find("(unit 7)"), std::string::npos) << s.error().message;
  EXPECT_NE(s.error().message.find("Target device failed to respond"), std::string::npos) << s.error().message;
}

TEST(ModbusIoDaq, OpenNamesAnAddressTheModuleDoesNotHave) {
  auto sim = start_sim(sim_config());
  ASSERT_NE(sim, nullptr);
  RemoteIoLayout wrong = default_remote_io_layout();
  wrong.sensor.address = 8;
  ModbusIoDaq daq(daq_config(sim->port(), wrong));
  const auto s = daq.open();
  ASSERT_FALSE(s.has_value());
  EXPECT_NE(s.error().message.find("input register 8"), std::string::npos) << s.error().message;
  EXPECT_NE(s.error().message.find("Illegal data address"), std::string::npos) << s.error().message;
}

TEST(ModbusIoDaq, Float32LayoutWorksEndToEnd) {
  RemoteIoLayout layout;
  layout.sensor = {.table = RegisterTable::kInput, .address = 10, .encoding = AnalogEncoding::kFloat32,
                   .word_order = core::WordOrder::kCDAB};
  layout.valve = {.table = RegisterTable::kHolding, .address = 20, .encoding = AnalogEncoding::kFloat32,
                  .word_order = core::WordOrder::kCDAB};
  auto sim = start_sim(sim_config(0, layout));
  ASSERT_NE(sim, nullptr);
  ModbusIoDaq daq(daq_config(sim->port(), layout));
  ASSERT_TRUE(daq.open().has_value());
  const SensorReading r = daq.read_sensor();
  ASSERT_EQ(r.status, IoStatus::kOk);
  EXPECT_NEAR(r.sensor_v, 2.0, 1e-6);
  ASSERT_EQ(daq.write_valve(-3.0), IoStatus::kOk);
  EXPECT_TRUE(poll_until([&] { return sim->position_mm() < 90.0; })) << sim->position_mm();
}

TEST(RemoteIoSimulator, SurvivesAGarbageClientAndRefusesABusyPort) {
  auto sim = start_sim(sim_config());
  ASSERT_NE(sim, nullptr);
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(sim->port()));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  const char garbage[] = "GET / HTTP/1.0\r\n\r\n\xff\xff\xff\xff\xff\xff\xff\xff";
  ASSERT_GT(send(fd, garbage, sizeof garbage, MSG_NOSIGNAL), 0);
  close(fd);
  EXPECT_TRUE(poll_until([&] { return sim->clients() == 0; }));
  ModbusIoDaq daq(daq_config(sim->port()));
  ASSERT_TRUE(daq.open().has_value());
  EXPECT_EQ(daq.read_sensor().status, IoStatus::kOk);

  auto second = RemoteIoSimulator::start(sim_config(sim->port()));
  ASSERT_FALSE(second.has_value());
  const std::string& message = second.error().message;
  EXPECT_NE(message.find(":" + std::to_string(sim->port())), std::string::npos) << message;
  EXPECT_NE(message.find("in use"), std::string::npos) << message;
}

// How a module's plant steps fall in a master's cycles: the master writes the valve every 20 ms and
// looks at the step count a quarter and three quarters of a period later, for 30 cycles at each of
// two phases half a period apart. A cycle "lands" when no step came between the write and the first
// look and exactly one between the two looks. A cycle is judged only when every look, and the write
// before it, was on time (within kLate), and when the module's plant thread was not itself late at
// a look: a thread that wakes late on a loaded machine (on CI, with the diagnosis's self-check on
// both cores) says nothing about the schedule it keeps. A step that comes late is told from one
// that is due late by the module's next_step_due(): late, it was due before the look.
struct MasterPhaseTally {
  int shift_ms = 0, judged = 0, landed = 0;
};

// A module with a 20 ms period, synchronised to valve writes or free-running, and the tally at each
// of the master's two phases; empty (with the failure recorded) when the module does not start.
// Fails too when a thread woke late so often that fewer than half the cycles could be judged.
std::vector<MasterPhaseTally> tally_steps_in_master_cycles(bool synchronised) {
  RemoteIoSimulatorConfig c = sim_config();
  c.model.Ts = 0.020;
  c.sync_to_valve_writes = synchronised;
  auto sim = start_sim(c);
  ModbusIoDaq daq(daq_config(sim ? sim->port() : 0));
  if (!sim || !daq.open().has_value()) {
    ADD_FAILURE() << "the module did not start or the master could not reach it";
    return {};
  }
  constexpr int kCycles = 30, kLockCycles = 3;
  constexpr auto kLate = 2ms;
  std::vector<MasterPhaseTally> tallies;
  auto cycle_start = Clock::now() + 7ms;
  for (const auto phase_shift : {0ms, 10ms}) {
    cycle_start += phase_shift;
    MasterPhaseTally tally{.shift_ms = static_cast<int>(phase_shift.count())};
    for (int k = 0; k < kCycles; ++k, cycle_start += 20ms) {
      bool late = false;
      // The module's due time is read before its count: a step that comes between the two reads
      // is then either counted or excused, never missed unexcused.
      auto look = [&](Clock::time_point due) {
        const auto module_due = sim->next_step_due();
        const auto steps = sim->steps();
        const auto now = Clock::now();
        late = late || now - due > kLate || now - module_due > kLate;
        return steps;
      };
      std::this_thread::sleep_until(cycle_start);
      if (daq.write_valve(0.0) != IoStatus::kOk) {
        ADD_FAILURE() << "valve write failed in cycle " << k;
        return {};
      }
      const auto at_write = look(cycle_start);
      std::this_thread::sleep_until(cycle_start + 5ms);
      const auto quarter = look(cycle_start + 5ms);
      std::this_thread::sleep_until(cycle_start + 15ms);
      const auto three_quarters = look(cycle_start + 15ms);
      if (k < kLockCycles || late) continue;
      ++tally.judged;
      if (quarter == at_write && three_quarters == at_write + 1) ++tally.landed;
    }
    EXPECT_GE(tally.judged, (kCycles - kLockCycles) / 2) << "phase shift " << tally.shift_ms << " ms: a thread woke late too often to judge";
    tallies.push_back(tally);
  }
  return tallies;
}

// A synchronised module steps half a period after each valve write, whatever the phase of the
// master's clock: every master cycle sees exactly one step, and it lands between its write and the
// next read. A 20 ms period leaves 5 ms of slack either side.
TEST(RemoteIoSimulator, SynchronisedStepsLandHalfAPeriodAfterEachValveWrite) {
  const auto tallies = tally_steps_in_master_cycles(true);
  ASSERT_EQ(tallies.size(), 2u);
  for (const MasterPhaseTally& t : tallies)
    EXPECT_EQ(t.landed, t.judged) << "phase shift " << t.shift_ms << " ms: " << t.landed << " of " << t.judged;
}

// The check above can fail: a free-running module keeps one phase, so at one of the master's two
// phases (half a period apart) its steps fall outside the window between the looks, or on its
// edges, in many cycles.
TEST(RemoteIoSimulator, AFreeRunningModuleFailsTheSynchronisedCheckAtOnePhase) {
  const auto tallies = tally_steps_in_master_cycles(false);
  ASSERT_EQ(tallies.size(), 2u);
  int worst_missed = 0;
  for (const MasterPhaseTally& t : tallies) worst_missed = std::max(worst_missed, t.judged - t.landed);
  EXPECT_GE(worst_missed, 27 / 4) << "a free-running module landed in nearly every cycle at both phases";
}

TEST(RemoteIoSimulator, StepsInRealTimeAndStopsPromptly) {
  auto sim = start_sim(sim_config());
  ASSERT_NE(sim, nullptr);
  const auto t0 = Clock::now();
  ASSERT_TRUE(poll_until([&] { return sim->steps() >= 40; }));
  const double took_ms = elapsed_ms(t0);
  EXPECT_GE(took_ms, 40 * 5.0 - 5.0);  // not faster than Ts = 5 ms per step
  const auto t1 = Clock::now();
  sim->stop();
  EXPECT_LT(elapsed_ms(t1), 200.0);
  const auto steps = sim->steps();
  sim->stop();  // idempotent
  EXPECT_EQ(sim->steps(), steps);
  EXPECT_DOUBLE_EQ(sim->position_mm(), 100.0);  // valve at 0 V: at rest
}

// `epa plant-server` with the physics plant: the same Modbus face, a different plant behind it.
TEST(RemoteIoSimulator, ServesThePhysicsPlant) {
  auto plant = plant::make_pneumatic_simulator({}, {.initial_position_mm = 100.0, .Ts = 0.002, .substeps = 20});
  ASSERT_TRUE(plant.has_value()) << plant.error().message;
  auto started = RemoteIoSimulator::start(sim_config(), std::move(*plant));
  ASSERT_TRUE(started.has_value()) << started.error().message;
  auto& sim = *started;
  ModbusIoDaq daq(daq_config(sim->port()));
  ASSERT_TRUE(daq.open().has_value());
  const SensorReading r = daq.read_sensor();
  ASSERT_EQ(r.status, IoStatus::kOk);
  EXPECT_NEAR(r.sensor_v, 2.0, kCountV);  // 100 mm of 500 mm over 0-10 V
  // Counted from here: the plant has been stepping since start, and on a loaded machine the
  // open and the first read can take several of its periods.
  const auto steps0 = sim->steps();
  const auto t0 = Clock::now();
  ASSERT_TRUE(poll_until([&] { return sim->steps() >= steps0 + 20; }));
  EXPECT_GE(elapsed_ms(t0), 19 * 2.0 - 2.0);  // stepped at the plant's own Ts = 2 ms
  EXPECT_DOUBLE_EQ(sim->position_mm(), 100.0);  // centred valve: at rest
  ASSERT_EQ(daq.write_valve(4.0), IoStatus::kOk);
  EXPECT_TRUE(poll_until([&] { return sim->position_mm() > 110.0; })) << sim->position_mm();
  EXPECT_TRUE(poll_until([&] { auto s = daq.read_sensor(); return s.status == IoStatus::kOk && s.sensor_v > 2.2; }));
}

TEST(RemoteIoSimulator, RefusesANullPlant) {
  auto sim = RemoteIoSimulator::start(sim_config(), nullptr);
  ASSERT_FALSE(sim.has_value());
  EXPECT_NE(sim.error().message.find("no plant"), std::string::npos) << sim.error().message;
}

}  // namespace
}  // namespace epa::hal
