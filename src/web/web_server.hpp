#pragma once
// The status page's HTTP server (cpp-httplib): the JSON API, /metrics, the page's static files
// and Chart.js, and, when a token is configured, the commands (setpoint, mode, reset, and any
// writable point through /api/points, a position record through /api/records), each decided by
// the one write gate. It reads only the published snapshot and keeps its own buffers (a sampler
// thread fills the 30 s trend), so it cannot slow the scan cycle; workers started per connection up to a cap (elastic_task_queue.hpp),
// a deadline per request (deadline_http_server.hpp), caps on the request head and body, and a token
// back-off bound what a crowd of clients can cost.
//
// With `tls` the port speaks HTTPS only (front_end_tls.hpp), with the certificate files of
// [modbus_tls]. A client certificate signed by its CA logs in: its role's rights decide the
// commands (a viewer's are refused 403), with no token; without one, the token rule holds.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/audit.hpp"
#include "core/result.hpp"
#include "points/client_rights.hpp"
#include "points/write_gate.hpp"
#include "runtime/loop_channels.hpp"
#include "tls/server_context.hpp"
#include "web/front_end_tls.hpp"
#include "web/json_api.hpp"

namespace epa::web {

// A role a client certificate may name, and what it may do ([modbus_tls.roles]).
struct CertificateRole {
  std::string role;
  points::Rights rights = points::Rights::kRead;
};

struct WebConfig {
  std::string address = "0.0.0.0";  // IPv4 or IPv6 address to listen on ("::": IPv6 and IPv4)
  int port = 8080;                   // 0: any free port (see port())
  std::string token;                 // "": commands refused (403); else "Authorization: Bearer <token>"
  std::string static_dir = "../web"; // index.html, app.js, style.css
  std::string chart_js = "/usr/share/javascript/chart.js/chart.min.js";  // Debian's libjs-chart.js
  // Requests answered at once. A worker never waits for a client (the front end buffers requests
  // and answers), so more workers than a few per core only share the CPU: at 512, a crowd's
  // answers slowed the page's poll to 0.6 s; at 16, 0.04 s.
  int worker_threads = 16;
  std::size_t max_body_bytes = 4096;
  int request_deadline_ms = 2000;    // a request's head and body arrive within this of its first byte, or 408
  int max_connections_per_address = 32;  // more from one client address are closed at once (503)
  // Names (or addresses) besides the host's own addresses, "localhost" and its host name that a
  // request's Host may carry; any other is refused 421 (a DNS-rebinding page carries its own name).
  std::vector<std::string> host_names;
  // HTTPS ([web] tls): the port speaks TLS only. The files and the roles are [modbus_tls]'s, which
  // the appliance fills in (config/appliance_config.cpp reads only the two [web] keys).
  bool tls = false;
  ClientCertificates client_certificates = ClientCertificates::kOptional;
  tls::ServerFiles tls_files;
  std::vector<CertificateRole> roles;
  std::function<void(const std::string&)> log;  // token lock-outs; may be empty
};

class RecentAudit;
class CommissionPort;

class WebServer {
 public:
  using ModbusStatsFn = std::function<ModbusStats()>;
  using StoreStatsFn = std::function<StoreStats()>;
  // Binds, then serves on its own thread. channels, gate and audit must outlive the server.
  // `gate` takes the commands (null: commands answer 503); `audit` may be null, else /api/audit
  // shows its entries (the gate records through it). `commission` may be null (then /api/commission
  // answers 404); it must outlive the server.
  static core::Result<std::unique_ptr<WebServer>> start(const WebConfig& config, runtime::LoopChannels& channels,
                                                        points::WriteGate* gate, RecentAudit* audit,
                                                        ModbusStatsFn modbus_stats = {}, StoreStatsFn store_stats = {},
                                                        CommissionPort* commission = nullptr);
  ~WebServer();
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  int port() const;
  // What the listener is bound to (getsockname): "127.0.0.1:8080", "[::1]:8080".
  const std::string& bound_address() const;
  void stop();

 private:
  struct Impl;
  explicit WebServer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace epa::web
