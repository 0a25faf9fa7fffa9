#include "web/deadline_http_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <deque>
#include <optional>
#include <string_view>
#include <unordered_map>

#include "tls/no_sigpipe.hpp"
#include "web/connection_bytes.hpp"
#include "web/front_end_tls.hpp"
#include "web/round_robin_by_key.hpp"

namespace epa::web {

namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

constexpr milliseconds kScanPeriod{50};        // how often deadlines are looked at
// How long a worker waits for bytes the front end's framing did not see coming: a chunked body
// whose end marker came early (inside a chunk's data). Short, so no client holds a worker.
constexpr milliseconds kWorkerReadGrace{100};
constexpr std::size_t kAcceptsPerWake = 256;   // then the connections get their turn
constexpr std::size_t kReservedDescriptors = 256;  // left to the rest of the process (Modbus, store, logs)
constexpr auto kTallyPeriod = std::chrono::minutes(1);

// Waits for `events` on `fd` for at most `wait` (not negative); true when they came.
bool poll_for(int fd, short events, milliseconds wait) {
  pollfd p{fd, events, 0};
  for (;;) {
    const int n = ::poll(&p, 1, static_cast<int>(std::max<milliseconds::rep>(0, wait.count())));
    if (n < 0 && errno == EINTR) continue;
    return n > 0;
  }
}

std::string address_text(const sockaddr_storage& a, int& port) {
  char text[INET6_ADDRSTRLEN] = {};
  port = 0;
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

bool iequals(std::string_view a, std::string_view b) {
  return a.size() == b.size() &&
         std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) { return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y)); });
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

// How much of a request the buffer holds. Only the framing is read here (where the head ends, how
// long the body is); httplib parses the request once it is whole.
enum class Framing { kPartial, kWhole, kTooLarge, kTooManyFields, kNul };

Framing framing(std::string_view buf, const RequestLimits& limits, std::size_t max_body_bytes) {
  const std::size_t head_end = buf.find("\r\n\r\n");
  if (head_end == std::string_view::npos) return buf.size() > limits.max_request_bytes ? Framing::kTooLarge : Framing::kPartial;
  const std::size_t body_start = head_end + 4;
  if (body_start > limits.max_request_bytes) return Framing::kTooLarge;
  // No field may hold a NUL (RFC 9110 5.5); httplib would read a value only up to it, so a token
  // followed by NUL and junk would pass as the token alone.
  if (buf.substr(0, head_end).find('\0') != std::string_view::npos) return Framing::kNul;
  std::size_t fields = 0;
  std::optional<std::string_view> length;
  bool chunked = false;
  std::size_t line = buf.find("\r\n") + 2;  // past the request line
  while (line < head_end + 2) {
    const std::size_t end = buf.find("\r\n", line);
    const std::string_view field = buf.substr(line, end - line);
    ++fields;
    const std::size_t colon = field.find(':');
    if (colon != std::string_view::npos) {
      const std::string_view name = field.substr(0, colon), value = trim(field.substr(colon + 1));
      if (iequals(name, "Content-Length")) length = value;
      if (iequals(name, "Transfer-Encoding")) chunked = true;
    }
    line = end + 2;
  }
  if (fields > limits.max_header_fields) return Framing::kTooManyFields;
  const std::string_view body = buf.substr(body_start);
  if (chunked) {  // whole once the last chunk (size 0) has come; a body cut short is read under the deadline
    if (body.rfind("0\r\n\r\n", 0) == 0 || body.find("\r\n0\r\n\r\n") != std::string_view::npos) return Framing::kWhole;
    return buf.size() > limits.max_request_bytes ? Framing::kTooLarge : Framing::kPartial;
  }
  if (!length) return Framing::kWhole;
  const bool digits = !length->empty() && length->size() <= 18 && length->find_first_not_of("0123456789") == std::string_view::npos;
  if (!digits) return Framing::kWhole;  // httplib answers it 400
  const std::size_t declared = std::stoull(std::string(*length));
  if (declared > max_body_bytes) return Framing::kWhole;  // answered 413 unread
  if (body.size() >= declared) return Framing::kWhole;
  return body_start + declared > limits.max_request_bytes ? Framing::kTooLarge : Framing::kPartial;
}

// An answer the front end gives itself (a refusal), whole, with `headers`.
std::string refusal_text(int status, std::string_view reason, const std::string& message, const httplib::Headers& headers) {
  const std::string body = R"({"error":")" + message + "\"}";
  std::string all = "HTTP/1.1 " + std::to_string(status) + " " + std::string(reason) + "\r\n";
  for (const auto& [k, v] : headers) all += k + ": " + v + "\r\n";
  all += "Content-Type: application/json\r\nContent-Length: " + std::to_string(body.size()) + "\r\nConnection: close\r\n\r\n" + body;
  return all;
}

// A refusal on a plain socket that has no connection yet, written without waiting; the caller closes.
void send_plain_refusal(int fd, int status, std::string_view reason, const std::string& message, const httplib::Headers& headers) {
  const std::string all = refusal_text(status, reason, message, headers);
  (void)::send(fd, all.data(), all.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
}

}  // namespace

// An event that may come thousands of times a second (a refused connection): the first is logged at
// once, the rest counted and logged once a minute ("..., 412 times in the last minute").
class Tally {
 public:
  explicit Tally(std::string what) : what_(std::move(what)) {}
  void note(Clock::time_point now, const DeadlineHttpServer::Log& log, const std::string& detail) {
    ++count_, detail_ = detail;
    if (!reported_ || now - since_ >= kTallyPeriod) report(now, log);
  }
  void flush(Clock::time_point now, const DeadlineHttpServer::Log& log) {
    if (count_ > 0 && now - since_ >= kTallyPeriod) report(now, log);
  }

 private:
  void report(Clock::time_point now, const DeadlineHttpServer::Log& log) {
    if (log) {
      const bool first = !reported_;
      log("web: " + what_ + (first ? "" : ", " + std::to_string(count_) + (count_ == 1 ? " time" : " times") + " in the last minute") +
          " (" + detail_ + ")" + (first ? "; further ones are counted and logged once a minute" : ""));
    }
    reported_ = true, count_ = 0, since_ = now;
  }
  std::string what_, detail_;
  std::uint64_t count_ = 0;
  bool reported_ = false;
  Clock::time_point since_{};
};

namespace {

std::size_t descriptor_limit() {
  rlimit r{};
  if (::getrlimit(RLIMIT_NOFILE, &r) != 0 || r.rlim_cur == RLIM_INFINITY) return SIZE_MAX;
  return static_cast<std::size_t>(r.rlim_cur);
}

}  // namespace

struct DeadlineHttpServer::Connection {
  int fd = -1;
  std::string peer;
  std::string buffer;  // read and not yet answered; starts with the next request's first byte
  Clock::time_point deadline{};
  bool in_request = false;  // the next request's first byte has come: `deadline` is its deadline
  std::size_t requests_left = 0;
  std::string out;          // answered, not yet taken by the client
  bool writing = false;     // the front end writes `out` (EPOLLOUT); `deadline` is the client's time to take it
  bool close_after_out = false;
  std::unique_ptr<tls::TlsConnection> tls;  // HTTPS: the connection's session; null on plain HTTP
  bool handshake_wants_write = false;       // HTTPS: the handshake waits for the socket to take its bytes (EPOLLOUT)
  // HTTPS: the handshake is not complete yet; `deadline` is its deadline.
  bool handshaking() const { return tls && !tls->handshake_done(); }
};

namespace {

// A refusal the front end or a worker gives on `c`, written without waiting; the caller closes.
// Over HTTPS it goes through the session, once there is one (before, there is nothing to say it in).
void send_refusal(DeadlineHttpServer::Connection& c, int status, std::string_view reason, const std::string& message,
                  const httplib::Headers& headers) {
  if (c.handshaking()) return;
  std::string all = refusal_text(status, reason, message, headers);
  (void)send_some(c.fd, c.tls.get(), all);
}

enum class Cut { kNone, kDeadline, kTooLarge };

// A connection as httplib's Stream, on a worker: the request is read from the bytes the front end
// buffered (usually all of it), and only a body the front end framed wrongly (chunked) from the
// socket, by the request's deadline or kWorkerReadGrace after the worker took it, whichever is first.
class BufferedStream final : public httplib::Stream {
 public:
  BufferedStream(DeadlineHttpServer::Connection& c, const RequestLimits& limits)
      : c_(c), limits_(limits), read_until_(std::min(c.deadline, Clock::now() + kWorkerReadGrace)) {}

  Cut cut() const { return cut_; }
  // Forgets the bytes of the request just answered.
  void consume() {
    c_.buffer.erase(0, pos_);
    pos_ = 0;
  }

  bool is_readable() const override {
    return pos_ < c_.buffer.size() || bytes_pending(c_.tls.get()) || poll_for(c_.fd, POLLIN, left());
  }
  bool is_writable() const override { return cut_ == Cut::kNone; }

  ssize_t read(char* ptr, std::size_t size) override {
    if (cut_ != Cut::kNone) return -1;
    if (pos_ == c_.buffer.size() && !fill()) return -1;
    const std::size_t n = std::min(size, c_.buffer.size() - pos_);
    std::memcpy(ptr, c_.buffer.data() + pos_, n);
    pos_ += n;
    return static_cast<ssize_t>(n);
  }

  // Into memory: the worker never waits for a client to read (flush() sends what the socket takes).
  ssize_t write(const char* ptr, std::size_t size) override {
    if (cut_ != Cut::kNone) return -1;
    c_.out.append(ptr, size);
    return static_cast<ssize_t>(size);
  }
  // Sends what the socket takes now; false when the connection failed.
  bool flush() { return send_some(c_.fd, c_.tls.get(), c_.out) != Sent::kFailed; }

  void get_remote_ip_and_port(std::string& ip, int& port) const override { endpoint(::getpeername, ip, port); }
  void get_local_ip_and_port(std::string& ip, int& port) const override { endpoint(::getsockname, ip, port); }
  socket_t socket() const override { return c_.fd; }

 private:
  milliseconds left() const {
    return std::max(milliseconds(0), std::chrono::duration_cast<milliseconds>(read_until_ - Clock::now()));
  }
  void endpoint(int (*get)(int, sockaddr*, socklen_t*), std::string& ip, int& port) const {
    sockaddr_storage a{};
    socklen_t len = sizeof a;
    ip.clear(), port = 0;
    if (get(c_.fd, reinterpret_cast<sockaddr*>(&a), &len) == 0) ip = address_text(a, port);
  }
  // More of the request from the socket, within its deadline and its size cap.
  bool fill() {
    constexpr std::size_t kChunkBytes = 4096;
    // TLS may hold bytes already read from the socket; but they may be only part of a record,
    // which takes the socket's next bytes to decrypt.
    bool wait_for_socket = !bytes_pending(c_.tls.get());
    for (;;) {
      if (left().count() <= 0 || (wait_for_socket && !poll_for(c_.fd, POLLIN, left()))) return cut_ = Cut::kDeadline, false;
      const std::size_t had = c_.buffer.size();
      const Received r = receive_some(c_.fd, c_.tls.get(), c_.buffer, kChunkBytes);
      wait_for_socket = true;
      if (r == Received::kNone) continue;
      if (r == Received::kEnded) return false;
      if (c_.buffer.size() > limits_.max_request_bytes) return c_.buffer.resize(had), cut_ = Cut::kTooLarge, false;
      return true;
    }
  }

  DeadlineHttpServer::Connection& c_;
  const RequestLimits& limits_;
  const Clock::time_point read_until_;  // this request's bytes from the socket, if any, come by then
  std::size_t pos_ = 0;
  Cut cut_ = Cut::kNone;
};

}  // namespace

// The front end's state: touched by its own thread only, except `returned` and `stopping` (mutex).
struct DeadlineHttpServer::Front {
  int epoll_fd = -1, wake_fd = -1, reserve_fd = -1;
  std::unordered_map<int, std::shared_ptr<Connection>> waiting;  // connections not at a worker
  std::unordered_map<std::string, std::size_t> per_address;      // every open connection, by peer
  std::atomic<std::size_t> open{0};
  std::size_t max_connections = 0;
  httplib::TaskQueue* queue = nullptr;
  RoundRobinByKey<std::shared_ptr<Connection>> ready;  // whole requests for the workers, by peer in turn
  Clock::time_point next_scan{}, accept_paused_until{};
  bool accept_paused = false;
  Tally no_descriptors{"accept refused: out of file descriptors"};
  Tally over_address_cap{"connections refused: too many from one address"};
  Tally over_total_cap{"connections refused: the web server's connection limit is reached"};

  std::mutex mutex;
  std::deque<std::pair<std::shared_ptr<Connection>, bool>> returned;  // from workers: (connection, close it)
  bool stopping = false, running = false;

  void wake() const {
    const std::uint64_t one = 1;
    (void)!::write(wake_fd, &one, sizeof one);
  }
  bool watch(int fd, int op, std::uint32_t events = EPOLLIN) const {
    epoll_event ev{};
    ev.events = events | EPOLLRDHUP;
    ev.data.fd = fd;
    return ::epoll_ctl(epoll_fd, op, fd, &ev) == 0;
  }
  void close_connection(const std::shared_ptr<Connection>& c) {
    if (c->tls) c->tls->shut_down();  // close_notify, after a complete handshake only
    ::shutdown(c->fd, SHUT_RDWR);
    ::close(c->fd);
    if (auto it = per_address.find(c->peer); it != per_address.end() && --it->second == 0) per_address.erase(it);
    --open;
  }
};

DeadlineHttpServer::DeadlineHttpServer(const RequestLimits& limits, Log log, httplib::Headers answer_headers)
    : limits_(limits), log_(std::move(log)), answer_headers_(std::move(answer_headers)), front_(std::make_unique<Front>()) {
  front_->epoll_fd = ::epoll_create1(EPOLL_CLOEXEC);
  front_->wake_fd = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  front_->reserve_fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);  // given up for an accept when descriptors run out
}

DeadlineHttpServer::~DeadlineHttpServer() {
  stop_serving();
  for (int fd : {front_->epoll_fd, front_->wake_fd, front_->reserve_fd})
    if (fd >= 0) ::close(fd);
}

// One request answered here, before any worker exists. httplib builds some of its parsers as
// function-local statics on the first request that needs them; built by whichever worker came
// first, the others then read them past a guard check that an uninstrumented library does without
// a call, which ThreadSanitizer cannot see (it reported a race between two workers' first
// requests). Built here, they are there before the workers start. Its answer goes nowhere, and it
// is no client's: warming_up() says so to the handlers while it runs.
void DeadlineHttpServer::warm_up() {
  Connection c;
  c.buffer = "GET / HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n\r\n";
  c.deadline = Clock::now() + limits_.request_deadline;
  BufferedStream stream(c, limits_);
  bool closed = false;
  warming_up_ = true;
  process_request(stream, true, closed, nullptr);
  warming_up_ = false;
}

void DeadlineHttpServer::use_tls(std::unique_ptr<FrontEndTls> tls) { tls_ = std::move(tls); }

bool DeadlineHttpServer::serving() const {
  std::lock_guard lock(front_->mutex);
  return front_->running;
}

std::size_t DeadlineHttpServer::connections() const { return front_->open.load(); }

void DeadlineHttpServer::stop_serving() {
  std::lock_guard lock(front_->mutex);
  front_->stopping = true;
  if (front_->wake_fd >= 0) front_->wake();
}

void DeadlineHttpServer::hand_back(std::shared_ptr<Connection> c, bool close) {
  std::unique_lock lock(front_->mutex);
  if (front_->stopping) {  // the front end has closed its own; this one is closed here
    lock.unlock();
    ::shutdown(c->fd, SHUT_RDWR);
    ::close(c->fd);
    return;
  }
  front_->returned.emplace_back(std::move(c), close);
  front_->wake();
}

// One request per turn: a pipelined request that is already whole goes back through the front end
// to wait for its turn behind one answer of each other address. A worker that answered every
// pipelined request at once held it for as many answers as the socket's buffer takes (megabytes on
// loopback), while the page's poll waited for a worker.
void DeadlineHttpServer::answer(std::shared_ptr<Connection> c) {
  BufferedStream stream(*c, limits_);
  bool connection_closed = false;
  // Over HTTPS the handlers find the client's session (and its certificate) in Request::ssl.
  std::function<void(httplib::Request&)> with_session;
  if (c->tls) with_session = [session = c->tls->ssl()](httplib::Request& req) { req.ssl = session; };
  const bool served = process_request(stream, c->requests_left <= 1, connection_closed, with_session);
  --c->requests_left;
  if (stream.cut() != Cut::kNone) {
    const bool late = stream.cut() == Cut::kDeadline;
    send_refusal(*c, late ? 408 : 431, late ? "Request Timeout" : "Request Header Fields Too Large",
                 late ? "request not complete within its deadline" : "request too large", answer_headers_);
    return hand_back(std::move(c), true);
  }
  // After a request it could not parse, httplib answers 400 and would read on from the next line:
  // the rest of a malformed request must not be taken as a new one (request smuggling).
  const bool malformed = c->out.starts_with("HTTP/1.1 400 ");
  if (!stream.flush()) return hand_back(std::move(c), true);
  if (!served || connection_closed || malformed || c->requests_left == 0) return hand_back(std::move(c), true);  // after `out`
  stream.consume();
  hand_back(std::move(c), false);  // the front end writes what the client has not taken, or frames the next request
}

// Accepts what the listening socket holds. Out of descriptors, the reserve descriptor is given up to
// accept and close one connection (so it is refused rather than left hanging, and epoll does not spin),
// and accepting pauses a moment; it is logged once a minute with a count.
void DeadlineHttpServer::accept_waiting(int listen_fd) {
  Front& f = *front_;
  for (std::size_t i = 0; i < kAcceptsPerWake; ++i) {
    sockaddr_storage a{};
    socklen_t len = sizeof a;
    const int fd = ::accept4(listen_fd, reinterpret_cast<sockaddr*>(&a), &len, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EINTR || errno == ECONNABORTED) continue;
      if (errno == EMFILE || errno == ENFILE) {
        f.no_descriptors.note(Clock::now(), log_, "open files limit " + std::to_string(descriptor_limit()) + ": raise LimitNOFILE");
        if (f.reserve_fd >= 0) {
          ::close(f.reserve_fd);
          const int dropped = ::accept4(listen_fd, nullptr, nullptr, SOCK_CLOEXEC);
          if (dropped >= 0) ::close(dropped);
          f.reserve_fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
        }
        ::epoll_ctl(f.epoll_fd, EPOLL_CTL_DEL, listen_fd, nullptr);
        f.accept_paused = true, f.accept_paused_until = Clock::now() + kScanPeriod;
      }
      return;  // EAGAIN: none left
    }
    int port = 0;
    admit(fd, address_text(a, port));
  }
}

// A new connection: closed at once past the per-address or the total cap (over HTTPS without an
// answer: there is no session yet to answer in), else it waits for its request, or over HTTPS
// for its handshake first.
void DeadlineHttpServer::admit(int fd, const std::string& peer) {
  Front& f = *front_;
  const auto now = Clock::now();
  std::size_t& from_peer = f.per_address[peer];
  if (from_peer >= limits_.max_connections_per_address || f.open >= f.max_connections) {
    const bool address = from_peer >= limits_.max_connections_per_address;
    if (from_peer == 0) f.per_address.erase(peer);
    (address ? f.over_address_cap : f.over_total_cap)
        .note(now, log_, address ? peer + " holds " + std::to_string(limits_.max_connections_per_address) + ", [web] max_connections_per_address"
                                 : std::to_string(f.max_connections) + " open");
    if (!tls_) send_plain_refusal(fd, 503, "Service Unavailable", address ? "too many connections from " + peer : "too many connections", answer_headers_);
    ::close(fd);
    return;
  }
  const int yes = 1;  // an answer is written as head and body: Nagle would hold the body for an ACK
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &yes, sizeof yes);
  auto c = std::make_shared<Connection>();
  c->fd = fd, c->peer = peer, c->deadline = now + limits_.read_timeout, c->requests_left = limits_.keep_alive_max_requests;
  if (tls_) {
    auto session = tls_->accept(fd);
    if (!session) {
      if (log_) log_("web: " + peer + ": " + session.error().message);
      ::close(fd);
      if (from_peer == 0) f.per_address.erase(peer);
      return;
    }
    c->tls = std::move(*session);
    c->deadline = now + limits_.handshake_timeout;
  }
  if (!f.watch(fd, EPOLL_CTL_ADD)) {
    ::close(fd);
    if (from_peer == 0) f.per_address.erase(peer);
    return;
  }
  ++from_peer, ++f.open;
  f.waiting.emplace(fd, std::move(c));
}

// Bytes came (or the peer's end): buffered; a request that is whole goes to a worker, one that
// breaks a cap is refused and its connection closed.
void DeadlineHttpServer::read_from(int fd) {
  Front& f = *front_;
  const auto it = f.waiting.find(fd);
  if (it == f.waiting.end()) return;
  const std::shared_ptr<Connection> c = it->second;
  if (c->handshaking() && !shake_hands(c)) return;
  if (c->handshaking()) return;
  constexpr std::size_t kChunkBytes = 16384;
  bool ended = false;
  while (c->buffer.size() <= limits_.max_request_bytes) {
    const Received r = receive_some(fd, c->tls.get(), c->buffer, kChunkBytes);
    if (r == Received::kNone) break;
    if (r == Received::kEnded) {
      ended = true;
      break;
    }
  }
  if (!c->buffer.empty() && !c->in_request) c->in_request = true, c->deadline = Clock::now() + limits_.request_deadline;
  const Framing state = c->buffer.empty() ? Framing::kPartial : framing(c->buffer, limits_, payload_max_length_);
  if (state == Framing::kWhole) return dispatch(c);
  if (state == Framing::kNul) {
    send_refusal(*c, 400, "Bad Request", "request head holds a NUL byte", answer_headers_);
    ended = true;
  } else if (state == Framing::kTooLarge || state == Framing::kTooManyFields) {
    send_refusal(*c, 431, "Request Header Fields Too Large",
                 state == Framing::kTooLarge ? "request too large (at most " + std::to_string(limits_.max_request_bytes) + " bytes)"
                                             : "request head has more than " + std::to_string(limits_.max_header_fields) + " header fields",
                 answer_headers_);
    ended = true;
  }
  if (ended) {
    f.waiting.erase(it);
    f.close_connection(c);
  }
}

// One step of an HTTPS connection's handshake, as far as its socket allows. Once it is complete the
// connection waits `read_timeout` for its first request, as a plain one does from its accept.
bool DeadlineHttpServer::shake_hands(std::shared_ptr<Connection> c) {
  Front& f = *front_;
  using Step = tls::TlsConnection::Step;
  const Step step = tls_->handshake(*c->tls, c->peer, log_);
  const bool wants_write = step == Step::kWantWrite;
  const bool rewatched = wants_write == c->handshake_wants_write || f.watch(c->fd, EPOLL_CTL_MOD, wants_write ? EPOLLOUT : EPOLLIN);
  if (step == Step::kFailed || !rewatched) {
    f.waiting.erase(c->fd);
    f.close_connection(c);
    return false;
  }
  c->handshake_wants_write = wants_write;
  if (step == Step::kDone) c->deadline = Clock::now() + limits_.read_timeout;
  return true;
}

void DeadlineHttpServer::dispatch(std::shared_ptr<Connection> c) {
  Front& f = *front_;
  ::epoll_ctl(f.epoll_fd, EPOLL_CTL_DEL, c->fd, nullptr);
  f.waiting.erase(c->fd);
  // A worker takes the next connection by address in turn, not this one: one per enqueue, so none is left.
  f.ready.push(c->peer, c);
  f.queue->enqueue([this] {
    if (auto next = front_->ready.pop()) answer(std::move(*next));
  });
}

// Connections the workers have answered: closed, or waiting again for their next request (which
// may already be here, pipelined).
void DeadlineHttpServer::take_back() {
  Front& f = *front_;
  std::deque<std::pair<std::shared_ptr<Connection>, bool>> returned;
  {
    std::lock_guard lock(f.mutex);
    returned.swap(f.returned);
  }
  const auto now = Clock::now();
  for (auto& [c, close] : returned) {
    if (!c->out.empty()) {  // the rest of the answer, as the client reads it, then closed or back to reading
      c->writing = true, c->close_after_out = close, c->deadline = now + limits_.write_timeout;
      if (!f.watch(c->fd, EPOLL_CTL_ADD, EPOLLOUT)) {
        f.close_connection(c);
        continue;
      }
      f.waiting.emplace(c->fd, c);
      continue;
    }
    if (close || !f.watch(c->fd, EPOLL_CTL_ADD)) {
      f.close_connection(c);
      continue;
    }
    f.waiting.emplace(c->fd, c);
    wait_for_request(c);
  }
}

void DeadlineHttpServer::wait_for_request(std::shared_ptr<Connection> c) {
  c->in_request = !c->buffer.empty();
  c->deadline = Clock::now() + (c->in_request ? limits_.request_deadline : limits_.keep_alive_timeout);
  // Frames what is buffered, and reads anything new; TLS may hold decrypted bytes no event announces.
  if (c->in_request || bytes_pending(c->tls.get())) read_from(c->fd);
}

void DeadlineHttpServer::write_to(std::shared_ptr<Connection> c) {
  Front& f = *front_;
  if (send_some(c->fd, c->tls.get(), c->out) == Sent::kWait) return;  // the client reads on: wait for EPOLLOUT
  if (!c->out.empty() || c->close_after_out || !f.watch(c->fd, EPOLL_CTL_MOD)) {
    f.waiting.erase(c->fd);
    f.close_connection(c);
    return;
  }
  c->writing = false;
  wait_for_request(c);
}

// Waits that ended: a request not whole by its deadline is answered 408, a silent connection closed.
void DeadlineHttpServer::end_waits(int listen_fd) {
  Front& f = *front_;
  const auto now = Clock::now();
  f.next_scan = now + kScanPeriod;
  for (auto it = f.waiting.begin(); it != f.waiting.end();) {
    if (it->second->deadline > now) {
      ++it;
      continue;
    }
    if (it->second->handshaking())
      tls_->handshake_too_slow(it->second->peer, log_);
    else if (it->second->in_request && !it->second->writing)
      send_refusal(*it->second, 408, "Request Timeout", "request not complete within its deadline", answer_headers_);
    f.close_connection(it->second);
    it = f.waiting.erase(it);
  }
  if (f.accept_paused && now >= f.accept_paused_until) f.accept_paused = !f.watch(listen_fd, EPOLL_CTL_ADD);
  for (Tally* t : {&f.no_descriptors, &f.over_address_cap, &f.over_total_cap}) t->flush(now, log_);
}

bool DeadlineHttpServer::serve_after_bind() {
  Front& f = *front_;
  const int listen_fd = svr_sock_;
  {
    std::lock_guard lock(f.mutex);
    if (f.stopping || listen_fd == INVALID_SOCKET || f.epoll_fd < 0 || f.wake_fd < 0) return false;
    f.running = true;
  }
  // HTTPS: OpenSSL's writes to a client gone raise SIGPIPE. httplib::Server's constructor ignores
  // it for the whole process; blocked here too, so HTTPS does not rest on that (the workers this
  // thread starts inherit the mask).
  tls::block_sigpipe_on_this_thread();
  warm_up();
  std::unique_ptr<httplib::TaskQueue> queue(new_task_queue());
  f.queue = queue.get();
  const std::size_t fd_limit = descriptor_limit();
  f.max_connections = std::min(limits_.max_connections, fd_limit > 2 * kReservedDescriptors ? fd_limit - kReservedDescriptors : fd_limit / 2);
  ::fcntl(listen_fd, F_SETFL, ::fcntl(listen_fd, F_GETFL) | O_NONBLOCK);
  f.watch(listen_fd, EPOLL_CTL_ADD);
  f.watch(f.wake_fd, EPOLL_CTL_ADD);

  // The loop: accept, read what came, dispatch whole requests, take connections back, end waits.
  std::array<epoll_event, 256> events{};
  for (;;) {
    {
      std::lock_guard lock(f.mutex);
      if (f.stopping) break;
    }
    const auto now = Clock::now();
    const auto wait = std::chrono::duration_cast<milliseconds>(f.next_scan - now).count();
    const int n = ::epoll_wait(f.epoll_fd, events.data(), static_cast<int>(events.size()), static_cast<int>(std::clamp<long long>(wait, 0, kScanPeriod.count())));
    if (n < 0 && errno != EINTR) break;
    for (int i = 0; i < std::max(n, 0); ++i) {
      const int fd = events[static_cast<std::size_t>(i)].data.fd;
      if (fd == listen_fd) {
        accept_waiting(listen_fd);
      } else if (fd == f.wake_fd) {
        std::uint64_t count = 0;
        (void)!::read(f.wake_fd, &count, sizeof count);
        take_back();
      } else if (const auto it = f.waiting.find(fd); it != f.waiting.end() && it->second->writing) {
        write_to(it->second);
      } else {
        read_from(fd);
      }
    }
    if (Clock::now() >= f.next_scan) end_waits(listen_fd);
  }

  // Stopping: the listening socket and the waiting connections close; workers finish and close theirs.
  svr_sock_ = INVALID_SOCKET;
  ::shutdown(listen_fd, SHUT_RDWR);
  ::close(listen_fd);
  for (auto& [fd, c] : f.waiting) f.close_connection(c);
  f.waiting.clear();
  queue->shutdown();
  {
    std::lock_guard lock(f.mutex);
    for (auto& [c, close] : f.returned) ::close(c->fd);
    f.returned.clear();
    f.running = false;
  }
  f.queue = nullptr;
  return true;
}

}  // namespace epa::web
