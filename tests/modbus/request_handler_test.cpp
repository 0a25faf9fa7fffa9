// The Modbus application layer without sockets: hand-built ADUs in, exception codes, register
// images and queued commands out. Expected words are worked out by hand (50.0f = 0x42480000).
#include "modbus/request_handler.hpp"

#include <gtest/gtest.h>
#include <modbus.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>

#include "control/paper_controller.hpp"
#include "core/version.hpp"

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
  // With `map_text`, that map (named test-map.csv) instead of registers/epa.csv.
  void make(WritePolicy policy, std::vector<int> unit_ids = {1, 0, 0xFF}, const std::string& map_text = "") {
    auto m = map_text.empty() ? RegisterMap::load(std::string(EPA_SOURCE_DIR) + "/registers/epa.csv")
                              : RegisterMap::parse(map_text, "/etc/epa/registers/test-map.csv");
    ASSERT_TRUE(m.has_value()) << m.error().message;
    map_ = std::make_unique<RegisterMap>(std::move(*m));
    auto limits = points::WriteLimits::from_config(loop_, "test.toml");
    ASSERT_TRUE(limits.has_value()) << limits.error().message;
    ASSERT_TRUE(narrow_limits(*map_, *limits));
    gate_ = std::make_unique<points::WriteGate>(std::move(*limits), loop_,
                                                control::paper_controller_config(control::ControllerKind::kPpFfidz), channels_,
                                                &sink_);
    handler_ = std::make_unique<RequestHandler>(*map_, std::move(policy), std::move(unit_ids), status_page_url(8080), *gate_, channels_,
                                                [this](const std::string& line) { log_.push_back(line); });
    if (image_) modbus_mapping_free(image_);
    image_ = new_register_image(*map_);
    ASSERT_NE(image_, nullptr);
    publish();
  }
  void TearDown() override { modbus_mapping_free(image_); }
  void publish() { channels_.snapshot.publish(snap_); }
  Reply reply(const Bytes& pdu, std::uint8_t unit = 1, const std::string& client = "127.0.0.1", std::int64_t now = 0) {
    const Bytes a = adu(pdu, unit);
    Session& session = sessions_.try_emplace(client, Session{client, client + ":50000", 0, ""}).first->second;
    return handler_->handle(a.data(), static_cast<int>(a.size()), session, now, image_);
  }
  // The exception code, 0 for a normal answer.
  std::uint8_t send(const Bytes& pdu, std::uint8_t unit = 1, const std::string& client = "127.0.0.1", std::int64_t now = 0) {
    return reply(pdu, unit, client, now).exception;
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

// The limits an HMI works within read as input registers 146-159 (float32 ABCD): the soft limits,
// the setpoint range writes are checked against, the in-position window, the following error's
// limit and time, each the running configuration's.
TEST_F(Handler, TheConfiguredLimitsReadAsInputRegisters) {
  ASSERT_EQ(send({0x04, 0x00, 146, 0x00, 14}), 0);
  auto f32 = [this](int address) {
    const std::uint32_t bits = (std::uint32_t{image_->tab_input_registers[address]} << 16) | image_->tab_input_registers[address + 1];
    float v;
    std::memcpy(&v, &bits, sizeof v);
    return static_cast<double>(v);
  };
  EXPECT_EQ(f32(146), static_cast<float>(loop_.soft_min_mm));
  EXPECT_EQ(f32(148), static_cast<float>(loop_.soft_max_mm));
  EXPECT_EQ(f32(150), static_cast<float>(loop_.setpoint_min_mm));
  EXPECT_EQ(f32(152), static_cast<float>(loop_.setpoint_max_mm));
  EXPECT_EQ(f32(154), static_cast<float>(loop_.in_position_window_mm));
  EXPECT_EQ(f32(156), static_cast<float>(loop_.following_error_mm));
  EXPECT_EQ(f32(158), static_cast<float>(loop_.following_error_time_s));
  EXPECT_NE(loop_.soft_max_mm, loop_.setpoint_max_mm) << "the test tells the two apart only when they differ";
}

// fault_history_count (input 200-201) and the newest 8 entries of 10 registers each from
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
  EXPECT_EQ(send({0x2B, 0x0D, 0x00, 0x00}), 0x01);        // FC43 with MEI 0x0D (CANopen): not supported
  EXPECT_EQ(send({0x08, 0x00, 0x00, 0x12, 0x34}), 0x01);  // diagnostics: not supported
}

TEST_F(Handler, UnitIdIsChecked) {
  EXPECT_EQ(send({0x04, 0x00, 0x00, 0x00, 0x02}, 7), 0x0B);
  EXPECT_EQ(send({0x04, 0x00, 0x00, 0x00, 0x02}, 0xFF), 0);
}

// The server's default: unit_id, 0 and 0xFF are this device; writes too, not only reads.
TEST_F(Handler, UnitsZeroAndFFAreThisDeviceByDefaultAndAnotherIs0B) {
  EXPECT_EQ(send({0x04, 0x00, 0x00, 0x00, 0x02}, 0), 0);
  EXPECT_EQ(image_->tab_input_registers[0], 0x42F7);  // 123.5f: really read
  EXPECT_EQ(send({0x06, 0x00, 0x02, 0x00, 0x00}, 0), 0);  // mode stop, for unit 0
  EXPECT_EQ(drain().size(), 1u);
  for (const int other : {2, 7, 247, 248, 0xFE}) EXPECT_EQ(send({0x04, 0x00, 0x00, 0x00, 0x02}, static_cast<std::uint8_t>(other)), 0x0B) << other;
  EXPECT_EQ(send({0x2B, 0x0E, 0x01, 0x00}, 9), 0x0B);  // device identification of another unit
}

TEST_F(Handler, WithoutAliasesOnlyTheUnitIdIsThisDevice) {
  make(WritePolicy{}, {17});  // [modbus] unit_id = 17, alias_unit_ids = []
  EXPECT_EQ(send({0x04, 0x00, 0x00, 0x00, 0x02}, 17), 0);
  for (const int other : {0, 1, 0xFF}) EXPECT_EQ(send({0x04, 0x00, 0x00, 0x00, 0x02}, static_cast<std::uint8_t>(other)), 0x0B) << other;
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

// 100.0f written with the words swapped (0x0000 0x42C8) decodes to 2.4e-41: inside the setpoint's
// range, and it would send the axis to 0 mm. A subnormal float is refused instead.
TEST_F(Handler, AWordSwappedFloatIsRefusedNotTakenAsATinyValue) {
  EXPECT_EQ(send({0x10, 0x00, 0x00, 0x00, 0x02, 0x04, 0x00, 0x00, 0x42, 0xC8}), 0x03);
  EXPECT_TRUE(drain().empty());
  EXPECT_EQ(send({0x10, 0x00, 0x00, 0x00, 0x02, 0x04, 0x00, 0x00, 0x00, 0x00}), 0);  // 0.0 itself is a value
  EXPECT_EQ(drain().size(), 1u);
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
  for (const auto& e : sink_.entries)  // the unlock that opened the tuning points, nothing refused
    EXPECT_EQ(core::audit_text(e), "set unlock from 0 to 1") << e.point;
}

TEST_F(Handler, WriteToAnUnmappedRegisterIs02) {
  EXPECT_EQ(send({0x06, 0x00, 0x10, 0x00, 0x01}), 0x02);  // holding 16: not mapped
}

// ---- bit tables in blocks of 16 ----

// A read of `quantity` bits (FC1 or FC2) from `address`.
Bytes read_bits(std::uint8_t fc, int address, int quantity) {
  return {fc, static_cast<std::uint8_t>(address >> 8), static_cast<std::uint8_t>(address), static_cast<std::uint8_t>(quantity >> 8),
          static_cast<std::uint8_t>(quantity)};
}

TEST_F(Handler, TheShippedMapsBitTablesReadInBlocksOf16) {
  for (const Table t : {Table::kDiscreteInput, Table::kCoil}) {
    const std::uint8_t fc = t == Table::kCoil ? 0x01 : 0x02;
    const int end = map_->end_address(t), padded = map_->readable_end(t);
    SCOPED_TRACE(std::string(to_string(t)) + ": end " + std::to_string(end) + ", readable to " + std::to_string(padded));
    EXPECT_EQ(padded % 16, 0);
    EXPECT_GE(padded, end);
    EXPECT_LT(padded - end, 16);
    EXPECT_EQ(send(read_bits(fc, 0, 8)), 0);  // what the integrator's client asked for
    EXPECT_EQ(send(read_bits(fc, 0, 16)), 0);
    EXPECT_EQ(send(read_bits(fc, 0, padded)), 0);
    EXPECT_EQ(send(read_bits(fc, padded - 1, 1)), 0);
    EXPECT_EQ(send(read_bits(fc, padded, 1)), 0x02);      // past the padding
    EXPECT_EQ(send(read_bits(fc, padded - 8, 16)), 0x02);  // runs past it
  }
  // The registers stay strict: a hole is 02.
  EXPECT_EQ(send({0x04, 0x00, 0x0B, 0x00, 0x01}), 0x02);  // input 11
  EXPECT_EQ(send({0x03, 0x00, 0x0F, 0x00, 0x01}), 0x02);  // holding 15
}

TEST_F(Handler, UnmappedBitsReadZeroAndStayUnwritable) {
  // Coils 0 (reset) and 17 (reset again, as a site's HMI may want it twice), discrete input 3
  // (fault_active), a register with a hole after it.
  make(WritePolicy{}, {1, 0, 0xFF},
       "name,table,address,type,access\n"
       "reset,coil,0,bool,rw\nreset,coil,17,bool,rw\nfault_active,discrete,3,bool,r\nmode,holding,0,uint16,rw\nfault_code,input,1,uint16,r\n");
  EXPECT_EQ(map_->readable_end(Table::kCoil), 32);
  EXPECT_EQ(map_->readable_end(Table::kDiscreteInput), 16);
  EXPECT_EQ(map_->readable_end(Table::kHoldingRegister), 1);
  snap_.mode = runtime::Mode::kFault;  // fault_active reads 1
  publish();
  std::fill(image_->tab_input_bits, image_->tab_input_bits + 16, 1);  // whatever was there: the answer is the map's
  std::fill(image_->tab_bits, image_->tab_bits + 32, 1);
  ASSERT_EQ(send(read_bits(0x02, 0, 16)), 0);
  for (int a = 0; a < 16; ++a) EXPECT_EQ(image_->tab_input_bits[a], a == 3 ? 1 : 0) << "discrete input " << a;
  ASSERT_EQ(send(read_bits(0x01, 0, 32)), 0);
  for (int a = 0; a < 32; ++a) EXPECT_EQ(image_->tab_bits[a], 0) << "coil " << a;  // reset reads 0, the rest is reserved
  EXPECT_EQ(send(read_bits(0x01, 32, 1)), 0x02);
  EXPECT_EQ(send(read_bits(0x02, 16, 1)), 0x02);
  // Writes to a reserved coil stay refused, alone or in a block with mapped ones.
  EXPECT_EQ(send({0x05, 0x00, 0x05, 0xFF, 0x00}), 0x02);                    // FC5 coil 5
  EXPECT_EQ(send({0x0F, 0x00, 0x00, 0x00, 0x02, 0x01, 0x03}), 0x02);        // FC15 coils 0-1
  EXPECT_EQ(send({0x0F, 0x00, 0x10, 0x00, 0x02, 0x01, 0x03}), 0x02);        // FC15 coils 16-17
  EXPECT_TRUE(drain().empty());
  EXPECT_EQ(send({0x05, 0x00, 0x11, 0xFF, 0x00}), 0);                       // coil 17: mapped
  EXPECT_EQ(drain().size(), 1u);
  // Register tables are not padded: holding 1, input 0 and 2 are 02.
  EXPECT_EQ(send({0x03, 0x00, 0x00, 0x00, 0x02}), 0x02);
  EXPECT_EQ(send({0x04, 0x00, 0x00, 0x00, 0x01}), 0x02);
  EXPECT_EQ(send({0x04, 0x00, 0x01, 0x00, 0x02}), 0x02);
}

TEST_F(Handler, AMapWithoutBitsHasNoBitsToRead) {
  make(WritePolicy{}, {1, 0, 0xFF}, "name,table,address,type\nposition_mm,input,1000,float32\n");
  EXPECT_EQ(map_->readable_end(Table::kCoil), 0);
  EXPECT_EQ(send(read_bits(0x01, 0, 1)), 0x02);
  EXPECT_EQ(send(read_bits(0x02, 0, 16)), 0x02);
}

// ---- FC43 / MEI 14: read device identification ----

struct DeviceId {
  std::uint8_t read_code = 0, conformity = 0, more_follows = 0, next_object = 0;
  std::vector<std::pair<int, std::string>> objects;
};

// Decodes a response PDU, checking that the object count and lengths add up to its size.
DeviceId decode_device_id(const Bytes& pdu) {
  DeviceId d;
  EXPECT_GE(pdu.size(), 7u);
  EXPECT_LE(pdu.size(), 253u);
  if (pdu.size() < 7) return d;
  EXPECT_EQ(pdu[0], 0x2B);
  EXPECT_EQ(pdu[1], 0x0E);
  d = {pdu[2], pdu[3], pdu[4], pdu[5], {}};
  std::size_t i = 7;
  for (int n = 0; n < pdu[6]; ++n) {
    if (i + 2 > pdu.size() || i + 2 + pdu[i + 1] > pdu.size()) {
      ADD_FAILURE() << "object " << n << " runs past the PDU";
      return d;
    }
    d.objects.emplace_back(pdu[i], std::string(pdu.begin() + static_cast<std::ptrdiff_t>(i + 2),
                                               pdu.begin() + static_cast<std::ptrdiff_t>(i + 2 + pdu[i + 1])));
    i += 2 + pdu[i + 1];
  }
  EXPECT_EQ(i, pdu.size()) << "bytes after the last object";
  return d;
}

const std::vector<std::pair<int, std::string>> kRegularObjects = {
    {0x00, "EPA project"}, {0x01, "epa"}, {0x02, std::string(core::kVersion)}, {0x03, "http://<appliance>:8080/"},
    {0x04, "EPA electro-pneumatic axis controller"}, {0x05, "epa appliance"}, {0x06, "epa.csv"}};

TEST_F(Handler, DeviceIdentificationBasicIsVendorProductAndRevision) {
  const Reply r = reply({0x2B, 0x0E, 0x01, 0x00});
  ASSERT_EQ(r.exception, 0);
  // By hand: function, MEI, read code 01, conformity 0x82, no more, next 0, 3 objects.
  const Bytes head = {0x2B, 0x0E, 0x01, 0x82, 0x00, 0x00, 0x03, 0x00, 0x0B, 'E', 'P', 'A', ' ', 'p', 'r', 'o', 'j', 'e', 'c', 't',
                      0x01, 0x03, 'e', 'p', 'a', 0x02, static_cast<std::uint8_t>(core::kVersion.size())};
  ASSERT_GE(r.pdu.size(), head.size());
  EXPECT_EQ(Bytes(r.pdu.begin(), r.pdu.begin() + static_cast<std::ptrdiff_t>(head.size())), head);
  const DeviceId d = decode_device_id(r.pdu);
  EXPECT_EQ(d.objects, (std::vector<std::pair<int, std::string>>(kRegularObjects.begin(), kRegularObjects.begin() + 3)));
  EXPECT_EQ(d.objects[2].second, std::to_string(core::kVersionMajor) + "." + std::to_string(core::kVersionMinor) + "." +
                                     std::to_string(core::kVersionPatch));
}

TEST_F(Handler, DeviceIdentificationRegularAndExtendedGiveTheSevenObjects) {
  for (const std::uint8_t code : {0x02, 0x03}) {
    const Reply r = reply({0x2B, 0x0E, code, 0x00});
    ASSERT_EQ(r.exception, 0) << int(code);
    const DeviceId d = decode_device_id(r.pdu);
    EXPECT_EQ(d.read_code, code);       // the request's, echoed
    EXPECT_EQ(d.conformity, 0x82);      // regular, stream and individual access: no extended objects
    EXPECT_EQ(d.more_follows, 0x00);
    EXPECT_EQ(d.next_object, 0x00);
    EXPECT_EQ(d.objects, kRegularObjects);
  }
  // A stream from object 4; a basic stream asked from a regular object starts again at 0.
  EXPECT_EQ(decode_device_id(reply({0x2B, 0x0E, 0x02, 0x04}).pdu).objects,
            (std::vector<std::pair<int, std::string>>(kRegularObjects.begin() + 4, kRegularObjects.end())));
  EXPECT_EQ(decode_device_id(reply({0x2B, 0x0E, 0x01, 0x05}).pdu).objects.size(), 3u);
  EXPECT_EQ(decode_device_id(reply({0x2B, 0x0E, 0x02, 0x80}).pdu).objects, kRegularObjects);  // unknown id: from the start
  // Unit 0 and 0xFF ask this device too; a request counts like any other.
  EXPECT_EQ(send({0x2B, 0x0E, 0x01, 0x00}, 0), 0);
  EXPECT_EQ(send({0x2B, 0x0E, 0x01, 0x00}, 0xFF), 0);
  EXPECT_TRUE(drain().empty());
}

TEST_F(Handler, DeviceIdentificationOneObjectByItsId) {
  for (const auto& [id, value] : kRegularObjects) {
    const Reply r = reply({0x2B, 0x0E, 0x04, static_cast<std::uint8_t>(id)});
    ASSERT_EQ(r.exception, 0) << id;
    const DeviceId d = decode_device_id(r.pdu);
    EXPECT_EQ(d.read_code, 0x04);
    EXPECT_EQ(d.more_follows, 0x00);  // individual access: always 00
    EXPECT_EQ(d.next_object, 0x00);
    ASSERT_EQ(d.objects.size(), 1u);
    EXPECT_EQ(d.objects[0], std::make_pair(id, value));
  }
  // The user application is the register map's file name, without its folder.
  make(WritePolicy{}, {1}, "name,table,address,type\nposition_mm,input,1000,float32\n");
  EXPECT_EQ(decode_device_id(reply({0x2B, 0x0E, 0x04, 0x06}).pdu).objects.at(0).second, "test-map.csv");
}

TEST_F(Handler, DeviceIdentificationExceptions) {
  EXPECT_EQ(send({0x2B, 0x0E, 0x04, 0x07}), 0x02);  // individual access to an object it does not have
  EXPECT_EQ(send({0x2B, 0x0E, 0x04, 0x80}), 0x02);  // ... an extended one
  EXPECT_EQ(send({0x2B, 0x0E, 0x04, 0xFF}), 0x02);
  EXPECT_EQ(send({0x2B, 0x0E, 0x00, 0x00}), 0x03);  // read codes are 01-04
  EXPECT_EQ(send({0x2B, 0x0E, 0x05, 0x00}), 0x03);
  EXPECT_EQ(send({0x2B, 0x0E, 0xFF, 0x00}), 0x03);
  EXPECT_EQ(send({0x2B, 0x0E, 0x01}), 0x03);              // the object id is missing
  EXPECT_EQ(send({0x2B, 0x0E, 0x01, 0x00, 0x00}), 0x03);  // a byte too many
  EXPECT_EQ(send({0x2B, 0x0D, 0x01, 0x00}), 0x01);        // another MEI type (CANopen general reference)
  EXPECT_EQ(send({0x2B, 0x00, 0x01, 0x00}), 0x01);
  EXPECT_EQ(send({0x2B}), 0x03);                          // no MEI type at all
  const Reply r = reply({0x2B, 0x0E, 0x04, 0x07});
  EXPECT_TRUE(r.pdu.empty());  // an exception carries no PDU of its own
}

// VendorUrl is the status page on the port the web server runs on, empty without one (serve passes
// the bound port: tests/interop/pymodbus_test.py reads it with pymodbus from a running appliance).
TEST(DeviceIdentification, TheVendorUrlIsTheStatusPageOnItsPortOrEmptyWithoutOne) {
  EXPECT_EQ(appliance_identity("/etc/epa/epa.csv", status_page_url(8123)).objects[3], "http://<appliance>:8123/");
  // Each answer names the address its client reached the appliance at.
  EXPECT_EQ(with_host(appliance_identity("/etc/epa/epa.csv", status_page_url(8123)), "192.0.2.7").objects[3], "http://192.0.2.7:8123/");
  EXPECT_EQ(with_host(appliance_identity("/etc/epa/epa.csv", ""), "192.0.2.7").objects[3], "") << "no status page: no URL";
  EXPECT_EQ(appliance_identity("/etc/epa/epa.csv", "").objects[3], "");
}

TEST(DeviceIdentification, AStreamLongerThanAPduIsSplitWithMoreFollows) {
  DeviceIdentity id;
  for (std::size_t i = 0; i < id.objects.size(); ++i) id.objects[i] = std::string(100, static_cast<char>('a' + i));
  id.objects[6] = std::string(300, 'z');  // longer than any response can carry: cut to 244 bytes
  std::vector<std::string> got;
  std::uint8_t object = 0;
  for (int request = 0; request < 10; ++request) {
    const std::uint8_t req[3] = {0x0E, 0x02, object};
    Bytes pdu;
    ASSERT_EQ(read_device_identification(req, 3, id, pdu), 0);
    const DeviceId d = decode_device_id(pdu);
    ASSERT_FALSE(d.objects.empty());
    EXPECT_EQ(d.objects.front().first, object);  // from the id asked for
    for (const auto& [i, v] : d.objects) got.push_back(v);
    if (d.more_follows == 0x00) {
      EXPECT_EQ(d.next_object, 0x00);
      break;
    }
    EXPECT_EQ(d.more_follows, 0xFF);
    EXPECT_EQ(d.next_object, d.objects.back().first + 1);
    object = d.next_object;
  }
  ASSERT_EQ(got.size(), 7u);  // every object once, none split
  for (std::size_t i = 0; i < 6; ++i) EXPECT_EQ(got[i], id.objects[i]);
  EXPECT_EQ(got[6], std::string(244, 'z'));
  // 7 + 2 + 244: the longest object fills a PDU exactly.
  const std::uint8_t last[3] = {0x0E, 0x04, 0x06};
  Bytes pdu;
  ASSERT_EQ(read_device_identification(last, 3, id, pdu), 0);
  EXPECT_EQ(pdu.size(), 253u);
}

TEST(TcpAdu, EchoesTheTransactionAndUnitWithTheLengthOfTheAnswer) {
  const std::uint8_t request[] = {0xBE, 0xEF, 0x00, 0x00, 0x00, 0x05, 0x00, 0x2B, 0x0E, 0x01, 0x00};
  const Bytes pdu(200, 0x55);
  const Bytes adu_bytes = tcp_adu(request, pdu);
  ASSERT_EQ(adu_bytes.size(), 207u);
  EXPECT_EQ(Bytes(adu_bytes.begin(), adu_bytes.begin() + 7), (Bytes{0xBE, 0xEF, 0x00, 0x00, 0x00, 201, 0x00}));
  EXPECT_EQ(Bytes(adu_bytes.begin() + 7, adu_bytes.end()), pdu);
}

TEST_F(Handler, ABlockWriteArrivesAsOneGroup) {
  // setpoint (0-1) = 50.0 and mode (2) = 1 in one FC16.
  EXPECT_EQ(send({0x10, 0x00, 0x00, 0x00, 0x03, 0x06, 0x42, 0x48, 0x00, 0x00, 0x00, 0x01}), 0);
  const auto c = drain();
  ASSERT_EQ(c.size(), 2u);  // the mode first: RUN entered holds, then the setpoint moves
  EXPECT_EQ(c[0].kind, runtime::CommandKind::kMode);
  EXPECT_EQ(c[0].mode, runtime::Mode::kRun);
  EXPECT_EQ(c[1].kind, runtime::CommandKind::kSetpoint);
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
  // The wrong key is audited as a refused attempt, the right one as the unlock it made (0 -> 1); each
  // names the connection alone in its source (the why goes to the log). No key, right or wrong, is
  // ever in the trail.
  std::vector<std::string> unlock_entries;
  for (const auto& e : sink_.entries) {
    if (e.point != "unlock") continue;
    unlock_entries.push_back(core::audit_text(e));
    EXPECT_EQ(e.source, "modbus 127.0.0.1:50000");
    EXPECT_EQ(e.source.find("5e3a"), std::string::npos) << e.source;
  }
  EXPECT_EQ(unlock_entries, (std::vector<std::string>{"(unlock: nothing changed)", "set unlock from 0 to 1"}));
}

// Modbus/TCP Security: the role in the client's certificate decides, through the one gate.
TEST_F(Handler, OnTheSecurePortTheRoleDecidesWhatAClientMayWrite) {
  const Bytes setpoint = {0x10, 0x00, 0x00, 0x00, 0x02, 0x04, 0x43, 0x20, 0x00, 0x00};  // 160.0f
  const Bytes lc = {0x10, 0x00, 0x1C, 0x00, 0x02, 0x04, 0x40, 0x40, 0x00, 0x00};        // lc_mm = 3.0f
  auto secure = [](const char* port, const char* role, points::Rights rights) {
    Session s{"10.0.0.9", std::string("10.0.0.9:") + port, 0, ""};
    s.rights = rights, s.role = role, s.subject = std::string("/CN=") + role;
    return s;
  };
  Session viewer = secure("1", "viewer", points::Rights::kRead), op = secure("2", "operator", points::Rights::kOperate),
          eng = secure("3", "engineer", points::Rights::kTune);
  auto on = [&](Session& s, const Bytes& pdu) {
    const Bytes a = adu(pdu);
    return handler_->handle(a.data(), static_cast<int>(a.size()), s, 0, image_).exception;
  };
  EXPECT_EQ(on(viewer, {0x03, 0x00, 0x00, 0x00, 0x02}), 0);
  EXPECT_EQ(on(viewer, setpoint), 0x04);
  EXPECT_EQ(on(op, lc), 0x04);
  EXPECT_EQ(on(op, unlock_pdu(kKey)), 0x04);  // the right key, but the role decides on this port
  EXPECT_EQ(on(eng, unlock_pdu(kKey)), 0x04);
  EXPECT_TRUE(handler_->status(op, 0).locked);
  EXPECT_FALSE(handler_->status(eng, 0).locked);
  EXPECT_TRUE(sink_.entries.empty()) << "refused writes and unlock attempts on the secure port leave no audit entry";
  EXPECT_EQ(on(op, setpoint), 0);
  EXPECT_EQ(on(eng, lc), 0);
  ASSERT_EQ(sink_.entries.size(), 2u);
  EXPECT_EQ(sink_.entries[0].source, "modbus-tls 10.0.0.9:2 /CN=operator (operator)");
  EXPECT_EQ(sink_.entries[1].point, "lc_mm");
  EXPECT_EQ(sink_.entries[1].source, "modbus-tls 10.0.0.9:3 /CN=engineer (engineer)");
}

TEST_F(Handler, AReadOnlyServerRefusesEveryRoleToo) {
  make(WritePolicy{.read_only = true, .unlock_key = kKey, .unlock_timeout_s = 10, .write_clients = {}});
  Session eng{"10.0.0.9", "10.0.0.9:3", 0, ""};
  eng.rights = points::Rights::kTune, eng.role = "engineer";
  const Bytes a = adu({0x10, 0x00, 0x00, 0x00, 0x02, 0x04, 0x43, 0x20, 0x00, 0x00});
  EXPECT_EQ(handler_->handle(a.data(), static_cast<int>(a.size()), eng, 0, image_).exception, 0x04);
}

TEST_F(Handler, TheUnlockBelongsToTheConnectionThatSentTheKey) {
  const Bytes lc = {0x10, 0x00, 0x1C, 0x00, 0x02, 0x04, 0x40, 0x40, 0x00, 0x00};  // lc_mm = 3.0f
  Session hmi{"127.0.0.1", "127.0.0.1:50001", 0, ""}, other{"127.0.0.1", "127.0.0.1:50002", 0, ""};
  auto on = [&](Session& s, const Bytes& pdu) {
    const Bytes a = adu(pdu);
    return handler_->handle(a.data(), static_cast<int>(a.size()), s, 0, image_).exception;
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
