#include "modbus/modbus_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <algorithm>
#include <cstring>
#include <vector>

#include <fmt/format.h>

#include "core/ip_address.hpp"
#include "core/listen_backlog.hpp"
#include "modbus/read_answer.hpp"
#include "modbus/slot_log.hpp"
#include "modbus/slot_policy.hpp"
#include "runtime/clock.hpp"
#include "tls/no_sigpipe.hpp"
#include "tls/refusal_log.hpp"
#include "tls/tls_connection.hpp"

namespace epa::modbus {

namespace {
constexpr int kMbapLength = 6;       // bytes before the MBAP length field's count starts
constexpr int kMaxAdu = MODBUS_TCP_MAX_ADU_LENGTH;
}  // namespace

// One connected client. Not in the anonymous namespace: ModbusServer::Impl holds them, and a member
// whose type has internal linkage is an error in the unity build (-Wsubobject-linkage).
struct ClientConnection {
  int fd = -1;
  Session session;   // address, "ip:port", this connection's unlock
  std::vector<std::uint8_t> buffer;
  std::int64_t idle_since_ns = 0;        // connected, or last request answered: bytes alone do not count
  std::int64_t frame_started_ns = -1;    // the first byte of the frame still incomplete; -1: none
  bool served = false;                   // has completed a request
  std::int64_t connected_ns = 0;
  std::int64_t last_valid_ns = -1;       // its last request answered without an exception (slot_policy)
  short revents = 0;                     // of this round's poll
  std::unique_ptr<tls::TlsConnection> tls;  // on the secure port: its TLS session; null on plain Modbus
  bool tls_wants_write = false;          // the handshake waits for the socket to take its bytes
};

namespace {
// The clients as the slot policy sees them: a client proves itself by its unlock or its address on
// write_clients (the history of valid requests the policy reads from the times).
std::vector<SlotHolder> slot_holders(const std::vector<ClientConnection>& clients, const WritePolicy& policy, std::int64_t now_ns) {
  std::vector<SlotHolder> out;
  out.reserve(clients.size());
  for (const ClientConnection& c : clients) {
    const auto& allowed = policy.write_clients;
    const bool writer = !allowed.empty() && std::find(allowed.begin(), allowed.end(), c.session.address) != allowed.end();
    // A TLS client whose certificate gives it rights to command has proved itself as an unlock
    // does; a viewer's certificate does not (16 viewer connections from one address held every slot).
    const bool certified = c.session.rights && *c.session.rights != points::Rights::kRead;
    out.push_back({c.session.address, c.connected_ns, c.last_valid_ns, c.served, writer || certified || now_ns < c.session.unlocked_until_ns});
  }
  return out;
}
}  // namespace

struct ModbusServer::Impl {
  ServerConfig config;
  RequestHandler handler;
  modbus_t* ctx = nullptr;
  modbus_mapping_t* image = nullptr;
  int listener = -1;         // plain Modbus; -1 when it is off
  int secure_listener = -1;  // Modbus/TCP Security; -1 when it is off
  std::unique_ptr<tls::ServerContext> tls_context;
  tls::RefusalLog refusal_log;
  int answer_pair[2] = {-1, -1};  // libmodbus writes an answer into [0], read back from [1] for TLS
  std::vector<ClientConnection> clients;
  runtime::MonotonicClock clock;
  Log log;
  SlotLog slot_log;
  std::vector<pollfd> fds;  // this round's: the two listeners, then each client in order
  std::int64_t accept_paused_until_ns = 0;

  Impl(const ServerConfig& c, const RegisterMap& map, points::WriteGate& gate, runtime::LoopChannels& ch, Log l)
      : config(c), handler(map, c.policy, unit_ids(c), c.status_page_url, gate, ch, l), log(std::move(l)) {}
  static std::vector<int> unit_ids(const ServerConfig& c) {
    std::vector<int> ids = {c.unit_id};
    ids.insert(ids.end(), c.alias_unit_ids.begin(), c.alias_unit_ids.end());
    return ids;
  }
  ~Impl() {
    for (auto& cl : clients) ::close(cl.fd);
    if (listener >= 0) ::close(listener);
    if (secure_listener >= 0) ::close(secure_listener);
    for (int fd : answer_pair)
      if (fd >= 0) ::close(fd);
    if (image) modbus_mapping_free(image);
    if (ctx) modbus_free(ctx);
  }

  bool poll_round(bool& accept_ready, bool& secure_ready);
  void accept_clients(int from, std::int64_t now_ns);
  bool make_room(const std::string& ip, std::int64_t now_ns);
  void drop(std::size_t i, const char* why);
  bool receive(std::size_t i, std::int64_t now_ns);
  bool receive_tls(std::size_t i, std::int64_t now_ns);
  bool finish_handshake(std::size_t i, std::int64_t now_ns);
  // A refused handshake, logged as the refusal log allows (once per address, then backed off).
  void log_refusal(const std::string& address, const std::string& why, std::int64_t now_ns) {
    if (const std::string line = refusal_log.refused(address, why, now_ns); log && !line.empty()) log("modbus-tls: " + line);
  }
  bool timed_out(std::size_t i, std::int64_t now_ns);
  int send_reply(ClientConnection& cl, std::size_t total, const Reply& reply);
  std::vector<std::uint8_t> answer_bytes(ClientConnection& cl, std::size_t total, const Reply& reply);
};

namespace {
// Out of file descriptors, accept fails and the listener stays readable: it is left out of the
// poll this long, or the loop would spin on it (the clients already connected are served).
constexpr std::int64_t kAcceptPauseNs = 50'000'000;
constexpr int kPollTimeoutMs = 100;  // how often stop() is looked at with nothing to do
constexpr std::size_t kReadBytes = 4096;  // taken from a client a round, as plain recv takes them
constexpr std::size_t kSecureListener = 1;  // fds: the plain listener, the secure one, then the clients
constexpr std::size_t kFirstClient = 2;
}  // namespace

// One poll over the listener (unless accepting is paused) and every client. Each client keeps its
// own result, so accepting and evicting cannot mix them up. False when poll failed for good.
bool ModbusServer::Impl::poll_round(bool& accept_ready, bool& secure_ready) {
  const bool accepting = clock.now_ns() >= accept_paused_until_ns;
  fds.assign(1, pollfd{accepting ? listener : -1, POLLIN, 0});
  fds.push_back({accepting ? secure_listener : -1, POLLIN, 0});
  bool decrypted_waiting = false;  // TLS holds bytes it decrypted beyond a round's read: no waiting for the socket
  for (const auto& cl : clients) {
    fds.push_back({cl.fd, static_cast<short>(POLLIN | (cl.tls_wants_write ? POLLOUT : 0)), 0});
    decrypted_waiting = decrypted_waiting || (cl.tls && cl.tls->has_pending());
  }
  if (poll(fds.data(), fds.size(), decrypted_waiting ? 0 : kPollTimeoutMs) < 0 && errno != EINTR) return false;
  for (std::size_t i = 0; i < clients.size(); ++i) {
    clients[i].revents = fds[i + kFirstClient].revents;
    if (clients[i].tls && clients[i].tls->has_pending()) clients[i].revents |= POLLIN;
  }
  accept_ready = (fds[0].revents & POLLIN) != 0;
  secure_ready = (fds[kSecureListener].revents & POLLIN) != 0;
  return true;
}

// Every connection waiting on listener `from`, each given a slot or closed at once. On the secure
// listener each starts its TLS handshake, which the poll rounds drive.
void ModbusServer::Impl::accept_clients(int from, std::int64_t now_ns) {
  for (;;) {
    sockaddr_storage peer{};  // IPv4 or IPv6; "::" hands IPv4 peers over as mapped addresses (ip_text unmaps them)
    socklen_t len = sizeof peer;
    const int fd = accept4(from, reinterpret_cast<sockaddr*>(&peer), &len, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0 && (errno == EMFILE || errno == ENFILE)) {
      slot_log.out_of_descriptors(now_ns);
      accept_paused_until_ns = now_ns + kAcceptPauseNs;
    }
    if (fd < 0) return;
    const std::string ip = core::ip_text(peer);
    if (!make_room(ip, now_ns)) {
      ::close(fd);
      continue;
    }
    const int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    sockaddr_storage local{};
    socklen_t local_len = sizeof local;
    const std::string local_ip = getsockname(fd, reinterpret_cast<sockaddr*>(&local), &local_len) == 0 ? core::url_host(local) : "";
    Session session{ip, core::endpoint_text(peer), 0, local_ip};
    session.opened_ns = now_ns;
    std::unique_ptr<tls::TlsConnection> tls;
    if (from == secure_listener) {
      auto accepted = tls::TlsConnection::accept(*tls_context, fd);
      if (!accepted) {
        if (log && slot_log.disconnect_line(now_ns)) log("modbus-tls: " + accepted.error().message);
        ::close(fd);
        continue;
      }
      tls = std::move(*accepted);
    }
    clients.push_back({.fd = fd, .session = std::move(session), .buffer = {}, .idle_since_ns = now_ns, .frame_started_ns = -1,
                       .served = false, .connected_ns = now_ns, .last_valid_ns = -1, .revents = 0, .tls = std::move(tls),
                       .tls_wants_write = false});
  }
}

// Room for a newcomer from `ip` (slot_policy.hpp): false when it is refused. An eviction or a
// refusal is counted for the summary line, not logged one by one.
bool ModbusServer::Impl::make_room(const std::string& ip, std::int64_t now_ns) {
  const Admission a = admit(slot_holders(clients, config.policy, now_ns), ip, now_ns, {config.max_clients, config.max_clients_per_address});
  if (a.kind == Admission::Kind::kRefuse) slot_log.refused(now_ns);
  if (a.kind == Admission::Kind::kEvict) slot_log.evicted(now_ns), drop(a.victim, nullptr);
  return a.kind != Admission::Kind::kRefuse;
}

// Closes client `i`; `why` (null: an eviction, counted elsewhere) goes to the log, rate-limited.
void ModbusServer::Impl::drop(std::size_t i, const char* why) {
  const std::int64_t now_ns = clock.now_ns();
  if (log && why && slot_log.disconnect_line(now_ns)) log(fmt::format("modbus: client {} disconnected ({})", clients[i].session.peer, why));
  handler.connection_closed(clients[i].session);
  if (clients[i].tls) clients[i].tls->shut_down();
  ::close(clients[i].fd);
  clients.erase(clients.begin() + static_cast<std::ptrdiff_t>(i));
}

// What client `i` sent this round, appended to its buffer. False when it was dropped.
bool ModbusServer::Impl::receive(std::size_t i, std::int64_t now_ns) {
  ClientConnection& cl = clients[i];
  if (cl.revents & (POLLERR | POLLHUP | POLLNVAL)) return drop(i, "connection closed"), false;
  if (cl.tls) return receive_tls(i, now_ns);
  if (!(cl.revents & POLLIN)) return true;
  std::uint8_t chunk[kReadBytes];
  const ssize_t n = recv(cl.fd, chunk, sizeof chunk, 0);
  if (n <= 0) return drop(i, n == 0 ? "closed by the client" : std::strerror(errno)), false;
  if (cl.buffer.empty()) cl.frame_started_ns = now_ns;
  cl.buffer.insert(cl.buffer.end(), chunk, chunk + n);
  return true;
}

// The secure client `i`'s handshake a step further, or what it sent, decrypted into its buffer.
// False when it was dropped.
bool ModbusServer::Impl::receive_tls(std::size_t i, std::int64_t now_ns) {
  ClientConnection& cl = clients[i];
  if (!(cl.revents & (POLLIN | POLLOUT))) return true;
  if (!cl.tls->handshake_done() && !finish_handshake(i, now_ns)) return false;
  if (!cl.tls->handshake_done()) return true;
  const bool was_empty = cl.buffer.empty();
  const tls::TlsConnection::Step step = cl.tls->read_into(cl.buffer, kReadBytes);
  if (was_empty && !cl.buffer.empty()) cl.frame_started_ns = now_ns;
  if (step == tls::TlsConnection::Step::kDone) return drop(i, "closed by the client"), false;
  if (step == tls::TlsConnection::Step::kFailed) return drop(i, cl.tls->failure().c_str()), false;
  return true;
}

// One step of client `i`'s handshake; once complete, its session takes the rights of its role.
// False when the handshake failed and the client was dropped (the refusal logged, held back).
bool ModbusServer::Impl::finish_handshake(std::size_t i, std::int64_t now_ns) {
  ClientConnection& cl = clients[i];
  const tls::TlsConnection::Step step = cl.tls->handshake();
  cl.tls_wants_write = step == tls::TlsConnection::Step::kWantWrite;
  if (step == tls::TlsConnection::Step::kFailed) {
    log_refusal(cl.session.address, cl.tls->failure(), now_ns);
    return drop(i, nullptr), false;
  }
  if (step != tls::TlsConnection::Step::kDone) return true;
  const tls::PeerIdentity& peer = cl.tls->peer();
  const auto role = std::ranges::find(config.secure.roles, peer.role, &RoleRights::role);  // the verification checked it is there
  cl.session.rights = role != config.secure.roles.end() ? role->rights : points::Rights::kRead;
  cl.session.role = peer.role;
  cl.session.subject = peer.subject;
  cl.idle_since_ns = now_ns;
  if (log && slot_log.disconnect_line(now_ns))
    log(fmt::format("modbus-tls: client {} connected as {}, role {} ({})", cl.session.peer, peer.subject, peer.role,
                    points::to_string(*cl.session.rights)));
  return true;
}

// Drops client `i` when its handshake, its frame or its silence lasted too long. True when it was dropped.
bool ModbusServer::Impl::timed_out(std::size_t i, std::int64_t now_ns) {
  const ClientConnection& cl = clients[i];
  if (cl.tls && !cl.tls->handshake_done() && now_ns - cl.connected_ns > static_cast<std::int64_t>(config.secure.handshake_timeout_s * 1e9)) {
    log_refusal(cl.session.address, "no handshake within handshake_timeout_s", now_ns);
    return drop(i, nullptr), true;
  }
  if (cl.frame_started_ns >= 0 && now_ns - cl.frame_started_ns > static_cast<std::int64_t>(config.frame_timeout_s * 1e9))
    return drop(i, "a frame not completed within frame_timeout_s of its first byte"), true;
  if (cl.frame_started_ns < 0 && now_ns - cl.idle_since_ns > static_cast<std::int64_t>(config.idle_timeout_s * 1e9))
    return drop(i, "idle"), true;
  return false;
}

// Sends the answer to the frame of `total` bytes at the head of `cl`'s buffer; < 0 when it failed.
int ModbusServer::Impl::send_reply(ClientConnection& cl, std::size_t total, const Reply& reply) {
  if (cl.tls) {
    const std::vector<std::uint8_t> adu = answer_bytes(cl, total, reply);
    return !adu.empty() && cl.tls->write(adu) ? 0 : -1;
  }
  modbus_set_socket(ctx, cl.fd);
  if (reply.exception) return modbus_reply_exception(ctx, cl.buffer.data(), reply.exception);
  if (reply.pdu.empty()) return modbus_reply(ctx, cl.buffer.data(), static_cast<int>(total), image);
  // One send, as libmodbus' own replies: an answer of at most 260 bytes that the socket cannot
  // take whole means a client that does not read, and it is dropped.
  const auto adu = tcp_adu(cl.buffer.data(), reply.pdu);
  return ::send(cl.fd, adu.data(), adu.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(adu.size()) ? 0 : -1;
}

// The answer's ADU as bytes, for a TLS client: reads built here (read_answer.hpp); libmodbus writes
// the other answers to a socket, so it writes them into a socket pair here and they are read back
// whole. Empty when that failed.
std::vector<std::uint8_t> ModbusServer::Impl::answer_bytes(ClientConnection& cl, std::size_t total, const Reply& reply) {
  if (reply.exception) {
    const std::uint8_t pdu[] = {static_cast<std::uint8_t>(cl.buffer[kMbapLength + 1] | 0x80), reply.exception};
    return tcp_adu(cl.buffer.data(), pdu);
  }
  if (!reply.pdu.empty()) return tcp_adu(cl.buffer.data(), reply.pdu);
  if (auto read = read_answer(cl.buffer.data() + kMbapLength + 1, static_cast<int>(total) - kMbapLength - 1, image))
    return tcp_adu(cl.buffer.data(), *read);  // the polls: no detour through the socket pair
  modbus_set_socket(ctx, answer_pair[0]);
  if (modbus_reply(ctx, cl.buffer.data(), static_cast<int>(total), image) < 0) return {};
  std::vector<std::uint8_t> adu(kMaxAdu);
  const ssize_t n = recv(answer_pair[1], adu.data(), adu.size(), MSG_DONTWAIT);
  if (n <= 0) return {};
  adu.resize(static_cast<std::size_t>(n));
  return adu;
}

namespace {
// A listener on `address`:`port`, and what it is bound to.
struct Bound {
  int fd = -1;
  int port = 0;
  std::string text;
};
core::Result<Bound> listen_on(const std::string& address_text, int port, const std::string& what) {
  const std::string where = address_text + ":" + std::to_string(port);
  auto address = core::parse_ip_address(address_text, port);
  if (!address) return core::invalid_argument(what + ": address " + address.error().message);
  auto listener = core::open_listener(*address, core::kListenBacklog, where);
  if (!listener) return core::io_error(what + ": " + listener.error().message);
  sockaddr_storage bound{};
  socklen_t len = sizeof bound;
  getsockname(*listener, reinterpret_cast<sockaddr*>(&bound), &len);
  return Bound{*listener, core::port_of(bound), core::endpoint_text(bound)};
}

std::vector<std::string> role_names(const SecureConfig& secure) {
  std::vector<std::string> names;
  for (const RoleRights& r : secure.roles) names.push_back(r.role);
  return names;
}
}  // namespace

core::Result<std::unique_ptr<ModbusServer>> ModbusServer::start(const ServerConfig& c, const RegisterMap& map,
                                                                points::WriteGate& gate, runtime::LoopChannels& ch, Log log) {
  // Our own listeners (IPv4 or IPv6, exactly the address given); libmodbus' context only builds
  // the answers, so its own address (it takes IPv4 only) is never used.
  auto impl = std::make_unique<Impl>(c, map, gate, ch, std::move(log));
  impl->ctx = modbus_new_tcp(nullptr, c.port);
  if (!impl->ctx) return core::io_error("modbus: cannot create the answering context: " + std::string(modbus_strerror(errno)));
  impl->image = new_register_image(map);  // bit tables padded to 16: the reserved bits read 0
  if (!impl->image) return core::io_error("modbus: cannot allocate the register image");
  Bound plain, secure;
  if (c.plain_enabled) {
    auto bound = listen_on(c.address, c.port, "modbus");
    if (!bound) return bound.error();
    plain = *bound;
    impl->listener = plain.fd;
  }
  if (c.secure.enabled) {
    auto context = tls::ServerContext::load(c.secure.files, {tls::ClientCertificate::kRequired, role_names(c.secure)});
    if (!context) return core::io_error("modbus_tls: " + context.error().message);
    impl->tls_context = std::move(*context);
    // A record's header and body, and what follows, in one read of the socket, not two. Safe here:
    // a client's bytes are read as soon as its handshake completes and until none are left.
    SSL_CTX_set_read_ahead(impl->tls_context->get(), 1);
    if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, impl->answer_pair) != 0)
      return core::io_error(std::string("modbus_tls: socketpair: ") + std::strerror(errno));
    auto bound = listen_on(c.secure.address, c.secure.port, "modbus_tls");
    if (!bound) return bound.error();
    secure = *bound;
    impl->secure_listener = secure.fd;
  }
  std::unique_ptr<ModbusServer> server(new ModbusServer(std::move(impl)));
  server->port_ = plain.port;
  server->bound_ = plain.text;
  server->secure_port_ = secure.port;
  server->secure_bound_ = secure.text;
  server->thread_ = std::thread([s = server.get()] { s->serve(); });
  return server;
}

ModbusServer::ModbusServer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

ModbusServer::~ModbusServer() { stop(); }

void ModbusServer::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void ModbusServer::serve() {
  Impl& m = *impl_;
  tls::block_sigpipe_on_this_thread();  // a TLS client gone mid-answer: EPIPE, not the process's end
  bool accept_ready = false, secure_ready = false;
  while (!stop_.load() && m.poll_round(accept_ready, secure_ready)) {
    const std::int64_t now = m.clock.now_ns();
    if (accept_ready) m.accept_clients(m.listener, now);
    if (secure_ready) m.accept_clients(m.secure_listener, now);
    // Clients in reverse, so dropping one does not disturb the indices still to visit.
    for (std::size_t i = m.clients.size(); i-- > 0;)
      if (m.receive(i, now) && !m.timed_out(i, now)) answer_frames(i, now);
    publish_counts(now);
  }
  const std::string line = m.slot_log.due(m.clock.now_ns(), m.config.max_clients, m.config.max_clients_per_address, true);
  if (m.log && !line.empty()) m.log(line);  // the count since the last summary, on the way out
  modbus_set_socket(m.ctx, -1);
}

// Answers every complete frame in client `i`'s buffer; a malformed header closes the connection.
void ModbusServer::answer_frames(std::size_t i, std::int64_t now_ns) {
  Impl& m = *impl_;
  ClientConnection& cl = m.clients[i];
  while (cl.buffer.size() >= static_cast<std::size_t>(kMbapLength + 1)) {
    const int protocol = (cl.buffer[2] << 8) | cl.buffer[3];
    const int count = (cl.buffer[4] << 8) | cl.buffer[5];
    if (protocol != 0 || count < 2 || kMbapLength + count > kMaxAdu) return m.drop(i, "malformed frame");
    const auto total = static_cast<std::size_t>(kMbapLength + count);
    if (cl.buffer.size() < total) return;
    // Function codes 128-255 are the exception answers' own: no request has one, and an
    // exception answer to it would wrap into a valid-looking function code.
    if (cl.buffer[kMbapLength + 1] & 0x80) return m.drop(i, "malformed frame: a function code of 128 or more");
    m.handler.set_clients(static_cast<int>(m.clients.size()));
    const Reply reply = m.handler.handle(cl.buffer.data(), static_cast<int>(total), cl.session, now_ns, m.image);
    const int rc = m.send_reply(cl, total, reply);
    requests_++;
    if (reply.exception) exceptions_++;
    if (rc < 0) return m.drop(i, "send failed");
    cl.buffer.erase(cl.buffer.begin(), cl.buffer.begin() + static_cast<std::ptrdiff_t>(total));
    cl.idle_since_ns = now_ns;
    cl.served = true;
    if (!reply.exception) cl.last_valid_ns = now_ns;
    cl.frame_started_ns = cl.buffer.empty() ? -1 : now_ns;  // a pipelined frame's clock starts now
  }
}

// The counters the accessors read, and the slot summary when one is due.
void ModbusServer::publish_counts(std::int64_t now_ns) {
  Impl& m = *impl_;
  clients_ = static_cast<int>(m.clients.size());
  evicted_ = m.slot_log.evicted_total();
  refused_ = m.slot_log.refused_total();
  if (const std::string line = m.slot_log.due(now_ns, m.config.max_clients, m.config.max_clients_per_address); m.log && !line.empty())
    m.log(line);
}

}  // namespace epa::modbus
