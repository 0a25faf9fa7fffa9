#include "web/connection_bytes.hpp"

#include <sys/socket.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdint>
#include <span>
#include <vector>

namespace epa::web {

namespace {

Received receive_plain(int fd, std::string& into, std::size_t max_bytes) {
  std::array<char, 16384> chunk{};
  for (;;) {
    const ssize_t n = ::recv(fd, chunk.data(), std::min(chunk.size(), max_bytes), 0);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return Received::kNone;
    if (n <= 0) return Received::kEnded;
    into.append(chunk.data(), static_cast<std::size_t>(n));
    return Received::kSome;
  }
}

Received receive_tls(tls::TlsConnection& tls, std::string& into, std::size_t max_bytes) {
  std::vector<std::uint8_t> got;
  const tls::TlsConnection::Step step = tls.read_into(got, max_bytes);
  into.append(got.begin(), got.end());
  if (!got.empty()) return Received::kSome;  // a close or failure behind them shows on the next call
  return step == tls::TlsConnection::Step::kWantRead ? Received::kNone : Received::kEnded;
}

Sent send_plain(int fd, std::string& out) {
  while (!out.empty()) {
    const ssize_t n = ::send(fd, out.data(), out.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return Sent::kWait;
    if (n <= 0) return Sent::kFailed;
    out.erase(0, static_cast<std::size_t>(n));
  }
  return Sent::kAll;
}

Sent send_tls(tls::TlsConnection& tls, std::string& out) {
  while (!out.empty()) {
    std::size_t taken = 0;
    const auto bytes = std::span(reinterpret_cast<const std::uint8_t*>(out.data()), out.size());
    const tls::TlsConnection::Step step = tls.write_some(bytes, taken);
    if (step == tls::TlsConnection::Step::kWantWrite) return Sent::kWait;
    // WANT_READ while writing would be a renegotiation, which the context refuses: a broken peer,
    // and waiting for the socket to be writable would only spin.
    if (step != tls::TlsConnection::Step::kDone || taken == 0) return Sent::kFailed;
    out.erase(0, taken);
  }
  return Sent::kAll;
}

}  // namespace

Received receive_some(int fd, tls::TlsConnection* tls, std::string& into, std::size_t max_bytes) {
  if (max_bytes == 0) return Received::kNone;
  return tls ? receive_tls(*tls, into, max_bytes) : receive_plain(fd, into, max_bytes);
}

Sent send_some(int fd, tls::TlsConnection* tls, std::string& out) { return tls ? send_tls(*tls, out) : send_plain(fd, out); }

}  // namespace epa::web
