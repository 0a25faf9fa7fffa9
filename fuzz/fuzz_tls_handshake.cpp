// The secure ports' TLS server side: whatever a client sends before and during its handshake
// (garbage before the ClientHello, a ClientHello cut short or mangled, records out of order) is
// fed to a TlsConnection over a socket pair, stepped until it fails, completes or waits for more.
// Nothing may crash or hang; a failure must say why; a handshake never completes from bytes that
// carry no valid client certificate (the fuzzer has no key to sign one with). The second half of
// the input, when it parses as a DER certificate, is read for its role the way the verification
// reads it.
#include <openssl/x509.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "tls/certificate_authority.hpp"
#include "tls/certificate_role.hpp"
#include "tls/server_context.hpp"
#include "tls/tls_connection.hpp"

namespace {

// The appliance's context, from certificates made once for the run.
std::unique_ptr<epa::tls::ServerContext> make_context() {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("epa-fuzz-tls." + std::to_string(::getpid()));
  fs::remove_all(dir);
  if (!epa::tls::ca::init(dir.string(), {})) __builtin_trap();
  const epa::tls::ServerFiles files{(dir / "ca.pem").string(), (dir / "device.pem").string(), (dir / "device.key").string(),
                                    (dir / "crl.pem").string()};
  auto context = epa::tls::ServerContext::load(files, {epa::tls::ClientCertificate::kRequired, {"operator"}});
  fs::remove_all(dir);
  if (!context) __builtin_trap();
  return std::move(*context);
}

void read_role(const std::uint8_t* der, std::size_t size) {
  const unsigned char* p = der;
  X509* cert = d2i_X509(nullptr, &p, static_cast<long>(size));
  if (!cert) return;
  (void)epa::tls::role_of(cert);
  (void)epa::tls::subject_of(cert);
  X509_free(cert);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using epa::tls::TlsConnection;
  static const std::unique_ptr<epa::tls::ServerContext> context = make_context();
  read_role(data + size / 2, size - size / 2);
  int fds[2];
  if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, fds) != 0) return 0;
  // What the client sent, then its end of the connection: the server sees the bytes, then EOF.
  if (size > 0 && ::write(fds[1], data, size) != static_cast<ssize_t>(size)) __builtin_trap();
  ::shutdown(fds[1], SHUT_WR);
  auto server = TlsConnection::accept(*context, fds[0]);
  if (!server) __builtin_trap();
  TlsConnection::Step step = TlsConnection::Step::kWantRead;
  for (int round = 0; round < 8 && (step == TlsConnection::Step::kWantRead || step == TlsConnection::Step::kWantWrite); ++round)
    step = (*server)->handshake();
  if (step == TlsConnection::Step::kDone) __builtin_trap();  // no certificate could have been proved
  if (step == TlsConnection::Step::kFailed && (*server)->failure().empty()) __builtin_trap();
  ::close(fds[0]);
  ::close(fds[1]);
  return 0;
}
