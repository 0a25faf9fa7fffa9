// Modbus TCP requests into the server's request path with the shipped map (registers/epa.csv):
// the input is a byte stream as a client sends it, cut into ADUs by the MBAP length exactly as
// ModbusServer does, each one through RequestHandler::handle and then libmodbus' modbus_reply /
// modbus_reply_exception (which reads the register image the handler filled), or the handler's
// own PDU (device identification) behind its MBAP header. Unlocking is
// configured (key 5e3a9c17d24b086f, in the dictionary and the seeds), so tuning writes are reached.
// Every input starts from a fresh handler and an empty command queue: a run replays alone.
#include <modbus.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>

#include "control/paper_controller.hpp"
#include "modbus/request_handler.hpp"

namespace {

using namespace epa;

constexpr int kMbapLength = 6;  // bytes before the MBAP length field's count starts (as the server)

struct Fixture {
  modbus::RegisterMap map;
  modbus_mapping_t* image = nullptr;
  modbus_t* ctx = nullptr;
  int sink[2] = {-1, -1};  // replies go to sink[0]; sink[1] is drained after each input
};

Fixture& fixture() {
  static Fixture* f = [] {
    auto m = modbus::RegisterMap::load(EPA_SOURCE_DIR "/registers/epa.csv");
    if (!m) std::abort();
    auto* fx = new Fixture{std::move(*m)};
    fx->image = modbus::new_register_image(fx->map);  // as the server's: bit tables padded to 16
    fx->ctx = modbus_new_tcp("127.0.0.1", 502);
    if (!fx->image || !fx->ctx || socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, fx->sink) != 0) std::abort();
    modbus_set_socket(fx->ctx, fx->sink[0]);
    return fx;
  }();
  return *f;
}

// Counts what reaches the audit trail (the store's queue in the appliance), so the audit path of
// an accepted write runs too, and the counters registers read something.
struct CountingSink final : core::AuditSink {
  std::uint64_t changes = 0;
  void record(const std::vector<core::AuditEntry>& change) override { changes += change.empty() ? 0 : 1; }
  core::ChangeCounters counters() const override { return {changes, changes}; }
};

runtime::Snapshot running_snapshot() {
  runtime::Snapshot s;
  s.mode = runtime::Mode::kRun;
  s.position_mm = 123.5;
  s.setpoint_mm = 100.0;
  s.tuning.b_r = 1.232;
  s.tuning.b_l = -1.722;
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Fixture& fx = fixture();
  runtime::LoopChannels channels(16);
  CountingSink audit;
  channels.snapshot.publish(running_snapshot());
  const runtime::RuntimeConfig loop;  // the configuration's limits and mm_per_volt, as shipped
  points::WriteGate gate(*points::WriteLimits::from_config(loop, "fuzz.toml"), loop,
                         control::paper_controller_config(control::ControllerKind::kPpFfidz), channels, &audit);
  modbus::RequestHandler handler(fx.map, modbus::WritePolicy{.read_only = false, .unlock_key = 0x5e3a9c17d24b086f, .unlock_timeout_s = 10},
                                 {1, 0, 0xFF}, modbus::status_page_url(8080), gate, channels);
  modbus::Session session{.address = "127.0.0.1", .peer = "127.0.0.1:50000"};
  std::int64_t now_ns = 0;
  std::size_t pos = 0;
  while (size - pos >= static_cast<std::size_t>(kMbapLength + 1)) {
    const std::uint8_t* frame = data + pos;
    const int protocol = (frame[2] << 8) | frame[3];
    const int count = (frame[4] << 8) | frame[5];
    if (protocol != 0 || count < 2 || kMbapLength + count > MODBUS_TCP_MAX_ADU_LENGTH) break;  // the server drops the client
    const auto total = static_cast<std::size_t>(kMbapLength + count);
    if (size - pos < total) break;  // incomplete: the server waits for more
    // The server hands libmodbus its own buffer of the frame; a copy of exactly `total` bytes lets
    // ASan see a read past the frame.
    std::unique_ptr<std::uint8_t[]> req(new std::uint8_t[total]);
    std::copy(frame, frame + total, req.get());
    const modbus::Reply reply = handler.handle(req.get(), static_cast<int>(total), session, now_ns, fx.image);
    if (reply.exception) {
      modbus_reply_exception(fx.ctx, req.get(), reply.exception);
    } else if (!reply.pdu.empty()) {  // FC43: the handler's own PDU, checked against the limit the server relies on
      if (reply.pdu.size() > static_cast<std::size_t>(modbus::kMaxPduBytes)) std::abort();
      const auto adu = modbus::tcp_adu(req.get(), reply.pdu);
      if (write(fx.sink[0], adu.data(), adu.size()) < 0) std::abort();
    } else {
      modbus_reply(fx.ctx, req.get(), static_cast<int>(total), fx.image);
    }
    runtime::Command c;
    while (channels.commands.try_pop(c)) {}
    std::uint8_t discard[512];
    while (read(fx.sink[1], discard, sizeof discard) > 0) {}
    pos += total;
    now_ns += 1'000'000'000;  // a second between requests: the 10 s unlock can run out
  }
  return 0;
}
