#include "rig/module_server.hpp"

#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <thread>

#include "rig/monotonic_clock.hpp"

namespace epa::rig {

namespace {
constexpr long kSelectTimeoutUs = 50'000;  // the server loop notices a stop at least this often
constexpr long kByteTimeoutUs = 100'000;   // a client stalled mid-frame longer than this is dropped
}  // namespace

core::Result<std::unique_ptr<ModuleServer>> ModuleServer::listen(const std::string& address, int port, const Setup& setup,
                                                                 ModuleRegisters& registers, const InjectedFaults& faults,
                                                                 MasterActivity& activity) {
  const std::string where = address + ":" + std::to_string(port);
  std::unique_ptr<ModuleServer> s(new ModuleServer(setup, registers, faults, activity));
  s->ctx_ = modbus_new_tcp(address.c_str(), port);
  if (s->ctx_ == nullptr)
    return core::io_error("remote I/O simulator: cannot create a Modbus TCP context for " + where + ": " + modbus_strerror(errno));
  // The response timeout is what modbus_reply sleeps before flushing a malformed request.
  modbus_set_response_timeout(s->ctx_, 0, 1000);
  modbus_set_byte_timeout(s->ctx_, 0, kByteTimeoutUs);
  modbus_set_indication_timeout(s->ctx_, 0, kByteTimeoutUs);
  s->listen_fd_ = modbus_tcp_listen(s->ctx_, kMaxClients);
  if (s->listen_fd_ < 0) return core::io_error("remote I/O simulator: cannot listen on " + where + ": " + std::strerror(errno));
  fcntl(s->listen_fd_, F_SETFD, FD_CLOEXEC);
  sockaddr_in bound{};
  socklen_t bound_len = sizeof bound;
  if (getsockname(s->listen_fd_, reinterpret_cast<sockaddr*>(&bound), &bound_len) != 0)
    return core::io_error("remote I/O simulator: cannot read the port bound for " + where + ": " + std::strerror(errno));
  s->bound_port_ = ntohs(bound.sin_port);
  s->client_fds_.reserve(kMaxClients);  // push_back in the server loop stays within capacity
  return s;
}

ModuleServer::~ModuleServer() {
  close_listener();
  if (ctx_ != nullptr) modbus_free(ctx_);
}

void ModuleServer::close_listener() {
  if (listen_fd_ >= 0) ::close(listen_fd_);
  listen_fd_ = -1;
}

void ModuleServer::serve(const std::atomic<bool>& running) noexcept {
  std::vector<int>& fds = client_fds_;
  std::uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
  while (running.load()) {
    fd_set read_set;
    FD_ZERO(&read_set);
    FD_SET(listen_fd_, &read_set);
    int max_fd = listen_fd_;
    for (int fd : fds) {
      FD_SET(fd, &read_set);
      max_fd = std::max(max_fd, fd);
    }
    timeval tv{0, kSelectTimeoutUs};
    const int n = select(max_fd + 1, &read_set, nullptr, nullptr, &tv);
    if (n == -1 && errno == EINTR) continue;
    if (n == -1) break;  // only a bug of ours (a closed descriptor) gets here
    if (n == 0) continue;
    for (std::size_t i = 0; i < fds.size();) {
      if (FD_ISSET(fds[i], &read_set) && !serve_request(fds[i], query)) {
        ::close(fds[i]);
        fds.erase(fds.begin() + static_cast<std::ptrdiff_t>(i));
        clients_.store(static_cast<int>(fds.size()));
      } else {
        ++i;
      }
    }
    if (FD_ISSET(listen_fd_, &read_set)) accept_client();
  }
  for (int fd : fds) ::close(fd);
  fds.clear();
  clients_.store(0);
}

void ModuleServer::accept_client() noexcept {
  const int fd = accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
  if (fd < 0) return;  // the client gave up already; nothing to do
  if (client_fds_.size() >= static_cast<std::size_t>(kMaxClients) || fd >= FD_SETSIZE) {
    ::close(fd);  // refused: select() cannot watch it, or too many clients
    return;
  }
  const int one = 1;
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);  // answers leave at once
  client_fds_.push_back(fd);
  clients_.store(static_cast<int>(client_fds_.size()));
}

// false: drop this client (it closed, sent garbage or stalled, or its answer could not be sent).
bool ModuleServer::serve_request(int fd, std::uint8_t* query) noexcept {
  modbus_set_socket(ctx_, fd);
  const int length = modbus_receive(ctx_, query);
  if (length == -1) return false;
  if (length == 0) return true;  // libmodbus ignored it
  if (setup_.record_valve_writes && writes_valve(query, length))
    activity_.last_valve_write_ns.store(monotonic_ns());  // the master's phase: when it sent, not when answered
  switch (faults_.answers()) {
    case ModuleFaults::Answers::kNormal: break;
    case ModuleFaults::Answers::kSilent: return true;  // read, never answered: the client times out
    case ModuleFaults::Answers::kLate: std::this_thread::sleep_for(std::chrono::milliseconds(faults_.late_ms())); break;
    case ModuleFaults::Answers::kGarbage: {
      // A frame that is no answer to anything: wrong transaction id, protocol id and length.
      static constexpr std::uint8_t kGarbage[] = {0xDE, 0xAD, 0xBE, 0xEF, 0x00, 0x03, 0x01, 0x83, 0x7F};
      return ::send(fd, kGarbage, sizeof kGarbage, MSG_NOSIGNAL) == static_cast<ssize_t>(sizeof kGarbage);
    }
  }
  const int unit = query[modbus_get_header_length(ctx_) - 1];
  // 0xFF is the Modbus TCP "unit id not used" value for a device addressed by IP alone (and
  // libmodbus' default), so it is answered too.
  const int rc = unit != setup_.unit_id && unit != MODBUS_TCP_SLAVE
                     ? modbus_reply_exception(ctx_, query, MODBUS_EXCEPTION_GATEWAY_TARGET)
                     : registers_.reply(ctx_, query, length);
  if (rc == -1) return false;
  requests_.fetch_add(1);
  activity_.last_request_ns.store(monotonic_ns());
  return true;
}

// Whether the request writes a register of the valve point (FC 6, 16 or 23); the frame was checked
// by modbus_receive, and each field read here is inside its length.
bool ModuleServer::writes_valve(const std::uint8_t* query, int length) const noexcept {
  const hal::AnalogPoint& valve = setup_.valve;
  if (valve.table != hal::RegisterTable::kHolding) return false;
  const int h = modbus_get_header_length(ctx_);
  const auto word = [&](int at) { return at + 1 < length ? (query[at] << 8) | query[at + 1] : -1; };
  int first = -1, count = 0;
  switch (h < length ? query[h] : 0) {
    case 0x06: first = word(h + 1), count = 1; break;
    case 0x10: first = word(h + 1), count = word(h + 3); break;
    case 0x17: first = word(h + 5), count = word(h + 7); break;  // read/write multiple: the write part
    default: return false;
  }
  return first >= 0 && count > 0 && first <= valve.address && valve.address < first + count;
}

}  // namespace epa::rig
