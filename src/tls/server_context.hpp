#pragma once
// A TLS server's OpenSSL context, as every secure port of the appliance sets it up: TLS 1.2 and
// 1.3 only, no renegotiation, no compression, forward-secret ciphers (ECDHE with AES-GCM or
// ChaCha20-Poly1305 in TLS 1.2), the device certificate and key, and the clients verified
// against the plant's CA (and its CRL, when one is given). A client certificate is required
// (Modbus/TCP Security), only asked for or not asked for (HTTPS, where it is one way to log in).
// No session is ever resumed: each handshake is a whole one, its certificate checked each time, and
// there is no cache for a crowd of clients to fill. When `roles`
// is not empty, a client certificate must carry the Modbus/TCP Security role extension naming
// one of them, or the handshake fails: a certificate without rights here never gets a session.
#include <memory>
#include <string>
#include <vector>

#include "core/result.hpp"
#include "tls/openssl_handles.hpp"

namespace epa::tls {

// The PEM files a secure port uses; relative paths are the caller's to resolve.
struct ServerFiles {
  std::string ca;    // the CA(s) that sign client certificates
  std::string cert;  // the device certificate (its chain may follow it in the file)
  std::string key;   // the device certificate's private key
  std::string crl;   // "": no revocation list; else clients are checked against it
};

enum class ClientCertificate {
  kRequired,  // Modbus/TCP Security: no certificate, no session
  kOptional,  // asked for; a client without one gets in (HTTPS, where the token is the other way)
  kNone,      // not asked for at all (a browser then never asks its user to pick one)
};

struct ClientPolicy {
  ClientCertificate certificate = ClientCertificate::kRequired;
  std::vector<std::string> roles;  // the roles a client certificate may name; empty: any, or none
};

class ServerContext {
 public:
  // Reads and checks the files (the key must match the certificate; a CRL must parse and be
  // signed by the CA); errors name the file and what was wrong.
  static core::Result<std::unique_ptr<ServerContext>> load(const ServerFiles& files, const ClientPolicy& policy);
  SSL_CTX* get() const { return context_.get(); }
  const ClientPolicy& policy() const { return policy_; }

  // Why the client at the other end of `ssl` was refused in its handshake ("" if it was not),
  // as the verification found it: "certificate CN=x: certificate revoked".
  static const std::string& refusal(const SSL* ssl);

 private:
  ServerContext(SslContextHandle context, ClientPolicy policy) : context_(std::move(context)), policy_(std::move(policy)) {}
  SslContextHandle context_;
  ClientPolicy policy_;
};

// A new SSL object for `fd` on `context`, with its refusal slot ready for the verification.
core::Result<SslHandle> new_server_ssl(const ServerContext& context, int fd);

}  // namespace epa::tls
