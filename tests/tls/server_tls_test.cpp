// The server side of TLS as the secure ports use it: the context's files and their errors, and a
// handshake over a socket pair against a client built directly on OpenSSL (its own verification,
// none of our code on that side): who the client proved to be, and each refusal with its reason.
#include <gtest/gtest.h>
#include <openssl/err.h>
#include <openssl/ssl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tls/certificate_authority.hpp"
#include "tls/refusal_log.hpp"
#include "tls/server_context.hpp"
#include "tls/tls_connection.hpp"

namespace epa::tls {
namespace {

namespace fs = std::filesystem;

class ServerTls : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::temp_directory_path() / ("epa-tls-test." + std::to_string(::getpid())));
    fs::remove_all(*dir_);
    const std::string pki = (*dir_ / "pki").string(), other = (*dir_ / "other").string();
    ASSERT_TRUE(ca::init(pki, {}));
    for (const auto& [name, role] : {std::pair{"hmi", "operator"}, {"guest", "guest"}, {"gone", "viewer"}})
      ASSERT_TRUE(ca::client(pki, name, role, {}));
    ASSERT_TRUE(ca::revoke(pki, pki + "/gone.pem", {}));
    ASSERT_TRUE(ca::init(other, {}));
    ASSERT_TRUE(ca::client(other, "hmi", "operator", {}));
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }
  static std::string pki(const std::string& file) { return (*dir_ / "pki" / file).string(); }
  static std::string other(const std::string& file) { return (*dir_ / "other" / file).string(); }
  static ServerFiles files() { return {pki("ca.pem"), pki("device.pem"), pki("device.key"), pki("crl.pem")}; }

  struct Outcome {
    bool server_done = false;
    std::string failure;
    PeerIdentity peer;
  };
  // One handshake: the server through TlsConnection, the client with `cert` (none: "") and at
  // most TLS version `max_version`, stepped in turn until both stop; then one byte each way.
  Outcome handshake(const std::string& cert, const std::string& key, int max_version = TLS1_3_VERSION,
                    const std::vector<std::string>& roles = {"viewer", "operator", "engineer"}) {
    auto context = ServerContext::load(files(), {ClientCertificate::kRequired, roles});
    EXPECT_TRUE(context) << context.error().message;
    int fds[2];
    EXPECT_EQ(socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, fds), 0);
    auto server = TlsConnection::accept(**context, fds[0]);
    EXPECT_TRUE(server);
    SSL_CTX* client_ctx = SSL_CTX_new(TLS_client_method());
    SSL_CTX_set_max_proto_version(client_ctx, max_version);
    SSL_CTX_load_verify_locations(client_ctx, pki("ca.pem").c_str(), nullptr);
    if (!cert.empty()) {
      EXPECT_EQ(SSL_CTX_use_certificate_file(client_ctx, cert.c_str(), SSL_FILETYPE_PEM), 1);
      EXPECT_EQ(SSL_CTX_use_PrivateKey_file(client_ctx, key.c_str(), SSL_FILETYPE_PEM), 1);
    }
    SSL* client = SSL_new(client_ctx);
    SSL_set_fd(client, fds[1]);
    SSL_set_connect_state(client);
    Outcome out;
    TlsConnection::Step step = TlsConnection::Step::kWantRead;
    for (int round = 0; round < 50 && step != TlsConnection::Step::kFailed && step != TlsConnection::Step::kDone; ++round) {
      SSL_do_handshake(client);
      step = (*server)->handshake();
    }
    out.server_done = step == TlsConnection::Step::kDone;
    out.failure = (*server)->failure();
    out.peer = (*server)->peer();
    if (out.server_done) {  // data both ways once the server has let the client in
      const unsigned char ping = 7;
      std::size_t n = 0;
      EXPECT_EQ(SSL_write_ex(client, &ping, 1, &n), 1);
      std::vector<std::uint8_t> got;
      EXPECT_EQ((*server)->read_into(got, 16), TlsConnection::Step::kWantRead);
      EXPECT_EQ(got, std::vector<std::uint8_t>{7});
      const std::uint8_t pong[] = {9, 8};
      EXPECT_TRUE((*server)->write(pong));
    }
    SSL_free(client);
    SSL_CTX_free(client_ctx);
    ERR_clear_error();
    ::close(fds[0]);
    ::close(fds[1]);
    return out;
  }

  static fs::path* dir_;
};
fs::path* ServerTls::dir_ = nullptr;

TEST_F(ServerTls, AClientWithARoleOfTheTableGetsInAndIsKnownByItsCertificate) {
  const Outcome o = handshake(pki("hmi.pem"), pki("hmi.key"));
  ASSERT_TRUE(o.server_done) << o.failure;
  EXPECT_TRUE(o.peer.has_certificate);
  EXPECT_EQ(o.peer.subject, "/CN=hmi");
  EXPECT_EQ(o.peer.role, "operator");
}

TEST_F(ServerTls, TheSameOverTls12) {
  const Outcome o = handshake(pki("hmi.pem"), pki("hmi.key"), TLS1_2_VERSION);
  ASSERT_TRUE(o.server_done) << o.failure;
  EXPECT_EQ(o.peer.role, "operator");
}

TEST_F(ServerTls, EachRefusalSaysWhy) {
  struct Case {
    const char* what;
    std::string cert, key;
    int max_version;
    const char* reason;
  };
  const Case cases[] = {
      {"no certificate", "", "", TLS1_3_VERSION, "certificate"},
      {"another CA", other("hmi.pem"), other("hmi.key"), TLS1_3_VERSION, "unable to get local issuer certificate"},
      {"revoked", pki("gone.pem"), pki("gone.key"), TLS1_3_VERSION, "certificate revoked"},
      {"a role not in the table", pki("guest.pem"), pki("guest.key"), TLS1_3_VERSION, "role \"guest\" is not in the role table"},
      {"TLS 1.1", pki("hmi.pem"), pki("hmi.key"), TLS1_1_VERSION, "unsupported protocol"},
  };
  for (const Case& c : cases) {
    const Outcome o = handshake(c.cert, c.key, c.max_version);
    EXPECT_FALSE(o.server_done) << c.what;
    EXPECT_NE(o.failure.find(c.reason), std::string::npos) << c.what << ": " << o.failure;
  }
}

TEST_F(ServerTls, WithoutARoleTableAnyCertificateOfTheCaGetsIn) {
  const Outcome o = handshake(pki("guest.pem"), pki("guest.key"), TLS1_3_VERSION, {});
  ASSERT_TRUE(o.server_done) << o.failure;
  EXPECT_EQ(o.peer.role, "guest");
}

TEST_F(ServerTls, GarbageBeforeTheClientHelloFailsTheHandshakeAlone) {
  auto context = ServerContext::load(files(), {ClientCertificate::kRequired, {"operator"}});
  ASSERT_TRUE(context);
  int fds[2];
  ASSERT_EQ(socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, fds), 0);
  const std::string garbage = "GET / HTTP/1.1\r\nHost: x\r\n\r\n\x16\x03\x01\xff\xff" + std::string(300, '\xa5');
  ASSERT_EQ(::write(fds[1], garbage.data(), garbage.size()), static_cast<ssize_t>(garbage.size()));
  auto server = TlsConnection::accept(**context, fds[0]);
  ASSERT_TRUE(server);
  EXPECT_EQ((*server)->handshake(), TlsConnection::Step::kFailed);
  EXPECT_FALSE((*server)->failure().empty());
  ::close(fds[0]);
  ::close(fds[1]);
}

TEST_F(ServerTls, TheFilesErrorsNameTheFile) {
  ServerFiles f = files();
  f.key = other("device.key");
  auto mismatch = ServerContext::load(f, {});
  ASSERT_FALSE(mismatch);
  EXPECT_NE(mismatch.error().message.find("does not belong"), std::string::npos) << mismatch.error().message;
  f = files();
  f.cert = pki("missing.pem");
  auto missing = ServerContext::load(f, {});
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("missing.pem"), std::string::npos) << missing.error().message;
  f = files();
  f.crl = pki("ca.pem");  // a certificate, not a CRL
  auto not_crl = ServerContext::load(f, {});
  ASSERT_FALSE(not_crl);
  EXPECT_NE(not_crl.error().message.find("not a PEM CRL"), std::string::npos) << not_crl.error().message;
}

TEST(RefusalLog, AnAddressIsToldOnceThenAfterABackOffThatDoubles) {
  RefusalLog log;
  constexpr std::int64_t s = 1'000'000'000;
  EXPECT_NE(log.refused("10.0.0.1", "certificate revoked", 0), "");
  EXPECT_EQ(log.refused("10.0.0.1", "certificate revoked", 1 * s), "");
  EXPECT_EQ(log.refused("10.0.0.1", "certificate revoked", 59 * s), "");
  EXPECT_NE(log.refused("10.0.0.2", "no certificate", 59 * s), "") << "another address is told at once";
  const std::string second = log.refused("10.0.0.1", "certificate revoked", 61 * s);
  EXPECT_NE(second.find("and 2 refusals from it not logged since"), std::string::npos) << second;
  EXPECT_EQ(log.refused("10.0.0.1", "certificate revoked", (61 + 119) * s), "") << "the back-off doubled to 120 s";
  EXPECT_NE(log.refused("10.0.0.1", "certificate revoked", (61 + 121) * s), "");
}

TEST(RefusalLog, ItsRecordsAreBounded) {
  RefusalLog log;
  for (std::size_t i = 0; i < 3 * RefusalLog::kMaxAddresses; ++i) (void)log.refused("10.1." + std::to_string(i), "garbage", 0);
  EXPECT_EQ(log.addresses(), RefusalLog::kMaxAddresses);
}

}  // namespace
}  // namespace epa::tls
