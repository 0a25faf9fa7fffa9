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
};

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
  std::vector<pollfd> fds;
  std::uint8_t chunk[4096];
  const auto idle_ns = static_cast<std::int64_t>(m.config.idle_timeout_s * 1e9);
  const auto frame_ns = static_cast<std::int64_t>(m.config.frame_timeout_s * 1e9);
  auto drop = [&](std::size_t i, const char* why) {
    const std::int64_t now_ns = m.clock.now_ns();
    if (m.log && why && m.slot_log.disconnect_line(now_ns))
      m.log("modbus: client " + m.clients[i].session.peer + " disconnected (" + why + ")");
    m.handler.connection_closed(m.clients[i].session);
    ::close(m.clients[i].fd);
    m.clients.erase(m.clients.begin() + static_cast<std::ptrdiff_t>(i));
  };
  // Room for a newcomer from `ip` (slot_policy.hpp): false when it is refused. An eviction or a
  // refusal is counted for the summary line, not logged one by one.
  auto make_room = [&](const std::string& ip, std::int64_t now_ns) {
    const Admission a = admit(slot_holders(m.clients, m.config.policy, now_ns), ip, now_ns, {m.config.max_clients, m.config.max_clients_per_address});
    if (a.kind == Admission::Kind::kRefuse) m.slot_log.refused(now_ns);
    if (a.kind == Admission::Kind::kEvict) m.slot_log.evicted(now_ns), drop(a.victim, nullptr);
    return a.kind != Admission::Kind::kRefuse;
  };

  // Out of file descriptors, accept fails and the listener stays readable: it is left out of the
  // poll for kAcceptPauseNs, or the loop would spin on it (the clients already connected are served).
  constexpr std::int64_t kAcceptPauseNs = 50'000'000;
  std::int64_t accept_paused_until_ns = 0;
  while (!stop_.load()) {
    const bool accepting = m.clock.now_ns() >= accept_paused_until_ns;
    fds.assign(1, pollfd{accepting ? m.listener : -1, POLLIN, 0});
    for (const auto& cl : m.clients) fds.push_back({cl.fd, POLLIN, 0});
    if (poll(fds.data(), fds.size(), 100) < 0 && errno != EINTR) break;
    const std::int64_t now = m.clock.now_ns();
    // Each client keeps its own poll result, so accepting and evicting below cannot mix them up.
    for (std::size_t i = 0; i < m.clients.size(); ++i) m.clients[i].revents = fds[i + 1].revents;

    if (fds[0].revents & POLLIN) {
      for (;;) {
        sockaddr_storage peer{};  // IPv4 or IPv6; "::" hands IPv4 peers over as mapped addresses (ip_text unmaps them)
        socklen_t len = sizeof peer;
        const int fd = accept4(m.listener, reinterpret_cast<sockaddr*>(&peer), &len, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd < 0 && (errno == EMFILE || errno == ENFILE)) {
          m.slot_log.out_of_descriptors(now);
          accept_paused_until_ns = now + kAcceptPauseNs;
        }
        if (fd < 0) break;
        const std::string ip = core::ip_text(peer);
        if (!make_room(ip, now)) {
          ::close(fd);
          continue;
        }
        const int one = 1;
        setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        sockaddr_storage local{};
        socklen_t local_len = sizeof local;
        const std::string local_ip = getsockname(fd, reinterpret_cast<sockaddr*>(&local), &local_len) == 0 ? core::url_host(local) : "";
        Session session{ip, core::endpoint_text(peer), 0, local_ip};
        session.opened_ns = now;
        m.clients.push_back({.fd = fd, .session = std::move(session), .buffer = {}, .idle_since_ns = now, .frame_started_ns = -1,
                             .served = false, .connected_ns = now, .last_valid_ns = -1, .revents = 0});
      }
    }

    // Clients in reverse, so dropping one does not disturb the indices still to visit.
    for (std::size_t i = m.clients.size(); i-- > 0;) {
      ClientConnection& cl = m.clients[i];
      const short revents = cl.revents;
      if (revents & (POLLERR | POLLHUP | POLLNVAL)) { drop(i, "connection closed"); continue; }
      if (revents & POLLIN) {
        const ssize_t n = recv(cl.fd, chunk, sizeof chunk, 0);
        if (n <= 0) { drop(i, n == 0 ? "closed by the client" : std::strerror(errno)); continue; }
        if (cl.buffer.empty()) cl.frame_started_ns = now;
        cl.buffer.insert(cl.buffer.end(), chunk, chunk + n);
      }
      if (cl.frame_started_ns >= 0 && now - cl.frame_started_ns > frame_ns) {
        drop(i, "a frame not completed within frame_timeout_s of its first byte");
        continue;
      }
      if (cl.frame_started_ns < 0 && now - cl.idle_since_ns > idle_ns) {
        drop(i, "idle");
        continue;
      }
      // Every complete frame in the buffer; a malformed header closes the connection.
      bool dropped = false;
      while (cl.buffer.size() >= static_cast<std::size_t>(kMbapLength + 1)) {
        const int protocol = (cl.buffer[2] << 8) | cl.buffer[3];
        const int count = (cl.buffer[4] << 8) | cl.buffer[5];
        if (protocol != 0 || count < 2 || kMbapLength + count > kMaxAdu) { drop(i, "malformed frame"); dropped = true; break; }
        const auto total = static_cast<std::size_t>(kMbapLength + count);
        if (cl.buffer.size() < total) break;
        // Function codes 128-255 are the exception answers' own: no request has one, and an
        // exception answer to it would wrap into a valid-looking function code.
        if (cl.buffer[kMbapLength + 1] & 0x80) { drop(i, "malformed frame: a function code of 128 or more"); dropped = true; break; }
        m.handler.set_clients(static_cast<int>(m.clients.size()));
        const Reply reply = m.handler.handle(cl.buffer.data(), static_cast<int>(total), cl.session, now, m.image);
        modbus_set_socket(m.ctx, cl.fd);
        int rc = 0;
        if (reply.exception) {
          rc = modbus_reply_exception(m.ctx, cl.buffer.data(), reply.exception);
        } else if (!reply.pdu.empty()) {
          // One send, as libmodbus' own replies: an answer of at most 260 bytes that the socket
          // cannot take whole means a client that does not read, and it is dropped.
          const auto adu = tcp_adu(cl.buffer.data(), reply.pdu);
          rc = ::send(cl.fd, adu.data(), adu.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(adu.size()) ? 0 : -1;
        } else {
          rc = modbus_reply(m.ctx, cl.buffer.data(), static_cast<int>(total), m.image);
        }
        requests_++;
        if (reply.exception) exceptions_++;
        if (rc < 0) { drop(i, "send failed"); dropped = true; break; }
        cl.buffer.erase(cl.buffer.begin(), cl.buffer.begin() + static_cast<std::ptrdiff_t>(total));
        cl.idle_since_ns = now;
        cl.served = true;
        if (!reply.exception) cl.last_valid_ns = now;
        cl.frame_started_ns = cl.buffer.empty() ? -1 : now;  // a pipelined frame's clock starts now
      }
      if (dropped) continue;
    }
    clients_ = static_cast<int>(m.clients.size());
    evicted_ = m.slot_log.evicted_total();
    refused_ = m.slot_log.refused_total();
    if (const std::string line = m.slot_log.due(now, m.config.max_clients, m.config.max_clients_per_address); m.log && !line.empty())
      m.log(line);
  }
  const std::string line = m.slot_log.due(m.clock.now_ns(), m.config.max_clients, m.config.max_clients_per_address, true);
  if (m.log && !line.empty()) m.log(line);  // the count since the last summary, on the way out
  modbus_set_socket(m.ctx, -1);
}

}  // namespace epa::modbus
