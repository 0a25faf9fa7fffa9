// The server over real sockets on loopback, with a libmodbus client: every function code and
// exception path, locked and unlocked writes, a half-float write, the unit id, the client cap, an
// idle client, a client that sends one byte at a time and one that sends garbage. Floats are
// encoded with our own pinned encoder: libmodbus 3.1.6's modbus_set_float_abcd gets ABCD wrong.
#include "modbus/modbus_server.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <modbus.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>
#include <thread>

#include "control/paper_controller.hpp"
#include "core/version.hpp"
#include "core/word_order.hpp"
#include "../support/wait_until.hpp"

namespace epa::modbus {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

class Server : public ::testing::Test {
 protected:
  void start(ServerConfig c) {
    auto m = RegisterMap::load(std::string(EPA_SOURCE_DIR) + "/registers/epa.csv");
    ASSERT_TRUE(m.has_value()) << m.error().message;
    map_ = std::make_unique<RegisterMap>(std::move(*m));
    runtime::Snapshot s;
    s.position_mm = 123.5;
    s.mode = runtime::Mode::kRun;
    s.saturated = true;
    channels_.snapshot.publish(s);
    c.address = "127.0.0.1";
    c.port = 0;
    gate_ = std::make_unique<points::WriteGate>(*points::WriteLimits::from_config(loop_, "test.toml"), loop_,
                                                control::paper_controller_config(control::ControllerKind::kPpFfidz), channels_,
                                                nullptr);
    auto server = ModbusServer::start(c, *map_, *gate_, channels_);
    ASSERT_TRUE(server.has_value()) << server.error().message;
    server_ = std::move(*server);
  }
  void SetUp() override {
    ServerConfig c;
    c.max_clients = 3;
    c.idle_timeout_s = 0.3;
    c.policy.unlock_key = 0x5e3a9c17d24b086f;
    start(c);
  }
  modbus_t* client(int unit = 1) {
    modbus_t* ctx = modbus_new_tcp("127.0.0.1", server_->port());
    modbus_set_slave(ctx, unit);
    modbus_set_response_timeout(ctx, 1, 0);
    EXPECT_EQ(modbus_connect(ctx), 0) << modbus_strerror(errno);
    clients_.push_back(ctx);
    return ctx;
  }
  // A connection that speaks raw bytes; from `source` (any loopback address: all of 127/8 is lo).
  int raw_socket(const char* source = nullptr) {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    if (source) {
      sockaddr_in local{};
      local.sin_family = AF_INET;
      inet_pton(AF_INET, source, &local.sin_addr);
      EXPECT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&local), sizeof local), 0);
    }
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(server_->port()));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    raw_.push_back(fd);
    return fd;
  }
  void TearDown() override {
    for (auto* c : clients_) { modbus_close(c); modbus_free(c); }
    for (int fd : raw_) close(fd);
    if (server_) server_->stop();
  }
  int drained() {
    int n = 0;
    runtime::Command c;
    while (channels_.commands.try_pop(c)) ++n;
    return n;
  }

  runtime::RuntimeConfig loop_;
  runtime::LoopChannels channels_{16};
  std::unique_ptr<points::WriteGate> gate_;
  std::unique_ptr<RegisterMap> map_;
  std::unique_ptr<ModbusServer> server_;
  std::vector<modbus_t*> clients_;
  std::vector<int> raw_;
};

TEST_F(Server, EveryFunctionCode) {
  modbus_t* c = client();
  std::uint8_t bits[4] = {};
  std::uint16_t regs[4] = {};
  ASSERT_EQ(modbus_read_bits(c, 0, 1, bits), 1);                  // FC1: reset coil reads 0
  EXPECT_EQ(bits[0], 0);
  ASSERT_EQ(modbus_read_input_bits(c, 0, 4, bits), 4);            // FC2: fault_active, saturated, io_ok, locked
  EXPECT_EQ(bits[1], 1);
  EXPECT_EQ(bits[3], 1);
  ASSERT_EQ(modbus_read_registers(c, 2, 1, regs), 1);             // FC3: mode
  EXPECT_EQ(regs[0], 1);
  ASSERT_EQ(modbus_read_input_registers(c, 0, 2, regs), 2);       // FC4: position
  EXPECT_EQ(core::decode_f32({regs[0], regs[1]}, core::WordOrder::kABCD), 123.5f);
  EXPECT_EQ(modbus_write_bit(c, 0, 1), 1);                        // FC5: reset
  EXPECT_EQ(modbus_write_register(c, 2, 0), 1);                   // FC6: mode stop
  const std::uint8_t one[1] = {1};
  EXPECT_EQ(modbus_write_bits(c, 0, 1, one), 1);                  // FC15: reset
  const auto setpoint_words = core::encode_f32(250.0f, core::WordOrder::kABCD);
  std::uint16_t setpoint[2] = {setpoint_words[0], setpoint_words[1]};
  EXPECT_EQ(modbus_write_registers(c, 0, 2, setpoint), 2) << modbus_strerror(errno);  // FC16: setpoint
  std::uint16_t back[2] = {};
  EXPECT_EQ(modbus_write_and_read_registers(c, 0, 2, setpoint, 0, 2, back), 2);  // FC23
  EXPECT_EQ(core::decode_f32({back[0], back[1]}, core::WordOrder::kABCD), 250.0f);
  EXPECT_EQ(drained(), 5);
  EXPECT_EQ(server_->exceptions(), 0u);
}

TEST_F(Server, EveryExceptionPath) {
  modbus_t* c = client();
  std::uint16_t regs[130] = {};
  EXPECT_EQ(modbus_read_registers(c, 200, 1, regs), -1);
  EXPECT_EQ(errno, EMBXILADD);  // 02 unmapped
  EXPECT_EQ(modbus_write_register(c, 0, 0x4248), -1);
  EXPECT_EQ(errno, EMBXILVAL);  // 03 half a float
  const auto too_far_words = core::encode_f32(900.0f, core::WordOrder::kABCD);
  std::uint16_t too_far[2] = {too_far_words[0], too_far_words[1]};
  EXPECT_EQ(modbus_write_registers(c, 0, 2, too_far), -1);
  EXPECT_EQ(errno, EMBXILVAL);  // 03 above max
  const auto lc_words = core::encode_f32(3.0f, core::WordOrder::kABCD);
  std::uint16_t lc[2] = {lc_words[0], lc_words[1]};
  EXPECT_EQ(modbus_write_registers(c, 28, 2, lc), -1);
  EXPECT_EQ(errno, EMBXSFAIL);  // 04 tuning locked
  const std::uint8_t raw_function[] = {0x01, 0x2B, 0x0D, 0x00, 0x00};  // unit 1, then FC43 with MEI 0x0D (CANopen)
  ASSERT_GT(modbus_send_raw_request(c, const_cast<std::uint8_t*>(raw_function), sizeof raw_function), 0);
  std::uint8_t rsp[MODBUS_TCP_MAX_ADU_LENGTH];
  EXPECT_EQ(modbus_receive_confirmation(c, rsp), 9);
  EXPECT_EQ(rsp[7], 0x2B | 0x80);
  EXPECT_EQ(rsp[8], 0x01);      // 01 illegal function
  EXPECT_EQ(drained(), 0);
}

TEST_F(Server, TuningWritesAfterUnlock) {
  modbus_t* c = client();
  const std::uint16_t key[4] = {0x5e3a, 0x9c17, 0xd24b, 0x086f};
  EXPECT_EQ(modbus_write_registers(c, 9, 4, key), 4);
  const auto lc_words = core::encode_f32(3.0f, core::WordOrder::kABCD);
  std::uint16_t lc[2] = {lc_words[0], lc_words[1]};
  EXPECT_EQ(modbus_write_registers(c, 28, 2, lc), 2);
  runtime::Command cmd;
  ASSERT_TRUE(channels_.commands.try_pop(cmd));
  EXPECT_EQ(cmd.kind, runtime::CommandKind::kTuning);
  std::uint8_t locked = 1;
  ASSERT_EQ(modbus_read_input_bits(c, 3, 1, &locked), 1);
  EXPECT_EQ(locked, 0);
}

TEST_F(Server, OtherUnitIdGetsGatewayException) {
  modbus_t* c = client(7);
  std::uint16_t r[2];
  EXPECT_EQ(modbus_read_input_registers(c, 0, 2, r), -1);
  EXPECT_EQ(errno, EMBXGTAR);
}

TEST_F(Server, UnitsZeroAndFFAreThisDeviceByDefault) {
  std::uint16_t r[2];
  EXPECT_EQ(modbus_read_input_registers(client(0), 0, 2, r), 2);
  EXPECT_EQ(core::decode_f32({r[0], r[1]}, core::WordOrder::kABCD), 123.5f);
  EXPECT_EQ(modbus_read_input_registers(client(0xFF), 0, 2, r), 2);
}

TEST_F(Server, WithoutAliasesUnitZeroGetsGatewayException) {
  server_->stop();
  ServerConfig c;
  c.alias_unit_ids = {};
  start(c);
  std::uint16_t r[2];
  EXPECT_EQ(modbus_read_input_registers(client(0), 0, 2, r), -1);
  EXPECT_EQ(errno, EMBXGTAR);
  EXPECT_EQ(modbus_read_input_registers(client(1), 0, 2, r), 2);
}

TEST_F(Server, BitTablesReadInBlocksOf16) {
  modbus_t* c = client();
  std::uint8_t bits[32];
  std::fill(std::begin(bits), std::end(bits), 7);
  ASSERT_EQ(modbus_read_input_bits(c, 0, 16, bits), 16) << modbus_strerror(errno);
  EXPECT_EQ(bits[1], 1);  // saturated
  const int inputs_end = map_->end_address(Table::kDiscreteInput);
  for (int a = inputs_end; a < 16; ++a) EXPECT_EQ(bits[a], 0) << "reserved discrete input " << a;
  ASSERT_EQ(modbus_read_input_bits(c, 0, 8, bits), 8);
  std::fill(std::begin(bits), std::end(bits), 7);
  ASSERT_EQ(modbus_read_bits(c, 0, 16, bits), 16) << modbus_strerror(errno);
  for (int a = 0; a < 16; ++a) EXPECT_EQ(bits[a], 0) << "coil " << a;  // reset reads 0, the rest is reserved
  EXPECT_EQ(modbus_read_input_bits(c, map_->readable_end(Table::kDiscreteInput), 1, bits), -1);
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(modbus_read_bits(c, map_->readable_end(Table::kCoil) - 8, 16, bits), -1);
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(modbus_write_bit(c, 15, 1), -1);  // reserved: readable, never writable
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(drained(), 0);
}

// Reads one Modbus TCP answer from a raw socket: the MBAP header, then as many bytes as it says.
std::vector<std::uint8_t> read_adu(int fd) {
  timeval tv{2, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  std::vector<std::uint8_t> adu(7);
  if (recv(fd, adu.data(), 7, MSG_WAITALL) != 7) return {};
  const int count = (adu[4] << 8) | adu[5];
  adu.resize(static_cast<std::size_t>(6 + count));
  if (count < 1 || recv(fd, adu.data() + 7, static_cast<std::size_t>(count - 1), MSG_WAITALL) != count - 1) return {};
  return adu;
}

TEST_F(Server, DeviceIdentificationIsAnsweredBehindTheRequestsMbapHeader) {
  const int fd = raw_socket();
  // Two requests in one segment, for unit 0: the regular stream, then object 2 alone.
  const std::uint8_t requests[] = {0x12, 0x34, 0x00, 0x00, 0x00, 0x05, 0x00, 0x2B, 0x0E, 0x02, 0x00,
                                   0x12, 0x35, 0x00, 0x00, 0x00, 0x05, 0x00, 0x2B, 0x0E, 0x04, 0x02};
  ASSERT_EQ(send(fd, requests, sizeof requests, 0), static_cast<ssize_t>(sizeof requests));
  const auto stream = read_adu(fd);
  ASSERT_GE(stream.size(), 14u);
  EXPECT_EQ(std::vector<std::uint8_t>(stream.begin(), stream.begin() + 4), (std::vector<std::uint8_t>{0x12, 0x34, 0x00, 0x00}));
  EXPECT_EQ(stream[6], 0x00);  // the request's unit id
  EXPECT_EQ(std::vector<std::uint8_t>(stream.begin() + 7, stream.begin() + 14),
            (std::vector<std::uint8_t>{0x2B, 0x0E, 0x02, 0x82, 0x00, 0x00, 0x07}));
  EXPECT_LE(stream.size() - 7, 253u);
  const std::string answer(stream.begin() + 14, stream.end());
  for (const std::string_view value : {std::string_view("EPA project"), std::string_view("EPA electro-pneumatic axis controller"), std::string_view("epa.csv"), core::kVersion})
    EXPECT_NE(answer.find(value), std::string::npos) << value;
  const auto one = read_adu(fd);
  const std::string version(core::kVersion);
  std::vector<std::uint8_t> expected = {0x12, 0x35, 0x00, 0x00, 0x00, static_cast<std::uint8_t>(1 + 7 + 2 + version.size()), 0x00,
                                        0x2B, 0x0E, 0x04, 0x82, 0x00, 0x00, 0x01, 0x02, static_cast<std::uint8_t>(version.size())};
  expected.insert(expected.end(), version.begin(), version.end());
  EXPECT_EQ(one, expected);
  // An object it does not have, asked for alone: exception 02, by libmodbus as every other.
  const std::uint8_t missing[] = {0x12, 0x36, 0x00, 0x00, 0x00, 0x05, 0x01, 0x2B, 0x0E, 0x04, 0x07};
  ASSERT_EQ(send(fd, missing, sizeof missing, 0), static_cast<ssize_t>(sizeof missing));
  EXPECT_EQ(read_adu(fd), (std::vector<std::uint8_t>{0x12, 0x36, 0x00, 0x00, 0x00, 0x03, 0x01, 0xAB, 0x02}));
  // The server counts after it sent the answer: wait for it, bounded.
  epa::test::wait_until([&] { return server_->exceptions() >= 1; }, 1s);
  EXPECT_EQ(server_->requests(), 3u);
  EXPECT_EQ(server_->exceptions(), 1u);
}

// Fair slots (slot_policy.hpp): at max_clients a newcomer evicts the youngest client that has not
// proved itself, so a reconnecting crowd churns among its newest and the established clients stay.
TEST_F(Server, ANewClientOverTheCapEvictsTheYoungestClientNotTheEstablishedOnes) {
  modbus_t* a = client();
  modbus_t* b = client();
  std::uint16_t r[2];
  for (auto* ctx : {a, b}) ASSERT_EQ(modbus_read_input_registers(ctx, 0, 2, r), 2);
  // c is accepted after a and b, on a later pass of the server's loop (a later accept time): a and
  // b were accepted on a pass before the one that answered them, and c connects after the answers.
  modbus_t* c = client();
  ASSERT_EQ(modbus_read_input_registers(c, 0, 2, r), 2);  // c is now the youngest, though a is idle the longest
  modbus_t* d = client();
  EXPECT_EQ(modbus_read_input_registers(d, 0, 2, r), 2);  // served, not refused
  EXPECT_EQ(modbus_read_input_registers(a, 0, 2, r), 2);
  EXPECT_EQ(modbus_read_input_registers(b, 0, 2, r), 2);
  EXPECT_EQ(modbus_read_input_registers(c, 0, 2, r), -1);  // c made room
  EXPECT_EQ(server_->clients(), 3);
  EXPECT_EQ(server_->evicted(), 1u);
}

// An unlocked connection has proved itself: never evicted for a newcomer; with every slot held by
// such clients a newcomer is refused (closed at once).
TEST_F(Server, AnUnlockedClientIsNeverEvictedAndANewcomerIsRefusedWhenAllAreProved) {
  const std::uint16_t key[4] = {0x5e3a, 0x9c17, 0xd24b, 0x086f};
  std::vector<modbus_t*> unlocked;
  for (int i = 0; i < 3; ++i) {
    unlocked.push_back(client());
    ASSERT_EQ(modbus_write_registers(unlocked.back(), 9, 4, key), 4) << modbus_strerror(errno);
  }
  modbus_t* late = modbus_new_tcp("127.0.0.1", server_->port());
  modbus_set_response_timeout(late, 1, 0);
  clients_.push_back(late);
  std::uint16_t r[2];
  if (modbus_connect(late) == 0) {
    EXPECT_EQ(modbus_read_input_registers(late, 0, 2, r), -1);  // closed at once
  }
  for (auto* ctx : unlocked) EXPECT_EQ(modbus_read_input_registers(ctx, 0, 2, r), 2);
  EXPECT_EQ(server_->refused(), 1u);
  EXPECT_EQ(server_->evicted(), 0u);
}

// max_clients_per_address is an address's share: with room anyone is admitted; when the server is
// full, a newcomer above its address's share takes the place of its own address's youngest, never
// another address's client.
TEST_F(Server, ANewcomerAboveItsAddressShareReplacesItsOwnAddressesClientWhenFull) {
  server_->stop();
  ServerConfig c;
  c.max_clients = 4;
  c.max_clients_per_address = 2;
  start(c);  // on 127.0.0.1; clients bound to 127.0.0.2 reach it too (all of 127/8 is loopback)
  auto from = [&](const char* source) { return raw_socket(source); };
  const std::uint8_t read[] = {0x00, 0x01, 0x00, 0x00, 0x00, 0x06, 0x01, 0x04, 0x00, 0x00, 0x00, 0x02};
  auto served = [&](int fd) {
    timeval tv{1, 0};
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    std::uint8_t answer[64];
    return send(fd, read, sizeof read, MSG_NOSIGNAL) == sizeof read && recv(fd, answer, sizeof answer, 0) > 0;
  };
  const int other = from("127.0.0.2");
  ASSERT_TRUE(served(other));
  const int first = from("127.0.0.1");
  ASSERT_TRUE(served(first));
  // Each newcomer is accepted on a later pass of the server's loop than the one before it (a later
  // accept time, which orders "youngest"): it connects after the one before was answered.
  const int second = from("127.0.0.1");
  ASSERT_TRUE(served(second));
  const int third = from("127.0.0.1");  // the address's third: above its share, but the server has room
  EXPECT_TRUE(served(third));
  EXPECT_TRUE(served(second));
  const int fourth = from("127.0.0.1");  // the server is full: the address gives up its own
  EXPECT_TRUE(served(fourth));
  EXPECT_FALSE(served(third));   // its own address's youngest made room
  EXPECT_TRUE(served(first));
  EXPECT_TRUE(served(second));
  EXPECT_TRUE(served(other));    // another address's client is never taken for it
  EXPECT_EQ(server_->clients(), 4);
}

TEST_F(Server, FreshIdleSocketsAreEvictedBeforeAWorkingClient) {
  modbus_t* hmi = client();
  std::uint16_t r[2];
  ASSERT_EQ(modbus_read_input_registers(hmi, 0, 2, r), 2);
  for (int i = 0; i < 10; ++i) raw_socket();  // a crowd that connects and says nothing, after the HMI
  // The server has accepted them all (each newcomer evicts as it is accepted): its listening
  // socket's accept queue is empty (bounded).
  epa::test::wait_until([&] { return epa::test::accept_queue_length(server_->port()) == 0; });
  EXPECT_EQ(modbus_read_input_registers(hmi, 0, 2, r), 2);  // still connected: the silent ones made room
  EXPECT_EQ(server_->clients(), 3);
}

TEST_F(Server, AnIdleClientIsDisconnected) {
  const int fd = raw_socket();
  char byte = 0;
  const auto until = Clock::now() + 3s;  // idle timeout 0.3 s; bounded wait
  timeval tv{0, 100000};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  ssize_t n = -1;
  while (Clock::now() < until && (n = recv(fd, &byte, 1, 0)) < 0) {
  }
  EXPECT_EQ(n, 0);  // orderly close by the server
}

// FC 0x84 once got "04 01": libmodbus' exception bit wrapped it into a valid-looking FC4 answer.
TEST_F(Server, AFunctionCodeWithTheExceptionBitClosesTheConnection) {
  const int fd = raw_socket();
  const std::uint8_t frame[] = {0x00, 0x01, 0x00, 0x00, 0x00, 0x06, 0x01, 0x84, 0x00, 0x00, 0x00, 0x02};
  ASSERT_EQ(send(fd, frame, sizeof frame, MSG_NOSIGNAL), static_cast<ssize_t>(sizeof frame));
  timeval tv{2, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  std::uint8_t answer[64];
  EXPECT_EQ(recv(fd, answer, sizeof answer, 0), 0);  // closed, nothing answered
}

TEST_F(Server, AClientSendingOneByteAtATimeDoesNotBlockOthers) {
  const int slow = raw_socket();
  const std::uint8_t frame[] = {0x00, 0x01, 0x00, 0x00, 0x00, 0x06, 0x01, 0x04, 0x00, 0x00, 0x00, 0x02};
  ASSERT_EQ(send(slow, frame, 3, 0), 3);  // a partial header, then nothing for a while
  modbus_t* fast = client();
  std::uint16_t r[2];
  const auto t0 = Clock::now();
  EXPECT_EQ(modbus_read_input_registers(fast, 0, 2, r), 2);
  EXPECT_LT(Clock::now() - t0, 50ms);
  for (std::size_t i = 3; i < sizeof frame; ++i) ASSERT_EQ(send(slow, frame + i, 1, 0), 1);  // the rest, byte by byte
  std::uint8_t rsp[13] = {};
  timeval tv{2, 0};
  setsockopt(slow, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  EXPECT_EQ(recv(slow, rsp, sizeof rsp, MSG_WAITALL), 13);  // then it is answered like anyone
  EXPECT_EQ(rsp[8], 4);  // byte count of two registers
}

TEST_F(Server, AFrameNotCompletedWithinTheFrameTimeoutIsClosedEvenIfBytesKeepComing) {
  server_->stop();
  ServerConfig c;
  c.frame_timeout_s = 0.3;
  c.idle_timeout_s = 60;
  start(c);
  const int slow = raw_socket();
  const std::uint8_t frame[] = {0x00, 0x01, 0x00, 0x00, 0x00, 0x06, 0x01, 0x04, 0x00, 0x00, 0x00, 0x02};
  const auto t0 = Clock::now();
  bool closed = false;
  for (std::size_t i = 0; i < sizeof frame && !closed; ++i) {  // one byte every 100 ms: 1.2 s for the frame
    if (send(slow, frame + i, 1, MSG_NOSIGNAL) != 1) closed = true;
    std::uint8_t byte = 0;
    if (recv(slow, &byte, 1, MSG_DONTWAIT) == 0) closed = true;
    std::this_thread::sleep_for(100ms);  // the stimulus: a client that sends one byte every 100 ms
  }
  EXPECT_TRUE(closed) << "a one-byte-a-tick client was served after all";
  EXPECT_LT(Clock::now() - t0, 1s);
}

TEST_F(Server, GarbageClosesOnlyThatClient) {
  const int bad = raw_socket();
  const std::uint8_t junk[] = {0x12, 0x34, 0xAB, 0xCD, 0x00, 0x06, 0x01, 0x03, 0x00, 0x00, 0x00, 0x01};
  ASSERT_EQ(send(bad, junk, sizeof junk, 0), static_cast<ssize_t>(sizeof junk));
  char byte = 0;
  timeval tv{2, 0};
  setsockopt(bad, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  EXPECT_EQ(recv(bad, &byte, 1, 0), 0);  // closed, no answer
  modbus_t* good = client();
  std::uint16_t r[2];
  EXPECT_EQ(modbus_read_input_registers(good, 0, 2, r), 2);
}

TEST_F(Server, ReadOnlyServerRefusesEveryWrite) {
  server_->stop();
  ServerConfig c;
  c.policy.read_only = true;
  start(c);
  modbus_t* ctx = client();
  EXPECT_EQ(modbus_write_register(ctx, 2, 1), -1);
  EXPECT_EQ(errno, EMBXSFAIL);
  std::uint16_t r[2];
  EXPECT_EQ(modbus_read_input_registers(ctx, 0, 2, r), 2);
}

}  // namespace
}  // namespace epa::modbus
