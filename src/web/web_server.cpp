#include "web/web_server.hpp"

#include <httplib.h>
#include <sys/socket.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <mutex>
#include <optional>
#include <thread>

#include "core/address_backoff.hpp"
#include "core/ip_address.hpp"
#include "core/listen_backlog.hpp"
#include "runtime/clock.hpp"
#include "tls/certificate_role.hpp"
#include "web/command_body.hpp"
#include "web/commission_port.hpp"
#include "web/deadline_http_server.hpp"
#include "web/elastic_task_queue.hpp"
#include "web/front_end_tls.hpp"
#include "web/host_check.hpp"
#include "web/prometheus.hpp"
#include "web/recent_audit.hpp"
#include "web/refusal_status.hpp"
#include "web/static_files.hpp"
#include "web/trend_buffer.hpp"

namespace epa::web {

namespace {

constexpr const char* kJson = "application/json";


// Compares without an early exit, so the time taken says nothing about how much of a guess was right.
bool constant_time_equal(const std::string& a, const std::string& b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  const std::size_t n = std::max(a.size(), b.size());
  for (std::size_t i = 0; i < n; ++i) {
    const unsigned char x = i < a.size() ? static_cast<unsigned char>(a[i]) : 0;
    const unsigned char y = i < b.size() ? static_cast<unsigned char>(b[i]) : 0;
    diff |= static_cast<unsigned char>(x ^ y);
  }
  return diff == 0;
}

void send_error(httplib::Response& res, int status, const std::string& message) {
  res.status = status;
  res.set_content(error_json(message), kJson);
}

// The request head a status page or an HMI sends is a few hundred bytes; these are generous.
constexpr std::size_t kMaxHeaderFields = 64;
constexpr std::size_t kMaxHeadBytes = 8192;
constexpr std::size_t kMaxRequestBytes = 64 * 1024;  // beyond it a request is cut unread (431), not parsed
constexpr std::size_t kIdleWorkers = 4;  // kept when nothing happens; more start per connection

// On every answer. The page loads only its own files (no inline script or style), so the policy
// allows nothing else; no other site may frame it (clickjacking the command panel) or learn its URL.
constexpr const char* kPageCsp =
    "default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' data:; connect-src 'self'; "
    "object-src 'none'; base-uri 'none'; form-action 'self'; frame-ancestors 'none'";
// The commissioning report is one self-contained HTML file with its own <style> and no script.
constexpr const char* kReportCsp = "default-src 'none'; style-src 'unsafe-inline'; img-src data:; frame-ancestors 'none'";

// Who a request's client certificate says its client is; none over plain HTTP, without a
// certificate, or with one the handshake did not verify (it refuses those; checked again here).
struct CertifiedClient {
  std::string subject;  // "/CN=eng"
  std::string role;     // "" when it names none
};

std::optional<CertifiedClient> certified_client(const httplib::Request& req) {
  if (!req.ssl || SSL_get_verify_result(req.ssl) != X509_V_OK) return std::nullopt;
  X509* cert = SSL_get0_peer_certificate(req.ssl);
  if (!cert) return std::nullopt;
  CertifiedClient who{tls::subject_of(cert), ""};
  if (auto role = tls::role_of(cert); role && *role) who.role = **role;
  return who;
}

httplib::Headers security_headers() {
  return {{"X-Frame-Options", "DENY"},
          {"X-Content-Type-Options", "nosniff"},
          {"Referrer-Policy", "no-referrer"},
          {"Content-Security-Policy", kPageCsp}};
}

HttpsSettings https_settings(const WebConfig& c) {
  HttpsSettings s{c.tls_files, c.client_certificates, {}};
  for (const CertificateRole& r : c.roles) s.roles.push_back(r.role);
  return s;
}

}  // namespace

struct WebServer::Impl {
  WebConfig config;
  runtime::LoopChannels& channels;
  // The loop's snapshot with the accepted writes it has not taken yet (read after write).
  runtime::Snapshot snapshot() const { return gate ? gate->snapshot() : channels.snapshot.read(); }
  points::HealthReport health_report(bool with_trend) const {
    if (gate) return gate->health_report(with_trend);
    points::HealthReport r;
    r.reason = "this server has no write gate, so no model-health monitor";
    return r;
  }
  points::WriteGate* gate;
  RecentAudit* audit;
  ModbusStatsFn modbus_stats;
  StoreStatsFn store_stats;
  CommissionPort* commission;
  DeadlineHttpServer server;
  TrendBuffer trend;
  std::string chart_js;
  int port = 0;
  std::string bound;  // getsockname of the listener: "127.0.0.1:8080", "[::1]:8080"
  std::atomic<std::uint64_t> requests{0};
  std::atomic<bool> listen_returned{false};

  std::mutex stop_mutex;
  std::condition_variable stop_cv;
  bool stopping = false;
  std::thread listener, sampler;

  StaticFiles static_files;  // read once at start (static_files.hpp says why)
  HostCheck hosts;
  std::mutex token_mutex;
  core::AddressBackoff token_guesses;  // by connection and by client address, under token_mutex
  // The trend's JSON is the dearest answer (every sample of the window): made at most once per
  // sampling period (50 ms) and shared, so that clients pipelining trend requests on 1,500
  // connections cannot take the CPU the status poll needs (60 % of polls within 1 s before).
  std::mutex trend_mutex;
  std::chrono::steady_clock::time_point trend_made{};
  std::shared_ptr<const std::string> trend_cached;
  std::shared_ptr<const std::string> trend_body() {
    std::lock_guard lock(trend_mutex);  // held while it is made: concurrent requests wait for one, not make their own
    const auto now = std::chrono::steady_clock::now();
    if (!trend_cached || now - trend_made >= std::chrono::milliseconds(50)) {
      trend_cached = std::make_shared<const std::string>(trend_json(trend.points(), channels.snapshot.read()));
      trend_made = now;
    }
    return trend_cached;
  }
  runtime::MonotonicClock clock;

  Impl(const WebConfig& c, runtime::LoopChannels& ch, points::WriteGate* g, RecentAudit* a, ModbusStatsFn m, StoreStatsFn st,
       CommissionPort* cp)
      : config(c),
        channels(ch),
        gate(g),
        audit(a),
        modbus_stats(std::move(m)),
        store_stats(std::move(st)),
        commission(cp),
        server(request_limits(c), c.log, security_headers()),
        hosts(c.host_names) {}

  static RequestLimits request_limits(const WebConfig& c) {
    RequestLimits limits;
    limits.request_deadline = std::chrono::milliseconds(c.request_deadline_ms);
    limits.handshake_timeout = limits.request_deadline;  // a TLS handshake is bounded as a request is
    limits.max_request_bytes = kMaxRequestBytes;
    limits.max_header_fields = kMaxHeaderFields;
    limits.max_connections_per_address = static_cast<std::size_t>(c.max_connections_per_address);
    return limits;
  }

  ModbusStats modbus() const { return modbus_stats ? modbus_stats() : ModbusStats{}; }
  StoreStats store() const { return store_stats ? store_stats() : StoreStats{}; }
  bool commands_enabled() const { return !config.token.empty(); }  // the page's command panel: it sends the token
  bool certificates_log_in() const { return config.tls && config.client_certificates == ClientCertificates::kOptional; }

  void sample_until_stopped() {
    std::unique_lock lock(stop_mutex);
    while (!stopping) {
      lock.unlock();
      trend.add(channels.snapshot.read());
      lock.lock();
      stop_cv.wait_for(lock, std::chrono::duration<double>(TrendBuffer::kPeriodS), [this] { return stopping; });
    }
  }

  // The token rule: none configured -> commands are off (403); else the bearer token must match
  // (401); a connection that sent 5 wrong tokens is refused unseen (429) for a back-off, and an
  // address that sent 5 is heard only on connections that sent no wrong token and sent their first
  // command 2 s before (core::AddressBackoff), so a token cannot be guessed at request speed and a
  // guesser on an operator's address does not lock the operator out. httplib does not tell when a
  // connection was opened: "ip:port" is the connection, its first command starts its clock.
  bool authorised(const httplib::Request& req, httplib::Response& res) {
    if (config.token.empty()) {
      send_error(res, 403, certificates_log_in() ? "commands need a client certificate whose role may write, or a [web] token"
                                                 : "commands are disabled: configure [web] token to enable them");
      return false;
    }
    const std::int64_t now_ns = clock.now_ns();
    std::unique_lock lock(token_mutex);
    const core::Guesser who{req.remote_addr, req.remote_addr + ":" + std::to_string(req.remote_port), -1};
    if (const std::int64_t until_ns = token_guesses.refused_until(who, now_ns); until_ns != 0) {
      const auto wait_s = std::to_string((until_ns - now_ns) / 1'000'000'000 + 1);
      res.set_header("Retry-After", wait_s);
      send_error(res, 429, "too many wrong tokens from " + req.remote_addr + ": try again in " + wait_s + " s");
      return false;
    }
    const std::string header = req.get_header_value("Authorization");
    const std::string prefix = "bearer ";  // the scheme is case-insensitive (RFC 9110 11.1)
    const bool bearer = header.size() >= prefix.size() &&
                        std::equal(prefix.begin(), prefix.end(), header.begin(),
                                   [](char p, char h) { return p == std::tolower(static_cast<unsigned char>(h)); });
    if (bearer && constant_time_equal(header.substr(prefix.size()), config.token)) {
      token_guesses.right(who);
      return true;
    }
    const auto lockout = token_guesses.wrong(who, now_ns);
    lock.unlock();
    if (lockout.started && config.log)
      config.log("web: wrong tokens from " + who.connection + ": " +
                 (lockout.address_started ? "commands from " + req.remote_addr + " are refused for " +
                                                std::to_string(lockout.backoff_ns / 1'000'000'000) +
                                                " s, except on a connection that sent no wrong token and its first command 2 s before"
                                          : "its commands are refused for " + std::to_string(lockout.backoff_ns / 1'000'000'000) + " s"));
    res.set_header("WWW-Authenticate", "Bearer");
    send_error(res, 401, "missing or wrong token: send 'Authorization: Bearer <token>'");
    return false;
  }

  // Who sends a command, with what rights: a client certificate by its role, else the token
  // (authorised()). None when the request is refused; `res` then holds the refusal. Commissioning
  // (`tuning`) needs the rights to tune; the token gives them.
  std::optional<points::Requester> commander(const httplib::Request& req, httplib::Response& res, bool tuning = false) {
    if (const auto cert = certified_client(req)) return by_certificate(*cert, req, res, tuning);
    if (!authorised(req, res)) return std::nullopt;
    return points::Requester{"web " + req.remote_addr, true, "", /*tuning_unlocked=*/true};  // the token is the unlock
  }

  // Who the request's client certificate says its client is, and its role's rights ("" when the
  // role is not in the table); none without one.
  std::optional<CertificateLogin> certificate_login(const httplib::Request& req) const {
    const auto cert = certified_client(req);
    if (!cert) return std::nullopt;
    const auto role = std::ranges::find(config.roles, cert->role, &CertificateRole::role);
    return CertificateLogin{cert->subject, cert->role, role == config.roles.end() ? "" : std::string(points::to_string(role->rights))};
  }

  // A client certificate's role and its rights in the role table; a token it may carry is not looked at.
  std::optional<points::Requester> by_certificate(const CertifiedClient& cert, const httplib::Request& req, httplib::Response& res,
                                                  bool tuning) {
    const auto role = std::ranges::find(config.roles, cert.role, &CertificateRole::role);
    if (cert.role.empty() || role == config.roles.end()) {
      send_error(res, 403, "certificate " + cert.subject + ": " +
                               (cert.role.empty() ? "it names no role" : "its role \"" + cert.role + "\" is not in [modbus_tls.roles]"));
      return std::nullopt;
    }
    const std::string source = "web " + req.remote_addr + " " + cert.subject + " (" + cert.role + ")";
    points::Requester who = points::requester_with_rights(source, cert.subject, cert.role, role->rights);
    // A command goes to the write gate, which refuses what the role may not write; commissioning
    // does not go through it, so its rights are checked here.
    if (tuning && !who.tuning_unlocked) {
      send_error(res, 403, who.may_write ? who.tuning_locked_reason : who.no_write_reason);
      return std::nullopt;
    }
    return who;
  }

  // The page's files, from memory (static_files.hpp).
  void serve_static(const httplib::Request& req, httplib::Response& res) {
    const StaticFile* file = static_files.find(req.path);
    if (!file) return send_error(res, 404, "no such resource");
    res.set_content(file->body, file->content_type);
  }

  // A command: the client's rights (certificate or token), then the body read into point writes,
  // then the write gate decides (and audits what it takes); its refusal becomes 400, 403, 409 or
  // 503 with the gate's reason.
  void command(CommandEndpoint endpoint, const httplib::Request& req, httplib::Response& res) {
    const auto who = commander(req, res);
    if (!who) return;
    const CommandBody body = parse_command_body(endpoint, req.body);
    if (!body.error.empty()) return send_error(res, 400, body.error);
    if (!gate) return send_error(res, 503, "this server takes no commands (no write gate)");
    const points::GateResult r = gate->submit(body.writes, *who);
    if (!r.accepted()) return send_error(res, http_status(r.refusal), r.reason);
    res.set_content(R"({"accepted":true})", kJson);
  }

  // Commissioning: starting and aborting need the token or a certificate with tuning rights;
  // progress, result and report are read like the status.
  void commission_routes() {
    auto& s = server;
    auto none = [](httplib::Response& res) { send_error(res, 404, "this appliance runs no commissioning service"); };
    s.Get("/api/commission", [this, none](const httplib::Request&, httplib::Response& res) {
      if (!commission) return none(res);
      res.set_content(commission->status_json(), kJson);
    });
    s.Get("/api/commission/result", [this, none](const httplib::Request&, httplib::Response& res) {
      if (!commission) return none(res);
      const auto j = commission->result_json();
      if (!j) return send_error(res, 404, "no commissioning run has ended yet");
      res.set_content(*j, kJson);
    });
    s.Get("/api/commission/report", [this, none](const httplib::Request&, httplib::Response& res) {
      if (!commission) return none(res);
      const auto html = commission->report_html();
      if (!html) return send_error(res, 404, "no commissioning run has ended yet");
      res.headers.erase("Content-Security-Policy");
      res.set_header("Content-Security-Policy", kReportCsp);
      res.set_content(*html, "text/html; charset=utf-8");
    });
    s.Post("/api/commission", [this, none](const httplib::Request& req, httplib::Response& res) {
      const auto who = commander(req, res, /*tuning=*/true);
      if (!who) return;
      if (!commission) return none(res);
      const auto r = commission->start(req.body, who->source);
      if (r.result == points::CommissionStart::kBadSpec) return send_error(res, 400, r.message);
      if (r.result == points::CommissionStart::kBusy) return send_error(res, 409, r.message);
      res.status = 202;
      res.set_content(R"({"accepted":true})", kJson);
    });
    s.Post("/api/commission/abort", [this, none](const httplib::Request& req, httplib::Response& res) {
      const auto who = commander(req, res, /*tuning=*/true);
      if (!who) return;
      if (!commission) return none(res);
      if (!commission->abort(who->source)) return send_error(res, 409, "no commissioning run is under way");
      res.set_content(R"({"accepted":true})", kJson);
    });
  }

  void routes() {
    auto& s = server;
    s.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
      if (!server.warming_up()) requests.fetch_add(1, std::memory_order_relaxed);  // clients' requests only
      res.set_header("Cache-Control", "no-store");
      if (!hosts.allowed(req.get_header_value("Host"), req.local_addr)) {
        res.set_header("Connection", "close");
        send_error(res, 421, "this appliance does not answer to the name '" + req.get_header_value("Host") +
                                 "': open it by its address, or list the name in [web] host_names");
        return httplib::Server::HandlerResponse::Handled;
      }
      // A cap on the head's bytes (its fields are counted as they arrive: deadline_http_server.cpp),
      // and a declared body over the cap refused before any of it is read.
      std::size_t head_bytes = req.method.size() + req.target.size();
      for (const auto& [k, v] : req.headers) head_bytes += k.size() + v.size() + 4;
      if (head_bytes > kMaxHeadBytes) {
        res.set_header("Connection", "close");
        send_error(res, 431, "request head too large (at most " + std::to_string(kMaxHeaderFields) + " fields, " +
                                 std::to_string(kMaxHeadBytes) + " bytes)");
        return httplib::Server::HandlerResponse::Handled;
      }
      const std::string length = req.get_header_value("Content-Length");
      const bool digits = !length.empty() && length.find_first_not_of("0123456789") == std::string::npos;
      if (digits && (length.size() > 18 || std::stoull(length) > config.max_body_bytes)) {
        res.set_header("Connection", "close");
        send_error(res, 413, "request body too large (at most " + std::to_string(config.max_body_bytes) + " bytes)");
        return httplib::Server::HandlerResponse::Handled;
      }
      return httplib::Server::HandlerResponse::Unhandled;
    });
    s.Get("/api/status", [this](const httplib::Request& req, httplib::Response& res) {
      // A client whose certificate's role may command sees the command panel without a token.
      const std::optional<CertificateLogin> login = certificate_login(req);
      const bool commands = commands_enabled() || (login && !login->rights.empty() && login->rights != points::to_string(points::Rights::kRead));
      res.set_content(status_json(snapshot(), modbus(), commands, store(), health_report(false), login), kJson);
    });
    s.Get("/api/health", [this](const httplib::Request&, httplib::Response& res) { res.set_content(health_json(health_report(true)), kJson); });
    s.Get("/api/trend", [this](const httplib::Request&, httplib::Response& res) { res.set_content(*trend_body(), kJson); });
    s.Get("/api/moves", [this](const httplib::Request&, httplib::Response& res) {
      res.set_content(moves_json(trend.moves()), kJson);
    });
    s.Get("/api/tuning", [this](const httplib::Request&, httplib::Response& res) {
      res.set_content(tuning_json(snapshot()), kJson);
    });
    s.Get("/api/points", [this](const httplib::Request&, httplib::Response& res) {
      if (!gate) return send_error(res, 404, "no point catalog on this server");
      res.set_content(points_json(gate->limits()), kJson);
    });
    s.Get("/api/records", [this](const httplib::Request&, httplib::Response& res) {
      if (!gate) return send_error(res, 404, "no position-record table on this server (no write gate)");
      res.set_content(records_json(gate->records(), gate->record_select()), kJson);
    });
    s.Get("/api/audit", [this](const httplib::Request&, httplib::Response& res) {
      res.set_content(audit_json(audit ? audit->entries() : std::vector<core::AuditEntry>{}), kJson);
    });
    s.Get("/api/faults", [this](const httplib::Request&, httplib::Response& res) {
      std::uint64_t count = 0;
      const auto faults = channels.fault_history.newest(runtime::kFaultHistoryEntries, &count);
      res.set_content(faults_json(count, faults, channels.snapshot.read().fault_events_dropped), kJson);
    });
    s.Get("/metrics", [this](const httplib::Request&, httplib::Response& res) {
      res.set_content(prometheus_text(channels.snapshot.read(), modbus(), requests.load(), gate ? gate->health_view() : points::HealthView{}),
                      "text/plain; version=0.0.4; charset=utf-8");
    });
    s.Get("/vendor/chart.js", [this](const httplib::Request&, httplib::Response& res) {
      if (chart_js.empty()) return send_error(res, 404, "Chart.js is not installed (" + config.chart_js + "; Debian: libjs-chart.js)");
      res.headers.erase("Cache-Control");  // a fixed file: the browser may keep it
      res.set_header("Cache-Control", "max-age=86400");
      res.set_content(chart_js, "text/javascript");
    });
    s.Post("/api/setpoint", [this](const httplib::Request& q, httplib::Response& r) { command(CommandEndpoint::kSetpoint, q, r); });
    s.Post("/api/mode", [this](const httplib::Request& q, httplib::Response& r) { command(CommandEndpoint::kMode, q, r); });
    s.Post("/api/reset", [this](const httplib::Request& q, httplib::Response& r) { command(CommandEndpoint::kReset, q, r); });
    s.Post("/api/points", [this](const httplib::Request& q, httplib::Response& r) { command(CommandEndpoint::kPoints, q, r); });
    s.Post("/api/records", [this](const httplib::Request& q, httplib::Response& r) { command(CommandEndpoint::kRecord, q, r); });
    commission_routes();
    s.Get(R"(/.*)", [this](const httplib::Request& q, httplib::Response& r) { serve_static(q, r); });  // last: the page

    // Every error leaves as JSON: httplib's own (404 no route, 413 payload too large, 400 bad request) included.
    s.set_error_handler(httplib::Server::HandlerWithResponse([](const httplib::Request&, httplib::Response& res) {
      if (!res.body.empty()) return httplib::Server::HandlerResponse::Unhandled;
      const char* what = res.status == 404   ? "no such resource"
                         : res.status == 413 ? "request body too large"
                         : res.status == 414 ? "request URI too long"
                         : res.status == 405 ? "method not allowed"
                         : res.status >= 500 ? "internal error"
                                             : "bad request";
      res.set_content(error_json(what), kJson);
      return httplib::Server::HandlerResponse::Handled;
    }));
    s.set_exception_handler([](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
      std::string what = "internal error";
      try {
        if (ep) std::rethrow_exception(ep);
      } catch (const std::exception& e) {
        what += std::string(": ") + e.what();
      } catch (...) {
      }
      send_error(res, 500, what);
    });
  }
};

core::Result<std::unique_ptr<WebServer>> WebServer::start(const WebConfig& config, runtime::LoopChannels& channels,
                                                          points::WriteGate* gate, RecentAudit* audit,
                                                          ModbusStatsFn modbus_stats, StoreStatsFn store_stats,
                                                   CommissionPort* commission) {
  if (config.worker_threads < 1) return core::invalid_argument("web: worker_threads must be >= 1");
  auto impl = std::make_unique<Impl>(config, channels, gate, audit, std::move(modbus_stats), std::move(store_stats), commission);
  if (config.max_connections_per_address < 1) return core::invalid_argument("web: max_connections_per_address must be >= 1");
  if (config.tls) {
    auto tls = FrontEndTls::load(https_settings(config));
    if (!tls) return core::io_error("web: tls: " + tls.error().message);
    impl->server.use_tls(std::move(*tls));
  }
  auto files = StaticFiles::load(config.static_dir, {"index.html", "app.js", "style.css"});
  if (!files) return files.error();
  impl->static_files = std::move(*files);
  if (config.log && !impl->static_files.skipped.empty()) {
    std::string names;
    for (const auto& s : impl->static_files.skipped) names += (names.empty() ? "" : ", ") + s;
    config.log("web: static_dir '" + config.static_dir + "': not served: " + names);
  }
  {
    std::ifstream in(config.chart_js, std::ios::binary);
    std::stringstream ss;
    if (in) ss << in.rdbuf(), impl->chart_js = ss.str();  // empty: /vendor/chart.js answers 404 and the page shows numbers only
  }
  auto& s = impl->server;
  const int threads = config.worker_threads;
  s.new_task_queue = [threads] {
    return new ElasticTaskQueue(kIdleWorkers, static_cast<std::size_t>(threads), std::chrono::seconds(5));
  };
  s.set_default_headers(security_headers());
  s.set_payload_max_length(config.max_body_bytes);  // timeouts and keep-alive: RequestLimits
  // Debian's libcpp-httplib is built with a listen queue of 5; the hook that sets the listening
  // socket's options is where its descriptor can be seen, to listen again with the larger queue.
  auto listening_socket = std::make_shared<socket_t>(INVALID_SOCKET);
  // Not httplib's default options: they set SO_REUSEPORT, with which a second appliance binds the
  // same port without an error and the kernel shares the connections between the two, so an
  // operator's page shows either axis. SO_REUSEADDR alone lets a restart bind past TIME_WAIT.
  s.set_socket_options([listening_socket](socket_t sock) {
    const int yes = 1;
    ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    *listening_socket = sock;
  });
  impl->routes();

  // Exactly an IP address: httplib would resolve a name, and bind what the resolver says.
  if (auto a = core::parse_ip_address(config.address, config.port); !a) return core::invalid_argument("web: address " + a.error().message);
  if (config.port == 0) {
    impl->port = s.bind_to_any_port(config.address);
    if (impl->port <= 0) return core::io_error("web: cannot bind to " + config.address + " (any port)");
  } else {
    if (!s.bind_to_port(config.address, config.port))
      return core::io_error("web: cannot bind to " + config.address + ":" + std::to_string(config.port) +
                            " (in use, or not an address of this host?)");
    impl->port = config.port;
  }
  if (*listening_socket == INVALID_SOCKET || ::listen(*listening_socket, core::kListenBacklog) != 0)
    return core::io_error("web: cannot enlarge the listen queue of " + config.address + ":" + std::to_string(impl->port));
  impl->bound = core::bound_endpoint(*listening_socket);
  Impl* p = impl.get();
  p->sampler = std::thread([p] { p->sample_until_stopped(); });
  p->listener = std::thread([p] {
    p->server.serve_after_bind();
    p->listen_returned = true;
  });
  return std::unique_ptr<WebServer>(new WebServer(std::move(impl)));
}

WebServer::WebServer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
WebServer::~WebServer() { stop(); }

int WebServer::port() const { return impl_->port; }
const std::string& WebServer::bound_address() const { return impl_->bound; }

void WebServer::stop() {
  {
    std::lock_guard lock(impl_->stop_mutex);
    impl_->stopping = true;
  }
  impl_->stop_cv.notify_all();
  if (impl_->listener.joinable()) {
    impl_->server.stop_serving();  // also when it has not begun: then it returns at once
    impl_->listener.join();
  }
  if (impl_->sampler.joinable()) impl_->sampler.join();
}

}  // namespace epa::web
