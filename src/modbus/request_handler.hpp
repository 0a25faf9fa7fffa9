#pragma once
// The Modbus application layer, without sockets: one request ADU in, a Reply out: an exception
// code, a register image filled for libmodbus' modbus_reply to build the answer from, or a whole
// response PDU built here for what modbus_reply does not know (FC43/14, device identification).
// Reads encode the published snapshot through the point catalog; writes are decoded (mapped,
// writable, whole 32-bit values), the unlock key is taken here, and the rest goes to the one
// write gate (points::WriteGate) as one group: queued for the scan cycle whole, or refused whole.
//
// Exceptions: 01 unsupported function (or MEI type); 02 unmapped address, a write to a read-only
// register or coil, or a device identification object this device does not have; 03 bad
// quantity, a value outside the limits (the catalog's, the configuration's and the map's), a
// write that covers only part of a 32-bit value, a wrong unlock key, tuning values that do not
// validate together, or a bad device identification read code; 04 the write cannot be applied
// (server read-only, client not allowed to write, tuning locked, wrong mode, fault latched, an
// unlock refused unseen: from a connection in its back-off, or while its address is in back-off
// from a connection that sent a wrong key or is not yet open 2 s; on the secure port, a write the
// client's role may not make, and any unlock: the role decides); 06 the command queue is full (busy); 0B a request
// for a unit id that is not this device's (unit_id, and by default 0 and 0xFF).
//
// Bit tables (coils, discrete inputs) read in blocks of 16, as clients poll them: every address
// from 0 up to the table's end rounded up to a multiple of 16 is readable, an unmapped one reads
// 0 (reserved); writing one is still 02. Register tables stay strict: an unmapped register is 02.
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "modbus/device_identification.hpp"
#include "modbus/register_map.hpp"
#include "modbus/unlock_guard.hpp"
#include "points/client_rights.hpp"
#include "points/write_gate.hpp"
#include "runtime/loop_channels.hpp"

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
  std::string local_address;           // this appliance's address the client reached (FC43's VendorUrl)
  std::int64_t opened_ns = 0;          // when the connection was accepted (the unlock back-off hears old ones)
  // Modbus/TCP Security: the rights of the role in the client's certificate (none: plain Modbus,
  // where write_clients and the unlock key decide), the role, and the certificate's subject.
  std::optional<points::Rights> rights{};
  std::string role{};
  std::string subject{};
};

// What goes back for one request.
struct Reply {
  std::uint8_t exception = 0;     // not 0: answer with this exception code (modbus_reply_exception)
  std::vector<std::uint8_t> pdu;  // else, when not empty: this whole response PDU, sent as tcp_adu();
                                  // else modbus_reply answers from the register image
};

// The unit ids a server answers as itself besides its own: 0 and 0xFF, which TCP clients and
// gateways send to mean "the server itself" ([modbus] alias_unit_ids).
inline const std::vector<int> kDefaultAliasUnitIds = {0, 0xFF};

class RequestHandler {
 public:
  using Log = std::function<void(const std::string&)>;
  // `unit_ids`: every unit id answered as this device (others get 0B); `status_page_url`: the
  // device identification's VendorUrl (appliance_identity). The map, gate and channels must
  // outlive the handler.
  RequestHandler(const RegisterMap& map, WritePolicy policy, std::vector<int> unit_ids, std::string_view status_page_url,
                 points::WriteGate& gate, runtime::LoopChannels& channels, Log log = {});

  // `req` is a whole Modbus TCP ADU (7-byte MBAP header, then the PDU); `image` is the register
  // image of new_register_image(), which the reply's modbus_reply reads.
  Reply handle(const std::uint8_t* req, int length, Session& session, std::int64_t now_ns, _modbus_mapping_t* image);

  // What the interface points read for `session` (`locked` is that connection's).
  points::InterfaceStatus status(const Session& session, std::int64_t now_ns) const;
  void set_clients(int n) { clients_ = n; }
  // The connection is closed: its own count of wrong keys goes (its address's stays).
  void connection_closed(const Session& session) { unlock_.closed(session.peer); }
  const RegisterMap& map() const { return map_; }

 private:
  struct Write {
    const RegisterEntry* entry;
    double value;
    std::uint64_t key = 0;  // a key64's words
  };
  std::uint8_t respond(const std::uint8_t* req, int length, Session& session, std::int64_t now_ns, _modbus_mapping_t* image,
                       std::vector<std::uint8_t>& pdu);
  std::uint8_t read_into(Table table, int address, int quantity, const runtime::Snapshot& snap, const Session& session,
                         std::int64_t now_ns, _modbus_mapping_t* image);
  std::uint8_t collect_register_writes(int address, int quantity, const std::uint8_t* bytes, std::vector<Write>& out) const;
  std::uint8_t collect_coil_writes(int address, int quantity, const std::uint8_t* bits, std::vector<Write>& out) const;
  std::uint8_t apply_writes(const std::vector<Write>& writes, Session& session, std::int64_t now_ns);
  std::uint8_t take_key(const Write& key, const Session& session, std::int64_t now_ns);
  points::Requester requester(const Session& session, std::int64_t now_ns) const;

  const RegisterMap& map_;
  WritePolicy policy_;
  std::vector<int> unit_ids_;
  DeviceIdentity identity_;
  points::WriteGate& gate_;
  runtime::LoopChannels& channels_;
  Log log_;
  UnlockGuard unlock_;
  std::uint64_t requests_ = 0;
  int clients_ = 0;
};

// libmodbus' register image for `map`: every table from address 0 to map.readable_end(), zeroed
// (the reserved bits of a bit table stay 0). nullptr when it cannot be allocated; free it with
// modbus_mapping_free.
_modbus_mapping_t* new_register_image(const RegisterMap& map);

// The Modbus TCP ADU that answers `request` (an ADU) with `pdu`: the request's transaction and
// unit id, protocol 0, the length of the unit id and the PDU.
std::vector<std::uint8_t> tcp_adu(const std::uint8_t* request, std::span<const std::uint8_t> pdu);

}  // namespace epa::modbus
