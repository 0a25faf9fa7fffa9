#include "web/front_end_tls.hpp"

#include <chrono>

namespace epa::web {

namespace {

std::int64_t steady_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// What the web front end adds to the context every secure port is given (server_context.hpp).
void set_up_for_the_front_end(SSL_CTX* ctx) {
  // Answers leave as the client reads them: a write takes what the socket takes, record by
  // record, and a connection that waits keeps no buffers of its own (thousands may wait).
  SSL_CTX_set_mode(ctx, SSL_MODE_ENABLE_PARTIAL_WRITE | SSL_MODE_ACCEPT_MOVING_WRITE_BUFFER | SSL_MODE_RELEASE_BUFFERS);
}

}  // namespace

core::Result<std::unique_ptr<FrontEndTls>> FrontEndTls::load(const HttpsSettings& settings) {
  const auto asked = settings.client_certificates == ClientCertificates::kOff ? tls::ClientCertificate::kNone : tls::ClientCertificate::kOptional;
  auto context = tls::ServerContext::load(settings.files, {asked, settings.roles});
  if (!context) return context.error();
  set_up_for_the_front_end((*context)->get());
  return std::unique_ptr<FrontEndTls>(new FrontEndTls(std::move(*context)));
}

core::Result<std::unique_ptr<tls::TlsConnection>> FrontEndTls::accept(int fd) const { return tls::TlsConnection::accept(*context_, fd); }

tls::TlsConnection::Step FrontEndTls::handshake(tls::TlsConnection& session, const std::string& address, const Log& log) {
  const tls::TlsConnection::Step step = session.handshake();
  if (step == tls::TlsConnection::Step::kFailed) refused(address, session.failure(), log);
  return step;
}

void FrontEndTls::handshake_too_slow(const std::string& address, const Log& log) {
  refused(address, "no handshake within the request deadline", log);
}

void FrontEndTls::refused(const std::string& address, const std::string& why, const Log& log) {
  const std::string line = refusals_.refused(address, why, steady_now_ns());
  if (log && !line.empty()) log("web: " + line);
}

}  // namespace epa::web
