#pragma once
// The Modbus application layer, without sockets: one request ADU in, an exception code or a
// filled register image out (libmodbus' modbus_reply then builds the answer). Reads encode the
// published snapshot through the point catalog; writes are decoded (mapped, writable, whole
// 32-bit values), the unlock key is taken here, and the rest goes to the one write gate
// (points::WriteGate) as one group: queued for the scan cycle whole, or refused whole.
//
// Exceptions: 01 unsupported function; 02 unmapped address or write to a read-only register;
// 03 bad quantity, a value outside the limits (the catalog's, the configuration's and the map's),
// a write that covers only part of a 32-bit value, a wrong unlock key, or tuning values that do
// not validate together; 04 the write cannot be applied (server read-only, client not allowed to
// write, tuning locked, wrong mode, fault latched, an unlock from an address in its back-off);
// 06 the command queue is full (busy); 0B a
// request for another unit id.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "modbus/register_map.hpp"
#include "modbus/unlock_guard.hpp"
#include "points/write_gate.hpp"
#include "runtime/scan_cycle.hpp"

struct _modbus_mapping_t;  // libmodbus' register image (modbus_mapping_t)

namespace epa::modbus {

struct WritePolicy {
  bool read_only = false;                  // refuse every write (exception 04)
  std::optional<std::uint64_t> unlock_key; // none: tuning registers can never be unlocked
  double unlock_timeout_s = 60.0;          // tuning stays writable this long after the key (per connection)
  std::vector<std::string> write_clients;  // IPv4 addresses allowed to write; empty: any
};

// One client connection as the handler sees it: who it is and whether it sent the key.
struct Session {
  std::string address;                 // the client's IPv4 address (write_clients, the unlock back-off)
  std::string peer;                    // "ip:port", for the log and the audit trail
  std::int64_t unlocked_until_ns = 0;  // the unlock is this connection's, until then or until it closes
};

class RequestHandler {
 public:
  using Log = std::function<void(const std::string&)>;
  // The map, gate and channels must outlive the handler.
  RequestHandler(const RegisterMap& map, WritePolicy policy, int unit_id, points::WriteGate& gate,
                 runtime::LoopChannels& channels, Log log = {});

  // `req` is a whole Modbus TCP ADU (7-byte MBAP header, then the PDU). Returns 0 when `image`
  // holds what modbus_reply needs for the answer, else the exception code to send.
  std::uint8_t handle(const std::uint8_t* req, int length, Session& session, std::int64_t now_ns, _modbus_mapping_t* image);

  // What the interface points read for `session` (`locked` is that connection's).
  points::InterfaceStatus status(const Session& session, std::int64_t now_ns) const;
  void set_clients(int n) { clients_ = n; }
  const RegisterMap& map() const { return map_; }

 private:
  struct Write {
    const RegisterEntry* entry;
    double value;
    std::uint64_t key = 0;  // a key64's words
  };
  std::uint8_t read_into(Table table, int address, int quantity, const runtime::Snapshot& snap, const Session& session,
                         std::int64_t now_ns, _modbus_mapping_t* image);
  std::uint8_t collect_register_writes(int address, int quantity, const std::uint8_t* bytes, std::vector<Write>& out) const;
  std::uint8_t collect_coil_writes(int address, int quantity, const std::uint8_t* bits, std::vector<Write>& out) const;
  std::uint8_t apply_writes(const std::vector<Write>& writes, Session& session, std::int64_t now_ns);
  std::uint8_t take_key(const Write& key, const Session& session, std::int64_t now_ns);

  const RegisterMap& map_;
  WritePolicy policy_;
  int unit_id_;
  points::WriteGate& gate_;
  runtime::LoopChannels& channels_;
  Log log_;
  UnlockGuard unlock_;
  std::uint64_t requests_ = 0;
  int clients_ = 0;
};

}  // namespace epa::modbus
