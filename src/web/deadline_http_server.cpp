#include "web/deadline_http_server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <string>

namespace epa::web {

namespace {

using Clock = std::chrono::steady_clock;

enum class Cut { kNone, kDeadline, kTooLarge };

// Waits for `events` on `fd` for at most `wait` (not negative); true when they came.
bool poll_for(int fd, short events, std::chrono::milliseconds wait) {
  pollfd p{fd, events, 0};
  for (;;) {
    const int n = ::poll(&p, 1, static_cast<int>(std::max<std::chrono::milliseconds::rep>(0, wait.count())));
    if (n < 0 && errno == EINTR) continue;
    return n > 0;
  }
}

std::string address_text(const sockaddr_storage& a, int& port) {
  char text[INET6_ADDRSTRLEN] = {};
  if (a.ss_family == AF_INET) {
    const auto& v4 = reinterpret_cast<const sockaddr_in&>(a);
    ::inet_ntop(AF_INET, &v4.sin_addr, text, sizeof text);
    port = ntohs(v4.sin_port);
  } else if (a.ss_family == AF_INET6) {
    const auto& v6 = reinterpret_cast<const sockaddr_in6&>(a);
    ::inet_ntop(AF_INET6, &v6.sin6_addr, text, sizeof text);
    port = ntohs(v6.sin6_port);
  }
  return text;
}

// One connection's socket as httplib's Stream. A request's clock starts with the first byte read
// after the previous answer; from then on every wait is bounded by what is left of the deadline
// and its bytes are counted. Once a request is cut, reads fail and httplib's answer to that
// failure (a 400) is not sent: the caller answers 408 or 431 itself and closes.
class DeadlineSocketStream final : public httplib::Stream {
 public:
  DeadlineSocketStream(int fd, const RequestLimits& limits) : fd_(fd), limits_(limits) {}

  // Waits up to `wait` for the next request's first byte, in slices so a stopping server is seen.
  template <typename Stopping>
  bool wait_for_request(std::chrono::milliseconds wait, Stopping stopping) const {
    if (pos_ < end_) return true;
    const auto until = Clock::now() + wait;
    while (!stopping()) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(until - Clock::now());
      if (left.count() <= 0) return false;
      if (poll_for(fd_, POLLIN, std::min(left, std::chrono::milliseconds(100)))) return true;
    }
    return false;
  }

  Cut cut() const { return cut_; }

  bool is_readable() const override { return pos_ < end_ || poll_for(fd_, POLLIN, limits_.read_timeout); }
  bool is_writable() const override { return cut_ == Cut::kNone && poll_for(fd_, POLLOUT, limits_.write_timeout); }

  ssize_t read(char* ptr, std::size_t size) override {
    if (cut_ != Cut::kNone) return -1;
    if (answering_) {  // a new request on this connection: its clock starts with its first byte
      answering_ = false, request_bytes_ = 0;
      started_ = pos_ < end_;  // pipelined: that byte is already here
      if (started_) deadline_ = Clock::now() + limits_.request_deadline;
    }
    if (pos_ == end_) {
      const ssize_t got = fill();
      if (got <= 0) return got;
    }
    const std::size_t n = std::min(size, end_ - pos_);
    if (request_bytes_ + n > limits_.max_request_bytes) {
      cut_ = Cut::kTooLarge;
      return -1;
    }
    std::memcpy(ptr, buffer_.data() + pos_, n);
    pos_ += n;
    request_bytes_ += n;
    return static_cast<ssize_t>(n);
  }

  ssize_t write(const char* ptr, std::size_t size) override {
    if (cut_ != Cut::kNone) return -1;
    answering_ = true;
    if (!poll_for(fd_, POLLOUT, limits_.write_timeout)) return -1;
    for (;;) {
      const ssize_t n = ::send(fd_, ptr, size, MSG_NOSIGNAL);
      if (n < 0 && errno == EINTR) continue;
      return n;
    }
  }

  // The answer to a cut request, written past httplib (which has given up on it).
  void answer_cut() const {
    const bool late = cut_ == Cut::kDeadline;
    const std::string body = late ? R"({"error":"request not complete within its deadline"})"
                                  : R"({"error":"request too large"})";
    const std::string head = std::string(late ? "HTTP/1.1 408 Request Timeout" : "HTTP/1.1 431 Request Header Fields Too Large") +
                             "\r\nContent-Type: application/json\r\nContent-Length: " + std::to_string(body.size()) +
                             "\r\nConnection: close\r\n\r\n";
    const std::string all = head + body;
    if (poll_for(fd_, POLLOUT, limits_.write_timeout)) (void)::send(fd_, all.data(), all.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
  }

  void get_remote_ip_and_port(std::string& ip, int& port) const override { endpoint(::getpeername, ip, port); }
  void get_local_ip_and_port(std::string& ip, int& port) const override { endpoint(::getsockname, ip, port); }
  socket_t socket() const override { return fd_; }

 private:
  // The address and port getpeername or getsockname gives for the socket.
  void endpoint(int (*get)(int, sockaddr*, socklen_t*), std::string& ip, int& port) const {
    sockaddr_storage a{};
    socklen_t len = sizeof a;
    ip.clear(), port = 0;
    if (get(fd_, reinterpret_cast<sockaddr*>(&a), &len) == 0) ip = address_text(a, port);
  }

  // Reads what the socket has into the empty buffer: >0 bytes, 0 at the peer's end, -1 on a
  // timeout, a cut or an error.
  ssize_t fill() {
    if (started_) {  // every wait inside a request ends at its deadline
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline_ - Clock::now());
      if (left.count() <= 0 || !poll_for(fd_, POLLIN, left)) {
        cut_ = Cut::kDeadline;
        return -1;
      }
    } else if (!poll_for(fd_, POLLIN, limits_.read_timeout)) {
      return -1;
    }
    for (;;) {
      const ssize_t n = ::recv(fd_, buffer_.data(), buffer_.size(), 0);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return n < 0 ? -1 : 0;
      pos_ = 0, end_ = static_cast<std::size_t>(n);
      if (!started_) started_ = true, deadline_ = Clock::now() + limits_.request_deadline;
      return n;
    }
  }

  int fd_;
  const RequestLimits& limits_;
  std::array<char, 4096> buffer_{};
  std::size_t pos_ = 0, end_ = 0;  // unread bytes: buffer_[pos_, end_)
  bool started_ = false;           // the current request's first byte has been read
  bool answering_ = false;         // the current request's answer has begun
  Clock::time_point deadline_{};
  std::size_t request_bytes_ = 0;
  Cut cut_ = Cut::kNone;
};

}  // namespace

bool DeadlineHttpServer::process_and_close_socket(socket_t sock) {
  DeadlineSocketStream stream(sock, limits_);
  bool served = false;
  for (std::size_t left = limits_.keep_alive_max_requests; left > 0; --left) {
    const auto stopping = [this] { return svr_sock_ == INVALID_SOCKET; };
    if (stopping() || !stream.wait_for_request(limits_.keep_alive_timeout, stopping)) break;
    bool connection_closed = false;
    served = process_request(stream, left == 1, connection_closed, nullptr);
    if (stream.cut() != Cut::kNone) {
      stream.answer_cut();
      served = false;
      break;
    }
    if (!served || connection_closed) break;
  }
  ::shutdown(sock, SHUT_RDWR);
  ::close(sock);
  return served;
}

}  // namespace epa::web
