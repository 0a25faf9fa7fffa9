#include "tls/tls_connection.hpp"

#include <openssl/err.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include <fmt/format.h>

#include "tls/certificate_role.hpp"

namespace epa::tls {

core::Result<std::unique_ptr<TlsConnection>> TlsConnection::accept(const ServerContext& context, int fd) {
  auto ssl = new_server_ssl(context, fd);
  if (!ssl) return ssl.error();
  SSL_set_accept_state(ssl->get());
  return std::unique_ptr<TlsConnection>(new TlsConnection(std::move(*ssl)));
}

TlsConnection::Step TlsConnection::handshake() {
  if (done_) return Step::kDone;
  ERR_clear_error();
  const int rc = SSL_do_handshake(ssl_.get());
  if (rc != 1) return failed(rc, "handshake");
  done_ = true;
  if (X509* cert = SSL_get0_peer_certificate(ssl_.get())) {
    peer_.has_certificate = true;
    peer_.subject = subject_of(cert);
    auto role = role_of(cert);  // checked in the verification when roles are asked for
    if (role && *role) peer_.role = **role;
  }
  return Step::kDone;
}

TlsConnection::Step TlsConnection::read_into(std::vector<std::uint8_t>& out, std::size_t max_bytes) {
  std::uint8_t chunk[4096];
  stopped_at_max_ = false;
  for (std::size_t taken = 0;;) {
    if (taken >= max_bytes) return stopped_at_max_ = SSL_has_pending(ssl_.get()) == 1, Step::kWantRead;
    ERR_clear_error();
    std::size_t n = 0;
    const int rc = SSL_read_ex(ssl_.get(), chunk, std::min(sizeof chunk, max_bytes - taken), &n);
    if (rc != 1) {
      const int e = SSL_get_error(ssl_.get(), rc);
      if (e == SSL_ERROR_ZERO_RETURN) return Step::kDone;
      return failed(rc, "read");
    }
    out.insert(out.end(), chunk, chunk + n);
    taken += n;
    // Nothing more read from the socket yet: the next bytes are the socket's to announce (another
    // read now would only find it empty: a system call of the few a request takes).
    if (SSL_has_pending(ssl_.get()) != 1) return Step::kWantRead;
  }
}

bool TlsConnection::write(std::span<const std::uint8_t> bytes) {
  ERR_clear_error();
  std::size_t n = 0;
  const int rc = SSL_write_ex(ssl_.get(), bytes.data(), bytes.size(), &n);
  if (rc == 1 && n == bytes.size()) return true;
  failed(rc, "write");
  return false;
}

TlsConnection::Step TlsConnection::write_some(std::span<const std::uint8_t> bytes, std::size_t& taken) {
  taken = 0;
  if (bytes.empty()) return Step::kDone;
  ERR_clear_error();
  const int rc = SSL_write_ex(ssl_.get(), bytes.data(), bytes.size(), &taken);
  if (rc == 1) return Step::kDone;
  taken = 0;
  return failed(rc, "write");
}

void TlsConnection::shut_down() {
  if (!done_) return;
  ERR_clear_error();
  SSL_shutdown(ssl_.get());  // sends close_notify; the client's own is not waited for
}

// The step after a call that did not succeed: waiting for the socket, or a failure and why.
TlsConnection::Step TlsConnection::failed(int rc, const char* doing) {
  switch (SSL_get_error(ssl_.get(), rc)) {
    case SSL_ERROR_WANT_READ: return Step::kWantRead;
    case SSL_ERROR_WANT_WRITE: return Step::kWantWrite;
    case SSL_ERROR_ZERO_RETURN:  // an end of file mid-handshake, as SSL_OP_IGNORE_UNEXPECTED_EOF reports it
      failure_ = fmt::format("TLS {}: the client closed the connection", doing);
      break;
    case SSL_ERROR_SYSCALL:
      failure_ = fmt::format("TLS {}: {}", doing, errno != 0 ? std::strerror(errno) : "the connection was closed");
      break;
    default: {
      const std::string& refused = ServerContext::refusal(ssl_.get());
      failure_ = refused.empty() ? fmt::format("TLS {}: {}", doing, take_openssl_errors()) : refused;
    }
  }
  ERR_clear_error();
  return Step::kFailed;
}

}  // namespace epa::tls
