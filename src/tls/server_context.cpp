#include "tls/server_context.hpp"

#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/x509_vfy.h>
#include <openssl/x509err.h>

#include <algorithm>
#include <cstdio>

#include <fmt/format.h>

#include "tls/certificate_role.hpp"

namespace epa::tls {

namespace {
// Forward secrecy only; TLS 1.3's own suites are all forward-secret and stay OpenSSL's default.
constexpr const char* kTls12Ciphers = "ECDHE-ECDSA-AES128-GCM-SHA256:ECDHE-RSA-AES128-GCM-SHA256:ECDHE-ECDSA-AES256-GCM-SHA384:"
                                      "ECDHE-RSA-AES256-GCM-SHA384:ECDHE-ECDSA-CHACHA20-POLY1305:ECDHE-RSA-CHACHA20-POLY1305";
constexpr int kMaxChainDepth = 4;  // a plant's PKI: root, an intermediate or two, the leaf

// Where each SSL keeps why its client was refused, and where the context keeps its policy.
int refusal_index() {
  static const int index = SSL_get_ex_new_index(0, nullptr, nullptr, nullptr, [](void*, void* p, CRYPTO_EX_DATA*, int, long, void*) {
    delete static_cast<std::string*>(p);
  });
  return index;
}
int policy_index() {
  static const int index = SSL_CTX_get_ex_new_index(0, nullptr, nullptr, nullptr, nullptr);
  return index;
}

std::string* refusal_slot(const SSL* ssl) { return static_cast<std::string*>(SSL_get_ex_data(ssl, refusal_index())); }

// The role check on the client's own certificate, once OpenSSL found its chain good.
std::string role_problem(X509* leaf, const ClientPolicy& policy) {
  if (policy.roles.empty()) return "";
  auto role = role_of(leaf);
  if (!role) return role.error().message;
  if (!*role) return fmt::format("it carries no role (extension {})", kModbusRoleOid);
  if (std::ranges::find(policy.roles, **role) == policy.roles.end()) return fmt::format("its role \"{}\" is not in the role table", **role);
  return "";
}

int verify_client(int preverified, X509_STORE_CTX* store) {
  auto* ssl = static_cast<SSL*>(X509_STORE_CTX_get_ex_data(store, SSL_get_ex_data_X509_STORE_CTX_idx()));
  std::string* why = ssl ? refusal_slot(ssl) : nullptr;
  X509* cert = X509_STORE_CTX_get_current_cert(store);
  const std::string who = cert ? subject_of(cert) : "?";
  if (!preverified) {
    if (why && why->empty()) *why = fmt::format("certificate {}: {}", who, X509_verify_cert_error_string(X509_STORE_CTX_get_error(store)));
    return 0;
  }
  if (X509_STORE_CTX_get_error_depth(store) != 0) return 1;
  const auto* policy = static_cast<const ClientPolicy*>(SSL_CTX_get_ex_data(SSL_get_SSL_CTX(ssl), policy_index()));
  if (const std::string problem = policy ? role_problem(cert, *policy) : ""; !problem.empty()) {
    if (why) *why = fmt::format("certificate {}: {}", who, problem);
    X509_STORE_CTX_set_error(store, X509_V_ERR_APPLICATION_VERIFICATION);
    return 0;
  }
  return 1;
}

core::Result<X509CrlHandle> read_crl(const std::string& path) {
  FILE* f = std::fopen(path.c_str(), "r");
  if (!f) return core::io_error(fmt::format("CRL {}: cannot open it", path));
  X509CrlHandle crl(PEM_read_X509_CRL(f, nullptr, nullptr, nullptr));
  std::fclose(f);
  if (!crl) return core::parse_error(fmt::format("CRL {}: not a PEM CRL ({})", path, take_openssl_errors()));
  return crl;
}

core::Status load_files(SSL_CTX* ctx, const ServerFiles& files) {
  ERR_clear_error();
  if (SSL_CTX_use_certificate_chain_file(ctx, files.cert.c_str()) != 1)
    return core::io_error(fmt::format("device certificate {}: {}", files.cert, take_openssl_errors()));
  // OpenSSL checks the key against the certificate as it loads it.
  const bool key_loaded = SSL_CTX_use_PrivateKey_file(ctx, files.key.c_str(), SSL_FILETYPE_PEM) == 1;
  if (!key_loaded && ERR_GET_REASON(ERR_peek_last_error()) == X509_R_KEY_VALUES_MISMATCH) {
    ERR_clear_error();
    return core::invalid_argument(fmt::format("device key {} does not belong to the certificate {}", files.key, files.cert));
  }
  if (!key_loaded) return core::io_error(fmt::format("device key {}: {}", files.key, take_openssl_errors()));
  if (SSL_CTX_load_verify_locations(ctx, files.ca.c_str(), nullptr) != 1)
    return core::io_error(fmt::format("CA {}: {}", files.ca, take_openssl_errors()));
  // The CAs the server names in its certificate request, so a client picks the right certificate.
  STACK_OF(X509_NAME)* names = SSL_load_client_CA_file(files.ca.c_str());
  if (!names) return core::io_error(fmt::format("CA {}: no certificate in it", files.ca));
  SSL_CTX_set_client_CA_list(ctx, names);
  if (files.crl.empty()) return core::ok();
  auto crl = read_crl(files.crl);
  if (!crl) return crl.error();
  X509_STORE* store = SSL_CTX_get_cert_store(ctx);
  if (X509_STORE_add_crl(store, crl->get()) != 1) return core::io_error(fmt::format("CRL {}: {}", files.crl, take_openssl_errors()));
  X509_STORE_set_flags(store, X509_V_FLAG_CRL_CHECK);  // the leaf against the CRL of its issuer
  return core::ok();
}
}  // namespace

core::Result<std::unique_ptr<ServerContext>> ServerContext::load(const ServerFiles& files, const ClientPolicy& policy) {
  SslContextHandle ctx(SSL_CTX_new(TLS_server_method()));
  if (!ctx) return core::io_error("TLS: " + take_openssl_errors());
  SSL_CTX_set_min_proto_version(ctx.get(), TLS1_2_VERSION);
  // A client that closes without close_notify has closed, not failed (most Modbus clients do).
  SSL_CTX_set_options(ctx.get(), SSL_OP_NO_RENEGOTIATION | SSL_OP_NO_COMPRESSION | SSL_OP_CIPHER_SERVER_PREFERENCE |
                                     SSL_OP_IGNORE_UNEXPECTED_EOF);
  // No resumption. TLS 1.3 tickets also arrive after the handshake as records without data, and a
  // client that polls its socket then reads (pymodbus 3.0's) takes them for an answer and fails.
  // With client certificates asked for, OpenSSL fails a TLS 1.2 client that offers to resume in a
  // context without a session id context ("internal error"): it is set, though nothing resumes.
  SSL_CTX_set_num_tickets(ctx.get(), 0);
  SSL_CTX_set_options(ctx.get(), SSL_OP_NO_TICKET);
  SSL_CTX_set_session_cache_mode(ctx.get(), SSL_SESS_CACHE_OFF);
  static constexpr unsigned char kSessionContext[] = "epa";
  SSL_CTX_set_session_id_context(ctx.get(), kSessionContext, sizeof kSessionContext - 1);
  if (SSL_CTX_set_cipher_list(ctx.get(), kTls12Ciphers) != 1) return core::io_error("TLS ciphers: " + take_openssl_errors());
  // Answers leave in one write each; a record the socket cannot take whole is the caller's to handle.
  SSL_CTX_set_mode(ctx.get(), SSL_MODE_ACCEPT_MOVING_WRITE_BUFFER);
  if (auto s = load_files(ctx.get(), files); !s) return s.error();
  const int mode = policy.certificate == ClientCertificate::kNone ? SSL_VERIFY_NONE
                   : SSL_VERIFY_PEER | (policy.certificate == ClientCertificate::kRequired ? SSL_VERIFY_FAIL_IF_NO_PEER_CERT : 0);
  SSL_CTX_set_verify(ctx.get(), mode, policy.certificate == ClientCertificate::kNone ? nullptr : verify_client);
  SSL_CTX_set_verify_depth(ctx.get(), kMaxChainDepth);
  std::unique_ptr<ServerContext> out(new ServerContext(std::move(ctx), policy));
  SSL_CTX_set_ex_data(out->get(), policy_index(), &out->policy_);
  return out;
}

const std::string& ServerContext::refusal(const SSL* ssl) {
  static const std::string none;
  const std::string* why = refusal_slot(ssl);
  return why ? *why : none;
}

core::Result<SslHandle> new_server_ssl(const ServerContext& context, int fd) {
  SslHandle ssl(SSL_new(context.get()));
  if (!ssl || SSL_set_fd(ssl.get(), fd) != 1) return core::io_error("TLS: " + take_openssl_errors());
  SSL_set_ex_data(ssl.get(), refusal_index(), new std::string);
  return ssl;
}

}  // namespace epa::tls
