// The Modbus application layer without sockets: hand-built ADUs in, exception codes, register
// images and queued commands out. Expected words are worked out by hand (50.0f = 0x42480000).
#include "modbus/request_handler.hpp"

#include <gtest/gtest.h>
#include <modbus.h>

#include <cmath>
#include <cstring>
#include <map>

#include "control/paper_controller.hpp"

namespace epa::modbus {
namespace {

using Bytes = std::vector<std::uint8_t>;
constexpr std::uint64_t kKey = 0x5e3a9c17d24b086f;
constexpr std::int64_t kSecond = 1'000'000'000;

Bytes adu(const Bytes& pdu, std::uint8_t unit = 1) {
  Bytes a(7 + pdu.size());  // sized first: g++ 12 warns (array-bounds) about inserting into a 7-byte list
  const std::uint8_t header[7] = {0x00, 0x01, 0x00, 0x00, 0x00, static_cast<std::uint8_t>(pdu.size() + 1), unit};
  std::copy(header, header + 7, a.begin());
  std::copy(pdu.begin(), pdu.end(), a.begin() + 7);
  return a;
}

// Records every change, and says it saved the first `saved_limit` of them.
struct RecordingSink final : core::AuditSink {
  std::vector<core::AuditEntry> entries;
  std::uint64_t changes = 0, saved_limit = 1000;
  void record(const std::vector<core::AuditEntry>& change) override {
    entries.insert(entries.end(), change.begin(), change.end());
    ++changes;
  }
  core::ChangeCounters counters() const override { return {changes, std::min(changes, saved_limit)}; }
};

class Handler : public ::testing::Test {
 protected:
  void SetUp() override { make(WritePolicy{.read_only = false, .unlock_key = kKey, .unlock_timeout_s = 10, .write_clients = {}}); }
  void make(WritePolicy policy) {
    auto m = RegisterMap::load(std::string(EPA_SOURCE_DIR) + "/registers/epa.csv");
    ASSERT_TRUE(m.has_value()) << m.error().message;
    map_ = std::make_unique<RegisterMap>(std::move(*m));
    auto limits = points::WriteLimits::from_config(loop_, "test.toml");
    ASSERT_TRUE(limits.has_value()) << limits.error().message;
    ASSERT_TRUE(narrow_limits(*map_, *limits));
    gate_ = std::make_unique<points::WriteGate>(std::move(*limits), loop_,
                                                control::paper_controller_config(control::ControllerKind::kPpFfidz), channels_,
                                                &sink_);
    handler_ = std::make_unique<RequestHandler>(*map_, std::move(policy), 1, *gate_, channels_,
                                                [this](const std::string& line) { log_.push_back(line); });
    if (image_) modbus_mapping_free(image_);
    image_ = modbus_mapping_new_start_address(0, map_->end_address(Table::kCoil), 0, map_->end_address(Table::kDiscreteInput), 0,
                                              map_->end_address(Table::kHoldingRegister), 0, map_->end_address(Table::kInputRegister));
    publish();
  }
  void TearDown() override { modbus_mapping_free(image_); }
  void publish() { channels_.snapshot.publish(snap_); }
  std::uint8_t send(const Bytes& pdu, std::uint8_t unit = 1, const std::string& client = "127.0.0.1", std::int64_t now = 0) {
    const Bytes a = adu(pdu, unit);
    Session& session = sessions_.try_emplace(client, Session{client, client + ":50000", 0}).first->second;
    return handler_->handle(a.data(), static_cast<int>(a.size()), session, now, image_);
  }
  // FC16 of a key64 to `unlock` (holding 9-12), most significant word first.
  static Bytes unlock_pdu(std::uint64_t key) {
    Bytes p = {0x10, 0x00, 0x09, 0x00, 0x04, 0x08, 0, 0, 0, 0, 0, 0, 0, 0};
    for (int i = 0; i < 8; ++i) p[6 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(key >> (56 - 8 * i));
    return p;
  }
  std::vector<runtime::Command> drain() {
    std::vector<runtime::Command> out;
    runtime::Command c;
    while (channels_.commands.try_pop(c)) out.push_back(c);
    return out;
  }

  runtime::Snapshot snap_ = [] {
    runtime::Snapshot s;
    s.position_mm = 123.5;
    s.mode = runtime::Mode::kRun;
    s.setpoint_mm = 100.0;
    s.tuning.b_r = 1.232;
    s.tuning.b_l = -1.722;
    return s;
  }();
  runtime::RuntimeConfig loop_;  // the configuration's limits: setpoint 0..500 mm, manual valve +-3 V
  runtime::LoopChannels channels_{16};
  RecordingSink sink_;
  std::unique_ptr<RegisterMap> map_;
  std::unique_ptr<points::WriteGate> gate_;
  std::map<std::string, Session> sessions_;  // one connection per client address
  std::vector<std::string> log_;
  std::unique_ptr<RequestHandler> handler_;
  modbus_mapping_t* image_ = nullptr;
};

TEST_F(Handler, ReadsThePositionFloatFromTheSnapshot) {
  EXPECT_EQ(send({0x04, 0x00, 0x00, 0x00, 0x02}), 0);
  EXPECT_EQ(image_->tab_input_registers[0], 0x42F7);  // 123.5f
  EXPECT_EQ(image_->tab_input_registers[1], 0x0000);
}

// Issue 16: fault_history_count (input 200-201) and the newest 8 entries of 10 registers each from
// 202 (code, mode, time uint32, position, setpoint, valve float32), newest first; empty slots read
// code 0, the integer sentinels and NaN. One read of all 82 registers: the block has no gap.
TEST_F(Handler, TheFaultHistoryReadsNewestFirstWithEmptySlots) {
  auto record = [](std::int64_t time_ms, runtime::FaultCode code, runtime::Mode mode, double position, double setpoint, double valve) {
    runtime::FaultRecord r;
    r.time_ms = time_ms, r.code = code, r.mode = mode, r.position_mm = position, r.setpoint_mm = setpoint, r.valve_v = valve;
    return r;
  };
  const runtime::FaultRecord stored[] = {
      record(1'795'579'167'123, runtime::FaultCode::kSoftLimit, runtime::Mode::kManual, 300.0, 150.0, 1.5),
      record(1'000'000'000'500, runtime::FaultCode::kHeartbeatLost, runtime::Mode::kRun, 100.0, 100.0, 0.0)};
  channels_.fault_history.load(stored, 12);
  ASSERT_EQ(send({0x04, 0x00, 0xC8, 0x00, 0x52}), 0);  // input 200, 82 registers
  const std::uint16_t* w = image_->tab_input_registers + 200;
  EXPECT_EQ(w[0], 0x0000);  // count 12
  EXPECT_EQ(w[1], 0x000C);
  const std::uint16_t newest[] = {3, 2, 0x6B06, 0x5D1F, 0x4396, 0x0000, 0x4316, 0x0000, 0x3FC0, 0x0000};
  const std::uint16_t older[] = {7, 1, 0x3B9A, 0xCA00, 0x42C8, 0x0000, 0x42C8, 0x0000, 0x0000, 0x0000};
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(w[2 + i], newest[i]) << "entry 0, word " << i;
    EXPECT_EQ(w[12 + i], older[i]) << "entry 1, word " << i;
  }
  for (int entry = 2; entry < 8; ++entry) {
    const std::uint16_t* e = w + 2 + 10 * entry;
    EXPECT_EQ(e[0], 0) << entry;       // code 0: empty
    EXPECT_EQ(e[1], 0xFFFF) << entry;  // mode: uint16's "no value"
    EXPECT_EQ(e[2], 0xFFFF) << entry;  // time: uint32's
    EXPECT_EQ(e[3], 0xFFFF) << entry;
    for (int f = 4; f < 10; f += 2) {
      std::uint32_t bits = (std::uint32_t{e[f]} << 16) | e[f + 1];
      float v;
      std::memcpy(&v, &bits, sizeof v);
      EXPECT_TRUE(std::isnan(v)) << entry << " word " << f;
    }
  }
  // A new fault pushes the others down: the supervisor adds, every read sees it.
  channels_.fault_history.add(record(1'795'579'200'000, runtime::FaultCode::kIoErrors, runtime::Mode::kStop, 50.0, 60.0, 0.0));
  ASSERT_EQ(send({0x04, 0x00, 0xC8, 0x00, 0x52}), 0);
  EXPECT_EQ(w[1], 13);
  EXPECT_EQ(w[2], 4);
  EXPECT_EQ(w[12], 3);
  EXPECT_EQ(w[22], 7);
  EXPECT_EQ(w[32], 0);
}

TEST_F(Handler, ReadExceptions) {
  EXPECT_EQ(send({0x03, 0x00, 0xC8, 0x00, 0x01}), 0x02);  // holding 200: unmapped
  EXPECT_EQ(send({0x04, 0x00, 0x00, 0x00, 0x0C}), 0x02);  // input 0..11: 11 is a gap
  EXPECT_EQ(send({0x03, 0x00, 0x00, 0x00, 0x00}), 0x03);  // quantity 0
  EXPECT_EQ(send({0x03, 0x00, 0x00, 0x00, 0x7E}), 0x03);  // quantity 126 > 125
  EXPECT_EQ(send({0x2B, 0x0E, 0x01, 0x00}), 0x01);        // device identification: not supported
  EXPECT_EQ(send({0x08, 0x00, 0x00, 0x12, 0x34}), 0x01);  // diagnostics: not supported
}

TEST_F(Handler, UnitIdIsChecked) {
  EXPECT_EQ(send({0x04, 0x00, 0x00, 0x00, 0x02}, 7), 0x0B);
  EXPECT_EQ(send({0x04, 0x00, 0x00, 0x00, 0x02}, 0xFF), 0);
}

TEST_F(Handler, SetpointWriteQueuesOneCommandAndIsAudited) {
  EXPECT_EQ(send({0x10, 0x00, 0x00, 0x00, 0x02, 0x04, 0x42, 0x48, 0x00, 0x00}), 0);  // 50.0f
  const auto c = drain();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].kind, runtime::CommandKind::kSetpoint);
  EXPECT_EQ(c[0].value, 50.0);
  EXPECT_EQ(handler_->status(Session{}, 0).change_counter, 1u);
  ASSERT_EQ(sink_.entries.size(), 1u);
  EXPECT_EQ(sink_.entries[0].point, "setpoint_mm");
  EXPECT_EQ(sink_.entries[0].old_value, 100.0);
  EXPECT_EQ(sink_.entries[0].new_value, 50.0);
  EXPECT_EQ(sink_.entries[0].source, "modbus 127.0.0.1:50000");  // ip:port of the connection
}

TEST_F(Handler, TheCountersSayHowManyChangesAreAcceptedAndHowManyAreOnDisk) {
  sink_.saved_limit = 1;  // the store has written the first change only
  EXPECT_EQ(send({0x10, 0x00, 0x00, 0x00, 0x02, 0x04, 0x42, 0x48, 0x00, 0x00}), 0);  // setpoint 50.0f
  EXPECT_EQ(send({0x10, 0x00, 0x00, 0x00, 0x02, 0x04, 0x42, 0x70, 0x00, 0x00}), 0);  // setpoint 60.0f
  EXPECT_EQ(send({0x10, 0x00, 0x06, 0x00, 0x02, 0x04, 0x00, 0x00, 0x00, 0x07}), 0);  // heartbeat 7: not a change
  EXPECT_EQ(sink_.changes, 2u);
  EXPECT_EQ(send({0x04, 0x00, 0x7A, 0x00, 0x02}), 0);  // input registers 122..123
  EXPECT_EQ(send({0x04, 0x00, 0x80, 0x00, 0x02}), 0);  // input registers 128..129
  EXPECT_EQ(image_->tab_input_registers[122], 0);
  EXPECT_EQ(image_->tab_input_registers[123], 2);  // change_counter
  EXPECT_EQ(image_->tab_input_registers[128], 0);
  EXPECT_EQ(image_->tab_input_registers[129], 1);  // saved_counter
}

TEST_F(Handler, HalfAFloatIsRefusedAndNothingIsQueued) {
  EXPECT_EQ(send({0x06, 0x00, 0x00, 0x42, 0x48}), 0x03);                    // FC6 on the first half
  EXPECT_EQ(send({0x10, 0x00, 0x01, 0x00, 0x01, 0x02, 0x00, 0x00}), 0x03);  // FC16 on the second half
  EXPECT_TRUE(drain().empty());
  EXPECT_EQ(handler_->status(Session{}, 0).change_counter, 0u);
}

TEST_F(Handler, ValueOutsideTheRangeIs03) {
  EXPECT_EQ(send({0x10, 0x00, 0x00, 0x00, 0x02, 0x04, 0x44, 0x16, 0x00, 0x00}), 0x03);  // 600.0f > 500
  EXPECT_EQ(send({0x06, 0x00, 0x02, 0x00, 0x03}), 0x03);                                // mode 3
  EXPECT_TRUE(drain().empty());
}

TEST_F(Handler, TheConfigurationsLimitsNarrowTheMapsForModbusToo) {
  // [limits] setpoint_max_mm = 300 while the map keeps 0..500: 400 is refused (03), nothing is
  // queued and nothing audited; 300 is taken.
  loop_.setpoint_max_mm = 300;
  make(WritePolicy{.read_only = false, .unlock_key = kKey, .unlock_timeout_s = 10, .write_clients = {}});
  EXPECT_EQ(send({0x10, 0x00, 0x00, 0x00, 0x02, 0x04, 0x43, 0xC8, 0x00, 0x00}), 0x03);  // 400.0f
  EXPECT_TRUE(drain().empty());
  EXPECT_TRUE(sink_.entries.empty());
  EXPECT_EQ(handler_->status(Session{}, 0).change_counter, 0u);
  EXPECT_EQ(send({0x10, 0x00, 0x00, 0x00, 0x02, 0x04, 0x43, 0x96, 0x00, 0x00}), 0);  // 300.0f
  EXPECT_EQ(drain().size(), 1u);
  EXPECT_EQ(sink_.entries.size(), 1u);
}

// Every writable register of the shipped map, written just beyond the gate's limits (the
// configuration narrows the setpoint to 0..300 and the manual valve to +-3 V): exception 03,
// nothing queued, nothing audited. Values the register type cannot carry are skipped.
TEST_F(Handler, EveryWritablePointBeyondItsLimitsIs03AndLeavesNoTrace) {
  loop_.setpoint_max_mm = 300;
  make(WritePolicy{.read_only = false, .unlock_key = kKey, .unlock_timeout_s = 10, .write_clients = {}});
  ASSERT_EQ(send(unlock_pdu(kKey)), 0);  // unlocked: the range must refuse tuning writes too
  snap_.mode = runtime::Mode::kManual;
  publish();
  int checked = 0;
  for (const RegisterEntry& e : map_->entries()) {
    if (!e.writable || e.point->access == points::Access::kKey) continue;
    const auto& r = gate_->limits().range(e.point->id);
    for (double v : {r.max.value + std::max(1.0, std::abs(r.max.value) * 1e-3), r.min.value - std::max(1.0, std::abs(r.min.value) * 1e-3)}) {
      Bytes pdu;
      if (e.table == Table::kCoil) {
        if (v != 0.0 && v != 1.0) continue;
        pdu = {0x05, 0x00, static_cast<std::uint8_t>(e.address), static_cast<std::uint8_t>(v != 0 ? 0xFF : 0x00), 0x00};
      } else {
        std::uint16_t words[2] = {};
        encode_value(e, v, words);
        if (decode_value(e, words) != static_cast<double>(static_cast<float>(v)) && decode_value(e, words) != v) continue;
        pdu = {0x10, static_cast<std::uint8_t>(e.address >> 8), static_cast<std::uint8_t>(e.address), 0x00,
               static_cast<std::uint8_t>(e.width()), static_cast<std::uint8_t>(2 * e.width())};
        for (int i = 0; i < e.width(); ++i) pdu.insert(pdu.end(), {static_cast<std::uint8_t>(words[i] >> 8), static_cast<std::uint8_t>(words[i])});
      }
      EXPECT_EQ(send(pdu), 0x03) << e.point->name << " = " << v;
      ++checked;
    }
  }
  EXPECT_GE(checked, 10);
  EXPECT_TRUE(drain().empty());
  EXPECT_TRUE(sink_.entries.empty());
}

TEST_F(Handler, WriteToAnUnmappedRegisterIs02) {
  EXPECT_EQ(send({0x06, 0x00, 0x10, 0x00, 0x01}), 0x02);  // holding 16: not mapped
}

TEST_F(Handler, ABlockWriteArrivesAsOneGroup) {
  // setpoint (0-1) = 50.0 and mode (2) = 1 in one FC16.
  EXPECT_EQ(send({0x10, 0x00, 0x00, 0x00, 0x03, 0x06, 0x42, 0x48, 0x00, 0x00, 0x00, 0x01}), 0);
  const auto c = drain();
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0].kind, runtime::CommandKind::kSetpoint);
  EXPECT_EQ(c[1].kind, runtime::CommandKind::kMode);
  EXPECT_EQ(c[1].mode, runtime::Mode::kRun);
  EXPECT_EQ(handler_->status(Session{}, 0).change_counter, 1u);  // one accepted write request
}

TEST_F(Handler, TuningIsLockedUntilTheKeyThenLocksAgain) {
  const Bytes lc = {0x10, 0x00, 0x1C, 0x00, 0x02, 0x04, 0x40, 0x40, 0x00, 0x00};  // lc_mm = 3.0f
  EXPECT_EQ(send(lc), 0x04);
  EXPECT_EQ(send(unlock_pdu(kKey + 1)), 0x03);  // wrong key
  EXPECT_EQ(send(unlock_pdu(kKey), 1, "127.0.0.1", 0), 0);
  EXPECT_FALSE(handler_->status(sessions_.at("127.0.0.1"), kSecond).locked);
  EXPECT_EQ(send(lc, 1, "127.0.0.1", kSecond), 0);
  const auto c = drain();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].kind, runtime::CommandKind::kTuning);
  EXPECT_DOUBLE_EQ(c[0].tuning.ffidz.lc_v(), 3.0 / 50.0);
  EXPECT_EQ(send(lc, 1, "127.0.0.1", 11 * kSecond), 0x04);  // the 10 s unlock has run out
  // The wrong key is audited as a refused attempt; no key, right or wrong, is ever in the trail.
  int unlock_entries = 0;
  for (const auto& e : sink_.entries) {
    if (e.point != "unlock") continue;
    ++unlock_entries;
    EXPECT_EQ(e.new_value, 0.0);
    EXPECT_EQ(e.source.find("5e3a"), std::string::npos) << e.source;
  }
  EXPECT_EQ(unlock_entries, 1);
}

TEST_F(Handler, TheUnlockBelongsToTheConnectionThatSentTheKey) {
  const Bytes lc = {0x10, 0x00, 0x1C, 0x00, 0x02, 0x04, 0x40, 0x40, 0x00, 0x00};  // lc_mm = 3.0f
  Session hmi{"127.0.0.1", "127.0.0.1:50001", 0}, other{"127.0.0.1", "127.0.0.1:50002", 0};
  auto on = [&](Session& s, const Bytes& pdu) {
    const Bytes a = adu(pdu);
    return handler_->handle(a.data(), static_cast<int>(a.size()), s, 0, image_);
  };
  ASSERT_EQ(on(hmi, unlock_pdu(kKey)), 0);
  EXPECT_EQ(on(other, lc), 0x04);  // the same address, another connection: still locked
  EXPECT_EQ(on(hmi, lc), 0);
  EXPECT_TRUE(handler_->status(other, 0).locked);
  EXPECT_FALSE(handler_->status(hmi, 0).locked);
}

TEST_F(Handler, BruteForceLocksTheAddressOutAndTheRightKeyIsThenRefusedUnseen) {
  for (std::uint64_t i = 1; i <= 50; ++i) {
    const auto e = send(unlock_pdu(kKey ^ i), 1, "10.9.8.7", static_cast<std::int64_t>(i) * 1000);
    EXPECT_EQ(e, i <= 5 ? 0x03 : 0x04) << "attempt " << i;  // 5 wrong keys looked at, then refused unseen
  }
  EXPECT_EQ(send(unlock_pdu(kKey), 1, "10.9.8.7", kSecond), 0x04);  // the right key, during the back-off
  EXPECT_TRUE(handler_->status(sessions_.at("10.9.8.7"), kSecond).locked);
  EXPECT_EQ(handler_->status(sessions_.at("10.9.8.7"), kSecond).unlock_failures, 51u);
  EXPECT_EQ(send({0x04, 0x00, 0x84, 0x00, 0x02}), 0);  // unlock_failures, input 132-133
  EXPECT_EQ((image_->tab_input_registers[132] << 16) | image_->tab_input_registers[133], 51);
  ASSERT_FALSE(log_.empty());
  EXPECT_NE(log_.back().find("10.9.8.7:50000"), std::string::npos) << log_.back();
  EXPECT_NE(log_.back().find("refused for 10 s"), std::string::npos) << log_.back();
  EXPECT_EQ(log_.size(), 5u);  // each key looked at, not each attempt refused unseen
  ASSERT_EQ(sink_.entries.size(), 5u);
  EXPECT_EQ(sink_.entries[0].point, "unlock");
  EXPECT_NE(sink_.entries[0].source.find("10.9.8.7:50000"), std::string::npos);
  EXPECT_EQ(send(unlock_pdu(kKey), 1, "127.0.0.1", kSecond), 0);  // another address is not locked out
  // After the back-off the right key works; a wrong one would lock out for twice as long.
  EXPECT_EQ(send(unlock_pdu(kKey ^ 1), 1, "10.9.8.7", 11 * kSecond), 0x03);
  EXPECT_NE(log_.back().find("refused for 20 s"), std::string::npos) << log_.back();
  EXPECT_EQ(send(unlock_pdu(kKey), 1, "10.9.8.7", 30 * kSecond), 0x04);
  EXPECT_EQ(send(unlock_pdu(kKey), 1, "10.9.8.7", 32 * kSecond), 0);
}

TEST(UnlockKey, SixteenHexDigitsThatAreNotTrivial) {
  EXPECT_EQ(*parse_unlock_key("5e3a9c17d24b086f"), 0x5e3a9c17d24b086fu);
  EXPECT_EQ(*parse_unlock_key("5E3A9C17D24B086F"), 0x5e3a9c17d24b086fu);
  for (const char* bad : {"4321", "5e3a9c17d24b086", "5e3a9c17d24b086f0", "5e3a9c17d24b086g", "0000000000000000", "0123456789abcdef",
                          "fedcba9876543210", "abababababababab", "1234123412341234", "1111111122222222"})
    EXPECT_FALSE(parse_unlock_key(bad).has_value()) << bad;
}

TEST_F(Handler, TuningValuesThatDoNotValidateTogetherAreRefusedWhole) {
  ASSERT_EQ(send(unlock_pdu(kKey)), 0);
  // b_l (26-27) = 2.0f > b_r = 1.232: the dead zone would be invalid.
  EXPECT_EQ(send({0x10, 0x00, 0x1A, 0x00, 0x02, 0x04, 0x40, 0x00, 0x00, 0x00}), 0x03);
  EXPECT_TRUE(drain().empty());
}

TEST_F(Handler, PolicyRefusalsAre04) {
  make(WritePolicy{.read_only = true, .unlock_key = std::nullopt, .unlock_timeout_s = 10, .write_clients = {}});
  EXPECT_EQ(send({0x06, 0x00, 0x02, 0x00, 0x01}), 0x04);
  make(WritePolicy{.read_only = false, .unlock_key = std::nullopt, .unlock_timeout_s = 10, .write_clients = {"10.0.0.5"}});
  EXPECT_EQ(send({0x06, 0x00, 0x02, 0x00, 0x01}, 1, "127.0.0.1"), 0x04);
  EXPECT_EQ(send({0x06, 0x00, 0x02, 0x00, 0x01}, 1, "10.0.0.5"), 0);
  EXPECT_EQ(send(unlock_pdu(kKey), 1, "10.0.0.5"), 0x03);  // no key configured: never unlocks
}

TEST_F(Handler, ModeDependentWritesAre04) {
  EXPECT_EQ(send({0x10, 0x00, 0x04, 0x00, 0x02, 0x04, 0x3F, 0x80, 0x00, 0x00}), 0x04);  // manual valve in RUN
  snap_.mode = runtime::Mode::kManual;
  publish();
  EXPECT_EQ(send({0x10, 0x00, 0x04, 0x00, 0x02, 0x04, 0x3F, 0x80, 0x00, 0x00}), 0);
  snap_.mode = runtime::Mode::kFault;
  publish();
  EXPECT_EQ(send({0x06, 0x00, 0x02, 0x00, 0x01}), 0x04);  // mode while a fault is latched: reset first
  EXPECT_EQ(send({0x05, 0x00, 0x00, 0xFF, 0x00}), 0);     // reset coil
  EXPECT_EQ(drain().back().kind, runtime::CommandKind::kReset);
}

TEST_F(Handler, AFullCommandQueueIsBusy06) {
  for (std::size_t i = 0; i < runtime::kCommandQueueCapacity; ++i) ASSERT_TRUE(channels_.commands.try_push(runtime::heartbeat_command(1)));
  EXPECT_EQ(send({0x06, 0x00, 0x02, 0x00, 0x01}), 0x06);
}

TEST_F(Handler, CoilValuesOtherThanOnOrOffAre03) {
  EXPECT_EQ(send({0x05, 0x00, 0x00, 0x12, 0x34}), 0x03);
}

TEST_F(Handler, WriteAndReadInOneRequest) {
  // FC23: read holding 0-1, write setpoint 0-1 = 50.0f.
  EXPECT_EQ(send({0x17, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x02, 0x04, 0x42, 0x48, 0x00, 0x00}), 0);
  EXPECT_EQ(drain().size(), 1u);
  EXPECT_EQ(send({0x17, 0x00, 0xC8, 0x00, 0x01, 0x00, 0x00, 0x00, 0x02, 0x04, 0x42, 0x48, 0x00, 0x00}), 0x02);  // read part unmapped
  EXPECT_TRUE(drain().empty());  // nothing applied when the read part is wrong
}

}  // namespace
}  // namespace epa::modbus
