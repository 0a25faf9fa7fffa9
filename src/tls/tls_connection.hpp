#pragma once
// One accepted TLS connection on a non-blocking socket, for a server that polls many of them on
// one thread: the handshake is driven a step at a time as the socket becomes ready, reads take
// what has arrived, and a write is whole or fails (answers are small: a socket that cannot take
// one is a client that does not read). The socket stays the caller's to poll and close.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/result.hpp"
#include "tls/server_context.hpp"

namespace epa::tls {

// Who the client proved to be in its handshake.
struct PeerIdentity {
  bool has_certificate = false;
  std::string subject;  // "/CN=hmi-1/O=Plant", printable ASCII
  std::string role;     // the role extension's name; "" when none
};

class TlsConnection {
 public:
  enum class Step { kDone, kWantRead, kWantWrite, kFailed };

  static core::Result<std::unique_ptr<TlsConnection>> accept(const ServerContext& context, int fd);

  // One step of the server handshake; kDone once it is complete (peer() is then known).
  Step handshake();
  bool handshake_done() const { return done_; }
  // Why the handshake or the connection failed, for the log.
  const std::string& failure() const { return failure_; }
  const PeerIdentity& peer() const { return peer_; }

  // Appends what has arrived (at most max_bytes) to `out`. kWantRead: nothing more now; kDone:
  // the client closed; kFailed: the connection is broken (failure() says why).
  Step read_into(std::vector<std::uint8_t>& out, std::size_t max_bytes);
  // Whether decrypted bytes wait that the socket's readiness will not announce (read_into takes them).
  // Bytes read from the socket that read_into left for want of room. Not SSL_has_pending alone:
  // it is also true for a record not complete yet, whose rest only the socket can bring (a server
  // polling with no wait for it spun a core).
  bool has_pending() const { return done_ && (stopped_at_max_ || SSL_pending(ssl_.get()) > 0); }
  // Sends `bytes` whole, or fails (false) when the socket cannot take them now.
  bool write(std::span<const std::uint8_t> bytes);
  // Sends what the socket takes now from the front of `bytes`, for a server that writes as its
  // client reads: kDone with `taken` (perhaps fewer than all), kWantWrite when it took none (call
  // again with the same bytes at the front, the rest may follow), kFailed. Needs the context's
  // SSL_MODE_ENABLE_PARTIAL_WRITE (and ACCEPT_MOVING_WRITE_BUFFER: the bytes may have moved).
  Step write_some(std::span<const std::uint8_t> bytes, std::size_t& taken);
  // The session, for a caller that hands it on with a request (httplib's Request::ssl).
  const SSL* ssl() const { return ssl_.get(); }
  // Tells the client the session ends (close_notify), without waiting for its answer.
  void shut_down();

 private:
  explicit TlsConnection(SslHandle ssl) : ssl_(std::move(ssl)) {}
  Step failed(int rc, const char* doing);
  SslHandle ssl_;
  bool done_ = false;
  bool stopped_at_max_ = false;  // the last read_into stopped at max_bytes with bytes still in OpenSSL
  std::string failure_;
  PeerIdentity peer_;
};

}  // namespace epa::tls
