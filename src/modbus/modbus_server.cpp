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
#include <cstring>
#include <vector>

#include "runtime/clock.hpp"

namespace epa::modbus {

namespace {
constexpr int kMbapLength = 6;       // bytes before the MBAP length field's count starts
constexpr int kMaxAdu = MODBUS_TCP_MAX_ADU_LENGTH;

struct Client {
  int fd = -1;
  std::string peer;  // "127.0.0.1" (what write_clients lists)
  std::vector<std::uint8_t> buffer;
  std::int64_t last_activity_ns = 0;
};
}  // namespace

struct ModbusServer::Impl {
  ServerConfig config;
  RequestHandler handler;
  modbus_t* ctx = nullptr;
  modbus_mapping_t* image = nullptr;
  int listener = -1;
  std::vector<Client> clients;
  runtime::MonotonicClock clock;
  Log log;

  Impl(const ServerConfig& c, const RegisterMap& map, points::WriteGate& gate, runtime::LoopChannels& ch, Log l)
      : config(c), handler(map, c.policy, c.unit_id, gate, ch), log(std::move(l)) {}
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
  auto impl = std::make_unique<Impl>(c, map, gate, ch, std::move(log));
  impl->ctx = modbus_new_tcp(c.address.c_str(), c.port);
  if (!impl->ctx) return core::invalid_argument("modbus: cannot listen on " + where + ": " + modbus_strerror(errno));
  impl->image = modbus_mapping_new_start_address(0, static_cast<unsigned>(map.end_address(Table::kCoil)), 0,
                                                 static_cast<unsigned>(map.end_address(Table::kDiscreteInput)), 0,
                                                 static_cast<unsigned>(map.end_address(Table::kHoldingRegister)), 0,
                                                 static_cast<unsigned>(map.end_address(Table::kInputRegister)));
  if (!impl->image) return core::io_error("modbus: cannot allocate the register image");
  impl->listener = modbus_tcp_listen(impl->ctx, 64);
  if (impl->listener < 0) return core::io_error("modbus: cannot listen on " + where + ": " + modbus_strerror(errno));
  fcntl(impl->listener, F_SETFL, O_NONBLOCK);
  sockaddr_in addr{};
  socklen_t len = sizeof addr;
  getsockname(impl->listener, reinterpret_cast<sockaddr*>(&addr), &len);
  std::unique_ptr<ModbusServer> server(new ModbusServer(std::move(impl)));
  server->port_ = ntohs(addr.sin_port);
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
  auto drop = [&](std::size_t i, const char* why) {
    if (m.log) m.log("modbus: client " + m.clients[i].peer + " disconnected (" + why + ")");
    ::close(m.clients[i].fd);
    m.clients.erase(m.clients.begin() + static_cast<std::ptrdiff_t>(i));
  };

  while (!stop_.load()) {
    fds.assign(1, pollfd{m.listener, POLLIN, 0});
    for (const auto& cl : m.clients) fds.push_back({cl.fd, POLLIN, 0});
    if (poll(fds.data(), fds.size(), 100) < 0 && errno != EINTR) break;
    const std::int64_t now = m.clock.now_ns();

    if (fds[0].revents & POLLIN) {
      for (;;) {
        sockaddr_in peer{};
        socklen_t len = sizeof peer;
        const int fd = accept4(m.listener, reinterpret_cast<sockaddr*>(&peer), &len, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd < 0) break;
        char ip[INET_ADDRSTRLEN] = "?";
        inet_ntop(AF_INET, &peer.sin_addr, ip, sizeof ip);
        if (static_cast<int>(m.clients.size()) >= m.config.max_clients) {
          ::close(fd);  // over the cap: refused at once, so it knows
          if (m.log) m.log(std::string("modbus: refused client ") + ip + " (" + std::to_string(m.config.max_clients) + " connected)");
          continue;
        }
        const int one = 1;
        setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        m.clients.push_back({fd, ip, {}, now});
      }
    }

    // Clients in reverse, so dropping one does not disturb the indices still to visit.
    for (std::size_t i = m.clients.size(); i-- > 0;) {
      Client& cl = m.clients[i];
      const short revents = i + 1 < fds.size() && fds[i + 1].fd == cl.fd ? fds[i + 1].revents : 0;
      if (revents & (POLLERR | POLLHUP | POLLNVAL)) { drop(i, "connection closed"); continue; }
      if (revents & POLLIN) {
        const ssize_t n = recv(cl.fd, chunk, sizeof chunk, 0);
        if (n <= 0) { drop(i, n == 0 ? "closed by the client" : std::strerror(errno)); continue; }
        cl.buffer.insert(cl.buffer.end(), chunk, chunk + n);
        cl.last_activity_ns = now;
      } else if (now - cl.last_activity_ns > idle_ns) {
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
        m.handler.set_clients(static_cast<int>(m.clients.size()));
        const std::uint8_t exception = m.handler.handle(cl.buffer.data(), static_cast<int>(total), cl.peer, now, m.image);
        modbus_set_socket(m.ctx, cl.fd);
        const int rc = exception ? modbus_reply_exception(m.ctx, cl.buffer.data(), exception)
                                 : modbus_reply(m.ctx, cl.buffer.data(), static_cast<int>(total), m.image);
        requests_++;
        if (exception) exceptions_++;
        if (rc < 0) { drop(i, "send failed"); dropped = true; break; }
        cl.buffer.erase(cl.buffer.begin(), cl.buffer.begin() + static_cast<std::ptrdiff_t>(total));
      }
      if (dropped) continue;
    }
    clients_ = static_cast<int>(m.clients.size());
  }
  modbus_set_socket(m.ctx, -1);
}

}  // namespace epa::modbus
