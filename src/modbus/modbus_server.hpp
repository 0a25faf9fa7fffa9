#pragma once
// The Modbus TCP server: one thread, poll() over non-blocking sockets, our own framing per client
// (so a client that sends one byte a second, or nothing, never blocks the others), libmodbus to
// build the answers and exceptions (modbus_reply / modbus_reply_exception) except the few whose
// PDU the RequestHandler builds itself (device identification), and the RequestHandler for what
// the answer says. A crowd of dead or slow connections cannot starve it:
// a frame must be complete within frame_timeout_s of its first byte, a client without a request
// for idle_timeout_s is closed, and the connection slots are shared fairly (slot_policy.hpp):
// per-address caps, and clients that proved themselves are never evicted for a newcomer.
//
// Modbus/TCP Security on a second listener (802 by default), served by the same thread, slots and
// handler: TLS 1.2/1.3 with mutual authentication (tls/server_context.hpp), each handshake driven
// a step at a time and bounded by handshake_timeout_s, refusals logged once per address with a
// back-off (tls/refusal_log.hpp). The client's rights are those its certificate's role maps to
// (the role table); a client that completed its handshake has proved itself for the slots.
#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "modbus/request_handler.hpp"
#include "points/client_rights.hpp"
#include "tls/server_context.hpp"

namespace epa::modbus {

// A role and what it may do, as [modbus_tls.roles] names them.
struct RoleRights {
  std::string role;
  points::Rights rights = points::Rights::kRead;
};

inline const std::vector<RoleRights> kDefaultRoles = {
    {"viewer", points::Rights::kRead}, {"operator", points::Rights::kOperate}, {"engineer", points::Rights::kTune}};

// Modbus/TCP Security ([modbus_tls]).
struct SecureConfig {
  bool enabled = false;
  std::string address = "0.0.0.0";
  int port = 802;                     // 0: any free port (see secure_port())
  tls::ServerFiles files;             // CA, device certificate and key, CRL
  double handshake_timeout_s = 3.0;   // a TLS handshake not complete this long after the connect: disconnected
  std::vector<RoleRights> roles = kDefaultRoles;
};

struct ServerConfig {
  std::string address = "0.0.0.0";  // IPv4 or IPv6 address to listen on ("::": IPv6 and IPv4)
  int port = 502;                    // 0: any free port (see port())
  int unit_id = 1;
  std::vector<int> alias_unit_ids = kDefaultAliasUnitIds;  // also answered as this device; others get 0B
  int max_clients = 16;
  int max_clients_per_address = 4;   // one address holds at most this many of them
  double idle_timeout_s = 60.0;      // a client without a complete request this long is disconnected
  double frame_timeout_s = 1.0;      // a frame not complete this long after its first byte: disconnected
  WritePolicy policy;
  std::string status_page_url;       // FC43's VendorUrl: status_page_url(the web port), "" with no status page
  bool plain_enabled = true;         // the plain listener (address, port); false: the secure one alone
  SecureConfig secure;
};

class ModbusServer {
 public:
  using Log = std::function<void(const std::string&)>;
  // Binds, then serves on its own thread. The map, gate and channels must outlive the server.
  static core::Result<std::unique_ptr<ModbusServer>> start(const ServerConfig& config, const RegisterMap& map,
                                                           points::WriteGate& gate, runtime::LoopChannels& channels,
                                                           Log log = {});
  ~ModbusServer();
  ModbusServer(const ModbusServer&) = delete;
  ModbusServer& operator=(const ModbusServer&) = delete;

  int port() const { return port_; }  // the plain listener's; 0 when it is off
  // What the listener is bound to (getsockname): "127.0.0.1:502", "[::1]:502"; "" when it is off.
  const std::string& bound_address() const { return bound_; }
  int secure_port() const { return secure_port_; }  // the Modbus/TCP Security listener's; 0 when it is off
  const std::string& secure_bound_address() const { return secure_bound_; }
  int clients() const { return clients_.load(); }
  std::uint64_t requests() const { return requests_.load(); }
  std::uint64_t exceptions() const { return exceptions_.load(); }
  std::uint64_t evicted() const { return evicted_.load(); }  // connections closed to make room for a newcomer
  std::uint64_t refused() const { return refused_.load(); }  // newcomers closed at once: no slot for them
  void stop();

 private:
  struct Impl;
  explicit ModbusServer(std::unique_ptr<Impl> impl);
  void serve();
  void answer_frames(std::size_t client, std::int64_t now_ns);
  void publish_counts(std::int64_t now_ns);

  std::unique_ptr<Impl> impl_;
  int port_ = 0, secure_port_ = 0;
  std::string bound_, secure_bound_;
  std::atomic<bool> stop_{false};
  std::atomic<int> clients_{0};
  std::atomic<std::uint64_t> requests_{0}, exceptions_{0}, evicted_{0}, refused_{0};
  std::thread thread_;
};

}  // namespace epa::modbus
