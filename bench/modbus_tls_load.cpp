// Load generator for bench/modbus_tls_vs_plain.sh: Modbus/TCP Security (TLS) against plain Modbus
// TCP with the same client code, so the comparison measures TLS and nothing else. N client
// threads, each with one persistent connection to HOST:PORT, reading `--count` holding registers
// (FC3) in a closed loop; the framing (MBAP header, as Modbus/TCP Security keeps it) and the
// answer's checks are this file's own in both modes, only the transport differs:
//   plain   send()/recv() on a blocking socket (1 s timeouts);
//   --tls   OpenSSL 3 on the same socket: the client certificate (--cert, --key), the plant's CA
//           trusted (--ca) and the appliance's certificate checked against --host (its SAN),
//           OpenSSL's default protocol choice (TLS 1.3 with the appliance), no session resumption.
// All threads start together; requests begun in the first second (warm-up: connect, handshake,
// caches) are not counted, those begun in the next --seconds are. Each latency goes into the
// thread's own histogram (1 us bins up to 100 ms, then one overflow bin; the exact maximum kept
// aside), merged at the end, as bench/modbus_load does. Prints one JSON line:
//   {"mode":"tls","clients":N,"seconds":T,"interval_ms":0,"requests":R,"throughput_rps":...,
//    "p50_us":...,"p99_us":...,"max_us":...,"errors":E}
// Percentiles are the upper edge of their 1 us bin.
//
// --interval-ms I   paced instead of closed-loop: each client starts a request every I ms (an HMI
//                   polling), on a fixed schedule; a late answer delays only its own request.
// --handshakes      (with --tls) each thread connects, completes the handshake, reads once,
//                   closes (close_notify), again and again; prints handshakes_per_s: the whole
//                   cycles completed in the measured seconds, and their latency percentiles.
// --wait-ready S    retry connect (+ handshake) + one FC3 read until it succeeds, at most S
//                   seconds (exit 2 if it never does); with --seconds 0 that is all it does.
// --bind ADDR       the clients' source address (a loopback address other than 127.0.0.1).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <openssl/err.h>
#include <openssl/ssl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "latency_tally.hpp"

namespace {

using Clock = std::chrono::steady_clock;

struct Options {
  std::string host = "127.0.0.1";
  std::string bind;
  int port = 802;
  int unit = 1;
  int address = 0;
  int count = 10;
  bool tls = false;
  std::string ca, cert, key;
};

std::string openssl_errors() {
  std::string out;
  for (unsigned long e = ERR_get_error(); e != 0; e = ERR_get_error()) {
    char buf[256];
    ERR_error_string_n(e, buf, sizeof buf);
    out += (out.empty() ? "" : "; ") + std::string(buf);
  }
  return out.empty() ? "no OpenSSL error queued" : out;
}

// The client side of TLS: the client's certificate, the CA that signed the appliance's, its name
// checked; TLS 1.2 at least (the appliance's floor), OpenSSL's default otherwise (TLS 1.3).
SSL_CTX* make_client_context(const Options& o) {
  SSL_CTX* ctx = SSL_CTX_new(TLS_client_method());
  if (!ctx) return nullptr;
  SSL_CTX_set_min_proto_version(ctx, TLS1_2_VERSION);
  SSL_CTX_set_session_cache_mode(ctx, SSL_SESS_CACHE_OFF);  // every connect a full handshake
  if (SSL_CTX_load_verify_locations(ctx, o.ca.c_str(), nullptr) != 1 ||
      SSL_CTX_use_certificate_chain_file(ctx, o.cert.c_str()) != 1 ||
      SSL_CTX_use_PrivateKey_file(ctx, o.key.c_str(), SSL_FILETYPE_PEM) != 1) {
    std::fprintf(stderr, "modbus_tls_load: loading %s, %s, %s: %s\n", o.ca.c_str(), o.cert.c_str(), o.key.c_str(),
                 openssl_errors().c_str());
    SSL_CTX_free(ctx);
    return nullptr;
  }
  SSL_CTX_set_verify(ctx, SSL_VERIFY_PEER, nullptr);
  return ctx;
}

// One connection, plain or TLS, on a blocking socket with 1 s send and receive timeouts.
class Connection {
 public:
  Connection(const Options& o, SSL_CTX* ctx) : o_(o), ctx_(ctx) {}
  ~Connection() { close(); }
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  bool open() {
    close();
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd_ < 0) return false;
    const timeval timeout{1, 0};
    setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
    setsockopt(fd_, SOL_SOCKET, SO_SNDTIMEO, &timeout, sizeof timeout);
    const int one = 1;
    setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    if (!o_.bind.empty()) {
      sockaddr_in local{};
      local.sin_family = AF_INET;
      if (inet_pton(AF_INET, o_.bind.c_str(), &local.sin_addr) != 1 || ::bind(fd_, reinterpret_cast<sockaddr*>(&local), sizeof local) != 0)
        return close(), false;
    }
    sockaddr_in peer{};
    peer.sin_family = AF_INET;
    peer.sin_port = htons(static_cast<std::uint16_t>(o_.port));
    if (inet_pton(AF_INET, o_.host.c_str(), &peer.sin_addr) != 1 || ::connect(fd_, reinterpret_cast<sockaddr*>(&peer), sizeof peer) != 0)
      return close(), false;
    if (!ctx_) return true;
    ssl_ = SSL_new(ctx_);
    if (!ssl_ || SSL_set_fd(ssl_, fd_) != 1 || SSL_set1_host(ssl_, o_.host.c_str()) != 1) return close(), false;
    ERR_clear_error();
    if (SSL_connect(ssl_) != 1) {
      ERR_clear_error();
      return close(), false;
    }
    return true;
  }

  bool is_open() const { return fd_ >= 0; }

  bool write_all(const std::uint8_t* data, std::size_t n) {
    if (ssl_) {
      std::size_t written = 0;
      ERR_clear_error();
      const bool ok = SSL_write_ex(ssl_, data, n, &written) == 1 && written == n;
      if (!ok) ERR_clear_error();
      return ok;
    }
    while (n > 0) {
      const ssize_t k = ::send(fd_, data, n, MSG_NOSIGNAL);
      if (k <= 0) return false;
      data += k;
      n -= static_cast<std::size_t>(k);
    }
    return true;
  }

  bool read_exact(std::uint8_t* data, std::size_t n) {
    while (n > 0) {
      std::size_t k = 0;
      if (ssl_) {
        ERR_clear_error();
        if (SSL_read_ex(ssl_, data, n, &k) != 1) return ERR_clear_error(), false;
      } else {
        const ssize_t r = ::recv(fd_, data, n, 0);
        if (r <= 0) return false;
        k = static_cast<std::size_t>(r);
      }
      data += k;
      n -= k;
    }
    return true;
  }

  void close() {
    if (ssl_) {
      SSL_shutdown(ssl_);  // close_notify, the server's own not waited for
      SSL_free(ssl_);
      ssl_ = nullptr;
    }
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  const Options& o_;
  SSL_CTX* ctx_;
  int fd_ = -1;
  SSL* ssl_ = nullptr;
};

enum class Answer { kOk, kException, kBroken };

// One FC3 request and its answer, framed and checked here: kException keeps the stream in step,
// kBroken (timeout, close, an answer that does not match the request) does not.
Answer read_holding(Connection& c, const Options& o, std::uint16_t tid) {
  const auto hi = [](int v) { return static_cast<std::uint8_t>((v >> 8) & 0xFF); };
  const auto lo = [](int v) { return static_cast<std::uint8_t>(v & 0xFF); };
  const std::array<std::uint8_t, 12> request = {hi(tid), lo(tid), 0, 0, 0, 6, static_cast<std::uint8_t>(o.unit), 0x03,
                                                hi(o.address), lo(o.address), hi(o.count), lo(o.count)};
  if (!c.write_all(request.data(), request.size())) return Answer::kBroken;
  std::array<std::uint8_t, 7 + 253> answer{};
  if (!c.read_exact(answer.data(), 7)) return Answer::kBroken;
  const int length = (answer[4] << 8) | answer[5];
  if (answer[0] != request[0] || answer[1] != request[1] || answer[2] != 0 || answer[3] != 0 || length < 2 || length > 254 ||
      answer[6] != request[6])
    return Answer::kBroken;
  if (!c.read_exact(answer.data() + 7, static_cast<std::size_t>(length - 1))) return Answer::kBroken;
  if (answer[7] == (0x03 | 0x80) && length == 3) return Answer::kException;
  const bool whole = answer[7] == 0x03 && answer[8] == 2 * o.count && length == 3 + 2 * o.count;
  return whole ? Answer::kOk : Answer::kBroken;
}

bool wait_ready(const Options& o, SSL_CTX* ctx, double timeout_s) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  do {
    Connection c(o, ctx);
    if (c.open() && read_holding(c, o, 1) == Answer::kOk) return true;
    c.close();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  } while (Clock::now() < deadline);
  return false;
}

using LatencyTally = epa::bench::LatencyTally;

struct Run {
  Clock::time_point from, until;  // measured: requests begun in [from, until)
  std::chrono::nanoseconds interval{0};
};

// One persistent connection (reconnecting when it breaks), requests closed-loop or on a schedule.
void poll_thread(const Options& o, SSL_CTX* ctx, const Run& run, LatencyTally& r) {
  Connection c(o, ctx);
  r.connected = c.open();
  std::uint16_t tid = 0;
  Clock::time_point next = Clock::now();
  for (Clock::time_point start = Clock::now(); start < run.until; start = Clock::now()) {
    if (run.interval.count() > 0) {
      if (next > start) std::this_thread::sleep_until(next);  // the stimulus: an HMI's poll period
      start = Clock::now();
      next += run.interval;
      if (next < start) next = start + run.interval;  // a late answer does not bunch the next requests
      if (start >= run.until) break;
    }
    if (!c.is_open()) {  // lost (or never had) the connection: count it, retry a little later
      if (start >= run.from) ++r.errors;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      c.open();
      continue;
    }
    const Answer a = read_holding(c, o, ++tid);
    const auto end = Clock::now();
    if (a != Answer::kOk) {
      if (a == Answer::kBroken) c.close();
      if (start >= run.from) ++r.errors;
      continue;
    }
    if (start >= run.from) r.record(start, end);
  }
}

// Connect, handshake, one read, close: each whole cycle is one sample.
void handshake_thread(const Options& o, SSL_CTX* ctx, const Run& run, LatencyTally& r) {
  std::uint16_t tid = 0;
  for (Clock::time_point start = Clock::now(); start < run.until; start = Clock::now()) {
    Connection c(o, ctx);
    const bool ok = c.open() && read_holding(c, o, ++tid) == Answer::kOk;
    c.close();
    const auto end = Clock::now();
    r.connected = r.connected || ok;
    if (start < run.from) continue;
    if (ok) {
      r.record(start, end);
    } else {
      ++r.errors;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Modbus TCP / Modbus/TCP Security load generator: N clients reading holding registers"};
  Options o;
  int clients = 1;
  double seconds = 10.0, warmup_s = 1.0, ready_timeout_s = 0.0, interval_ms = 0.0;
  bool handshakes = false;
  app.add_option("--host", o.host, "Server IPv4 address (with --tls also the name checked in its certificate)")->capture_default_str();
  app.add_option("--bind", o.bind, "Source IPv4 address of the clients");
  app.add_option("--port", o.port, "Server TCP port")->capture_default_str()->check(CLI::Range(1, 65535));
  app.add_option("--unit", o.unit, "Unit id")->capture_default_str()->check(CLI::Range(0, 255));
  app.add_option("--address", o.address, "First holding register (0-based)")->capture_default_str()->check(CLI::Range(0, 65535));
  app.add_option("--count", o.count, "Holding registers per request")->capture_default_str()->check(CLI::Range(1, 125));
  app.add_option("--clients", clients, "Client threads, one connection each")->capture_default_str()->check(CLI::Range(1, 256));
  app.add_option("--seconds", seconds, "Measured time after the warm-up (0: no load)")->capture_default_str()->check(CLI::Range(0.0, 3600.0));
  app.add_option("--warmup", warmup_s, "Warm-up before measuring, s")->capture_default_str()->check(CLI::Range(0.0, 60.0));
  app.add_option("--interval-ms", interval_ms, "Paced: each client starts a request this often (0: closed loop)")
      ->capture_default_str()->check(CLI::Range(0.0, 60000.0));
  app.add_option("--wait-ready", ready_timeout_s, "First wait until one read succeeds, at most this many seconds")->check(CLI::Range(0.0, 600.0));
  app.add_flag("--tls", o.tls, "Modbus/TCP Security: TLS with a client certificate");
  app.add_option("--ca", o.ca, "With --tls: the CA certificate that signed the server's (PEM)");
  app.add_option("--cert", o.cert, "With --tls: the client's certificate (PEM)");
  app.add_option("--key", o.key, "With --tls: the client's private key (PEM)");
  app.add_flag("--handshakes", handshakes, "With --tls: connect, handshake, one read, close, in a loop; prints handshakes per second");
  CLI11_PARSE(app, argc, argv);
  if (o.tls && (o.ca.empty() || o.cert.empty() || o.key.empty()))
    return std::fprintf(stderr, "modbus_tls_load: --tls needs --ca, --cert and --key\n"), 1;
  if (handshakes && !o.tls) return std::fprintf(stderr, "modbus_tls_load: --handshakes needs --tls\n"), 1;
  std::signal(SIGPIPE, SIG_IGN);  // OpenSSL writes with write(): a closed peer is an error, not a signal

  SSL_CTX* ctx = nullptr;
  if (o.tls && !(ctx = make_client_context(o))) return 1;
  struct FreeContext {
    SSL_CTX* c;
    ~FreeContext() { SSL_CTX_free(c); }
  } free_context{ctx};

  if (ready_timeout_s > 0 && !wait_ready(o, ctx, ready_timeout_s)) {
    std::fprintf(stderr, "modbus_tls_load: %s:%d did not answer a read%s within %g s\n", o.host.c_str(), o.port, o.tls ? " over TLS" : "",
                 ready_timeout_s);
    return 2;
  }
  if (seconds <= 0) return 0;

  Run run;
  run.from = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(warmup_s));
  run.until = run.from + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
  run.interval = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double, std::milli>(interval_ms));
  std::vector<LatencyTally> results(static_cast<std::size_t>(clients));
  {
    std::vector<std::jthread> threads;
    for (auto& r : results)
      threads.emplace_back(handshakes ? handshake_thread : poll_thread, std::cref(o), ctx, std::cref(run), std::ref(r));
  }

  const epa::bench::LatencySummary all(results);
  if (all.connected < clients) std::fprintf(stderr, "modbus_tls_load: only %d of %d clients connected at first\n", all.connected, clients);
  const std::string rate = epa::bench::json_number(static_cast<double>(all.requests) / seconds);
  std::printf("{\"mode\":\"%s\",\"clients\":%d,\"seconds\":%g,\"interval_ms\":%g,\"%s\":%llu,\"%s\":%s,\"p50_us\":%s,\"p99_us\":%s,"
              "\"max_us\":%s,\"errors\":%llu}\n",
              handshakes ? "handshakes" : o.tls ? "tls" : "plain", clients, seconds, interval_ms, handshakes ? "handshakes" : "requests",
              static_cast<unsigned long long>(all.requests), handshakes ? "handshakes_per_s" : "throughput_rps", rate.c_str(),
              epa::bench::json_number(all.percentile_us(0.50), "%.0f").c_str(),
              epa::bench::json_number(all.percentile_us(0.99), "%.0f").c_str(), epa::bench::json_number(all.max_us()).c_str(),
              static_cast<unsigned long long>(all.errors));
  return all.requests > 0 ? 0 : 1;
}
