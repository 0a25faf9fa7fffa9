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
#include "modbus/slot_log.hpp"
#include "modbus/slot_policy.hpp"
#include "runtime/clock.hpp"

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
    out.push_back({c.session.address, c.connected_ns, c.last_valid_ns, c.served, writer || now_ns < c.session.unlocked_until_ns});
  }
  return out;
}
}  // namespace

struct ModbusServer::Impl {
  ServerConfig config;
  RequestHandler handler;
  modbus_t* ctx = nullptr;
  modbus_mapping_t* image = nullptr;
  int listener = -1;
  std::vector<ClientConnection> clients;
  runtime::MonotonicClock clock;
  Log log;
  SlotLog slot_log;
  std::vector<pollfd> fds;  // this round's: the listener, then each client in order
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
    if (image) modbus_mapping_free(image);
    if (ctx) modbus_free(ctx);
  }

  bool poll_round(bool& accept_ready);
  void accept_clients(std::int64_t now_ns);
  bool make_room(const std::string& ip, std::int64_t now_ns);
  void drop(std::size_t i, const char* why);
  bool receive(std::size_t i, std::int64_t now_ns);
  bool timed_out(std::size_t i, std::int64_t now_ns);
  int send_reply(ClientConnection& cl, std::size_t total, const Reply& reply);
};

namespace {
// Out of file descriptors, accept fails and the listener stays readable: it is left out of the
// poll this long, or the loop would spin on it (the clients already connected are served).
constexpr std::int64_t kAcceptPauseNs = 50'000'000;
constexpr int kPollTimeoutMs = 100;  // how often stop() is looked at with nothing to do
}  // namespace

// One poll over the listener (unless accepting is paused) and every client. Each client keeps its
// own result, so accepting and evicting cannot mix them up. False when poll failed for good.
bool ModbusServer::Impl::poll_round(bool& accept_ready) {
  const bool accepting = clock.now_ns() >= accept_paused_until_ns;
  fds.assign(1, pollfd{accepting ? listener : -1, POLLIN, 0});
  for (const auto& cl : clients) fds.push_back({cl.fd, POLLIN, 0});
  if (poll(fds.data(), fds.size(), kPollTimeoutMs) < 0 && errno != EINTR) return false;
  for (std::size_t i = 0; i < clients.size(); ++i) clients[i].revents = fds[i + 1].revents;
  accept_ready = (fds[0].revents & POLLIN) != 0;
  return true;
}

// Every connection waiting on the listener, each given a slot or closed at once.
void ModbusServer::Impl::accept_clients(std::int64_t now_ns) {
  for (;;) {
    sockaddr_storage peer{};  // IPv4 or IPv6; "::" hands IPv4 peers over as mapped addresses (ip_text unmaps them)
    socklen_t len = sizeof peer;
    const int fd = accept4(listener, reinterpret_cast<sockaddr*>(&peer), &len, SOCK_NONBLOCK | SOCK_CLOEXEC);
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
    clients.push_back({.fd = fd, .session = std::move(session), .buffer = {}, .idle_since_ns = now_ns, .frame_started_ns = -1,
                       .served = false, .connected_ns = now_ns, .last_valid_ns = -1, .revents = 0});
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
  ::close(clients[i].fd);
  clients.erase(clients.begin() + static_cast<std::ptrdiff_t>(i));
}

// What client `i` sent this round, appended to its buffer. False when it was dropped.
bool ModbusServer::Impl::receive(std::size_t i, std::int64_t now_ns) {
  ClientConnection& cl = clients[i];
  if (cl.revents & (POLLERR | POLLHUP | POLLNVAL)) return drop(i, "connection closed"), false;
  if (!(cl.revents & POLLIN)) return true;
  std::uint8_t chunk[4096];
  const ssize_t n = recv(cl.fd, chunk, sizeof chunk, 0);
  if (n <= 0) return drop(i, n == 0 ? "closed by the client" : std::strerror(errno)), false;
  if (cl.buffer.empty()) cl.frame_started_ns = now_ns;
  cl.buffer.insert(cl.buffer.end(), chunk, chunk + n);
  return true;
}

// Drops client `i` when its frame or its silence lasted too long. True when it was dropped.
bool ModbusServer::Impl::timed_out(std::size_t i, std::int64_t now_ns) {
  const ClientConnection& cl = clients[i];
  if (cl.frame_started_ns >= 0 && now_ns - cl.frame_started_ns > static_cast<std::int64_t>(config.frame_timeout_s * 1e9))
    return drop(i, "a frame not completed within frame_timeout_s of its first byte"), true;
  if (cl.frame_started_ns < 0 && now_ns - cl.idle_since_ns > static_cast<std::int64_t>(config.idle_timeout_s * 1e9))
    return drop(i, "idle"), true;
  return false;
}

// Sends the answer to the frame of `total` bytes at the head of `cl`'s buffer; < 0 when it failed.
int ModbusServer::Impl::send_reply(ClientConnection& cl, std::size_t total, const Reply& reply) {
  modbus_set_socket(ctx, cl.fd);
  if (reply.exception) return modbus_reply_exception(ctx, cl.buffer.data(), reply.exception);
  if (reply.pdu.empty()) return modbus_reply(ctx, cl.buffer.data(), static_cast<int>(total), image);
  // One send, as libmodbus' own replies: an answer of at most 260 bytes that the socket cannot
  // take whole means a client that does not read, and it is dropped.
  const auto adu = tcp_adu(cl.buffer.data(), reply.pdu);
  return ::send(cl.fd, adu.data(), adu.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(adu.size()) ? 0 : -1;
}

core::Result<std::unique_ptr<ModbusServer>> ModbusServer::start(const ServerConfig& c, const RegisterMap& map,
                                                                points::WriteGate& gate, runtime::LoopChannels& ch, Log log) {
  const std::string where = c.address + ":" + std::to_string(c.port);
  // Our own listener (IPv4 or IPv6, exactly the address given); libmodbus' context only builds
  // the answers, so its own address (it takes IPv4 only) is never used.
  auto address = core::parse_ip_address(c.address, c.port);
  if (!address) return core::invalid_argument("modbus: address " + address.error().message);
  auto impl = std::make_unique<Impl>(c, map, gate, ch, std::move(log));
  impl->ctx = modbus_new_tcp(nullptr, c.port);
  if (!impl->ctx) return core::io_error("modbus: cannot create the answering context: " + std::string(modbus_strerror(errno)));
  impl->image = new_register_image(map);  // bit tables padded to 16: the reserved bits read 0
  if (!impl->image) return core::io_error("modbus: cannot allocate the register image");
  auto listener = core::open_listener(*address, core::kListenBacklog, where);
  if (!listener) return core::io_error("modbus: " + listener.error().message);
  impl->listener = *listener;
  sockaddr_storage bound{};
  socklen_t len = sizeof bound;
  getsockname(impl->listener, reinterpret_cast<sockaddr*>(&bound), &len);
  std::unique_ptr<ModbusServer> server(new ModbusServer(std::move(impl)));
  server->port_ = core::port_of(bound);
  server->bound_ = core::endpoint_text(bound);
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
  bool accept_ready = false;
  while (!stop_.load() && m.poll_round(accept_ready)) {
    const std::int64_t now = m.clock.now_ns();
    if (accept_ready) m.accept_clients(now);
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
