#include "web/deadline_http_server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdint>
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

  Cut cut() const { return cut_; }
  bool has_buffered() const { return pos_ < end_; }

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

DeadlineHttpServer::DeadlineHttpServer(const RequestLimits& limits) : limits_(limits) {
  epoll_fd_ = ::epoll_create1(EPOLL_CLOEXEC);
  wake_fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (epoll_fd_ >= 0 && wake_fd_ >= 0) {
    epoll_event ev{};
    ev.events = EPOLLIN;
    ev.data.fd = wake_fd_;
    ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, wake_fd_, &ev);
    epoll_ok_ = true;
    parker_ = std::thread([this] { park_loop(); });
  } else {
    parking_ = false;  // no epoll: a silent connection keeps its worker (serve)
  }
}

DeadlineHttpServer::~DeadlineHttpServer() {
  stop_parking();
  if (epoll_fd_ >= 0) ::close(epoll_fd_);
  if (wake_fd_ >= 0) ::close(wake_fd_);
}

void DeadlineHttpServer::set_task_queue(httplib::TaskQueue* queue) {
  std::lock_guard lock(mutex_);
  queue_ = queue;
}

void DeadlineHttpServer::stop_parking() {
  {
    std::lock_guard lock(mutex_);
    if (!parking_ && !parker_.joinable()) return;
    parking_ = false;
    queue_ = nullptr;
  }
  const std::uint64_t one = 1;
  if (wake_fd_ >= 0) (void)!::write(wake_fd_, &one, sizeof one);
  if (parker_.joinable()) parker_.join();
  std::lock_guard lock(mutex_);
  for (const auto& [sock, p] : parked_) ::close(sock);
  parked_.clear();
}

void DeadlineHttpServer::park(socket_t sock, std::size_t requests_left, std::chrono::milliseconds wait) {
  std::unique_lock lock(mutex_);
  if (!parking_ || !queue_) {
    lock.unlock();
    ::shutdown(sock, SHUT_RDWR);
    ::close(sock);
    return;
  }
  parked_[sock] = {Clock::now() + wait, requests_left};
  epoll_event ev{};
  ev.events = EPOLLIN | EPOLLRDHUP | EPOLLONESHOT;
  ev.data.fd = sock;
  if (::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, sock, &ev) != 0) {
    parked_.erase(sock);
    lock.unlock();
    ::close(sock);
    return;
  }
  lock.unlock();
  const std::uint64_t one = 1;  // the loop's next timeout may be this one's
  (void)!::write(wake_fd_, &one, sizeof one);
}

void DeadlineHttpServer::park_loop() {
  std::array<epoll_event, 64> events{};
  for (;;) {
    int timeout_ms = 1000;
    {
      std::lock_guard lock(mutex_);
      if (!parking_) return;
      const auto now = Clock::now();
      for (auto it = parked_.begin(); it != parked_.end();) {  // waits that ended: closed unanswered
        if (it->second.until <= now) {
          ::epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, it->first, nullptr);
          ::close(it->first);
          it = parked_.erase(it);
        } else {
          const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(it->second.until - now).count() + 1;
          timeout_ms = static_cast<int>(std::min<long long>(timeout_ms, left));
          ++it;
        }
      }
    }
    const int n = ::epoll_wait(epoll_fd_, events.data(), static_cast<int>(events.size()), timeout_ms);
    if (n < 0 && errno != EINTR) return;
    for (int i = 0; i < n; ++i) {
      const int fd = events[static_cast<std::size_t>(i)].data.fd;
      if (fd == wake_fd_) {
        std::uint64_t count = 0;
        (void)!::read(wake_fd_, &count, sizeof count);
        continue;
      }
      std::lock_guard lock(mutex_);
      const auto it = parked_.find(fd);
      if (it == parked_.end()) continue;
      const std::size_t left = it->second.requests_left;
      parked_.erase(it);
      ::epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, fd, nullptr);
      if (!parking_ || !queue_) {
        ::close(fd);
        continue;
      }
      queue_->enqueue([this, fd, left] { serve(fd, left, false); });  // a byte (or the peer's end) came
    }
  }
}

bool DeadlineHttpServer::process_and_close_socket(socket_t sock) {
  serve(sock, limits_.keep_alive_max_requests, true);
  return true;
}

void DeadlineHttpServer::serve(socket_t sock, std::size_t requests_left, bool first) {
  DeadlineSocketStream stream(sock, limits_);
  const auto stopping = [this] { return svr_sock_ == INVALID_SOCKET; };
  for (std::size_t left = requests_left; left > 0; --left) {
    if (stopping()) break;
    const auto wait = first ? limits_.read_timeout : limits_.keep_alive_timeout;
    if (!stream.has_buffered() && !poll_for(sock, POLLIN, std::chrono::milliseconds(0))) {
      if (epoll_ok_) {  // silent: wait on the parker rather than on this worker
        park(sock, left, wait);
        return;
      }
      if (!poll_for(sock, POLLIN, wait)) break;  // no epoll on this system: wait here, as httplib does
    }
    first = false;
    bool connection_closed = false;
    const bool served = process_request(stream, left == 1, connection_closed, nullptr);
    if (stream.cut() != Cut::kNone) {
      stream.answer_cut();
      break;
    }
    if (!served || connection_closed) break;
  }
  ::shutdown(sock, SHUT_RDWR);
  ::close(sock);
}

}  // namespace epa::web
