#pragma once
// HTTPS in the web front end (deadline_http_server.hpp): the TLS context its connections share,
// each connection's handshake driven a step at a time on the front end's one thread as its
// socket becomes ready, and refusals logged once per address with a back-off (a client with a
// bad certificate, or a scanner sending garbage, reconnects in a loop). TLS lives below httplib:
// a worker parses and answers the decrypted bytes as it does plain HTTP (connection_bytes.hpp).
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/result.hpp"
#include "tls/refusal_log.hpp"
#include "tls/server_context.hpp"
#include "tls/tls_connection.hpp"

namespace epa::web {

enum class ClientCertificates {
  kOff,       // none asked for: the token alone gives commands
  kOptional,  // asked for: one signed by the CA logs in with its role's rights; without one, the token
};

struct HttpsSettings {
  tls::ServerFiles files;  // the CA, the device certificate and key, the CRL ("": none)
  ClientCertificates client_certificates = ClientCertificates::kOptional;
  std::vector<std::string> roles;  // a client certificate must name one of them, or its handshake fails (empty: any)
};

class FrontEndTls {
 public:
  using Log = std::function<void(const std::string&)>;

  // Reads and checks the files; the error names the file and what was wrong.
  static core::Result<std::unique_ptr<FrontEndTls>> load(const HttpsSettings& settings);

  // A TLS session on the accepted socket `fd`, its handshake not begun.
  core::Result<std::unique_ptr<tls::TlsConnection>> accept(int fd) const;
  // One step of `session`'s handshake with the client at `address`; a failure is logged through
  // `log` (at most once per address per back-off) and the caller closes the connection.
  tls::TlsConnection::Step handshake(tls::TlsConnection& session, const std::string& address, const Log& log);
  // `address` did not complete its handshake by the deadline: logged as a refusal.
  void handshake_too_slow(const std::string& address, const Log& log);

 private:
  explicit FrontEndTls(std::unique_ptr<tls::ServerContext> context) : context_(std::move(context)) {}
  void refused(const std::string& address, const std::string& why, const Log& log);
  std::unique_ptr<tls::ServerContext> context_;
  tls::RefusalLog refusals_;  // the front end's thread only
};

}  // namespace epa::web
