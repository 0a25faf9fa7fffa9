// HTTPS on the status page's server, in-process on 127.0.0.1 (port 0), with certificates made in a
// temp folder by the library of `epa certs`: the API and the page over TLS only; a client
// certificate's role deciding the commands (a viewer's refused 403 naming the role, an operator's
// taken without a token and audited by its subject, tuning and commissioning for an engineer
// only); the token for a client without one; and hostile clients held off: garbage before the
// ClientHello, a handshake that never ends, a role outside the table, a renegotiation, the
// per-address cap, a client that reads its answer slowly (partial TLS writes) or resets mid-answer.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <openssl/err.h>
#include <openssl/ssl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "../support/temp_path.hpp"
#include "../support/wait_until.hpp"
#include "control/paper_controller.hpp"
#include "tls/certificate_authority.hpp"
#include "tls/openssl_handles.hpp"
#include "web/commission_port.hpp"
#include "web/recent_audit.hpp"
#include "web/web_server.hpp"

// A named namespace, not an anonymous one: the executable's files share unity batches.
namespace https_test {

using namespace std::chrono_literals;
using nlohmann::json;
using epa::runtime::Command;
using epa::runtime::CommandKind;
namespace ca = epa::tls::ca;

constexpr const char* kToken = "s3cret-token";

class Collecting : public epa::core::AuditSink {
 public:
  void record(const std::vector<epa::core::AuditEntry>& change) override { entries.insert(entries.end(), change.begin(), change.end()); }
  epa::core::ChangeCounters counters() const override { return {}; }
  std::vector<epa::core::AuditEntry> entries;
};

// A commissioning service that records who started it.
class FakeCommission final : public epa::web::CommissionPort {
 public:
  epa::points::CommissionStartResult start(const std::string&, const std::string& source) override {
    running = true, last_source = source;
    return {};
  }
  bool abort(const std::string&) override { return std::exchange(running, false); }
  epa::points::CommissionView view() const override { return {}; }
  std::string status_json() const override { return R"({"running":false})"; }
  std::optional<std::string> result_json() const override { return std::nullopt; }
  std::optional<std::string> report_html() const override { return std::nullopt; }
  bool running = false;
  std::string last_source;
};

// The plant's CA folder, made once per process: the appliance's certificate (localhost,
// 127.0.0.1, ::1) and one client per role of the table, plus a role the table does not have.
const std::filesystem::path& pki() {
  static const epa::test::TempDir dir("https-pki");
  static const std::string made = [] {
    if (auto files = ca::init(dir.path.string(), {}); !files) return files.error().message;
    for (const char* role : {"viewer", "operator", "engineer", "intruder"})
      if (auto issued = ca::client(dir.path.string(), role, role, {}); !issued) return issued.error().message;
    return std::string();
  }();
  EXPECT_EQ(made, "");
  return dir.path;
}
std::string pki_file(const std::string& name) { return (pki() / name).string(); }

int connect_to(int port, int receive_buffer_bytes = 0) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (receive_buffer_bytes > 0)  // before connect: the window the client offers
    ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &receive_buffer_bytes, sizeof receive_buffer_bytes);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// How long until the server closed `fd` (read end or reset), reading and dropping what it sends;
// `limit` when it had not by then.
std::chrono::milliseconds time_to_close(int fd, std::chrono::milliseconds limit) {
  const auto t0 = std::chrono::steady_clock::now();
  for (;;) {
    const auto spent = std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - t0);
    if (spent >= limit) return limit;
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>((limit - spent).count())) <= 0) continue;
    char sink[4096];
    const ssize_t n = ::recv(fd, sink, sizeof sink, 0);
    if (n <= 0) return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - t0);
  }
}

// A TLS client written with OpenSSL directly, for what httplib's client does not do: a small
// receive window, reading at its own pace, a renegotiation, a reset mid-answer.
class RawTlsClient {
 public:
  // `resume`: a session of an earlier connection, offered to the server again.
  RawTlsClient(int port, int receive_buffer_bytes = 0, int max_version = 0, const std::string& cert = "", SSL_SESSION* resume = nullptr)
      : fd_(connect_to(port, receive_buffer_bytes)) {
    ctx_.reset(SSL_CTX_new(TLS_client_method()));
    if (max_version) SSL_CTX_set_max_proto_version(ctx_.get(), max_version);
    SSL_CTX_load_verify_locations(ctx_.get(), pki_file("ca.pem").c_str(), nullptr);
    SSL_CTX_set_verify(ctx_.get(), SSL_VERIFY_PEER, nullptr);
    if (!cert.empty()) {
      SSL_CTX_use_certificate_file(ctx_.get(), pki_file(cert + ".pem").c_str(), SSL_FILETYPE_PEM);
      SSL_CTX_use_PrivateKey_file(ctx_.get(), pki_file(cert + ".key").c_str(), SSL_FILETYPE_PEM);
    }
    ssl_.reset(SSL_new(ctx_.get()));
    SSL_set_fd(ssl_.get(), fd_);
    if (resume) SSL_set_session(ssl_.get(), resume);
    connected_ = fd_ >= 0 && SSL_connect(ssl_.get()) == 1;
  }
  ~RawTlsClient() {
    ssl_.reset();
    if (fd_ >= 0) ::close(fd_);
  }
  bool connected() const { return connected_; }
  SSL* ssl() const { return ssl_.get(); }
  int fd() const { return fd_; }
  bool send(const std::string& text) {
    std::size_t n = 0;
    return SSL_write_ex(ssl_.get(), text.data(), text.size(), &n) == 1 && n == text.size();
  }
  // Everything until the server closes (or fails), read `chunk_bytes` at a time.
  std::string read_all(std::size_t chunk_bytes = 16384) {
    std::string all;
    std::vector<char> chunk(chunk_bytes);
    std::size_t n = 0;
    while (SSL_read_ex(ssl_.get(), chunk.data(), chunk.size(), &n) == 1) all.append(chunk.data(), n);
    return all;
  }
  // Closes with a TCP reset, unread bytes and all: the server's next write fails.
  void reset() {
    const linger now{1, 0};
    ::setsockopt(fd_, SOL_SOCKET, SO_LINGER, &now, sizeof now);
    ::close(fd_);
    fd_ = -1;
  }

 private:
  int fd_ = -1;
  epa::tls::SslContextHandle ctx_;
  epa::tls::SslHandle ssl_;
  bool connected_ = false;
};

class HttpsTest : public ::testing::Test {
 protected:
  void start(const std::string& token = "") {
    snap_.mode = epa::runtime::Mode::kRun;
    snap_.setpoint_mm = 120.0;
    snap_.position_mm = 118.5;
    snap_.Ts = 0.005;
    snap_.tuning.F = {1.0, -1.778, 0.7828};
    snap_.tuning.nF = 2;
    snap_.tuning.b_l = -1.722;
    snap_.tuning.b_r = 1.232;
    snap_.tuning.lc_mm = 5.0;
    channels_.snapshot.publish(snap_);
    epa::web::WebConfig config;
    config.address = "127.0.0.1";
    config.port = 0;
    config.token = token;
    config.static_dir = std::string(EPA_SOURCE_DIR) + "/web";
    if (!chart_js_.empty()) config.chart_js = chart_js_;
    config.request_deadline_ms = request_deadline_ms_;
    config.max_connections_per_address = max_connections_per_address_;
    config.tls = true;
    config.client_certificates = client_certificates_;
    config.tls_files = {pki_file("ca.pem"), pki_file("device.pem"), pki_file("device.key"), pki_file("crl.pem")};
    config.roles = {{"viewer", epa::points::Rights::kRead}, {"operator", epa::points::Rights::kOperate}, {"engineer", epa::points::Rights::kTune}};
    config.log = [this](const std::string& line) {
      std::lock_guard lock(log_mutex_);
      log_.push_back(line);
    };
    auto limits = epa::points::WriteLimits::from_config(limits_, "test.toml");
    ASSERT_TRUE(limits.has_value()) << limits.error().message;
    gate_ = std::make_unique<epa::points::WriteGate>(std::move(*limits), limits_,
                                                     epa::control::paper_controller_config(epa::control::ControllerKind::kPpFfidz),
                                                     channels_, &audit_);
    auto server = epa::web::WebServer::start(config, channels_, gate_.get(), &audit_, {}, {}, commission_);
    ASSERT_TRUE(server.has_value()) << server.error().message;
    server_ = std::move(*server);
  }
  int port() const { return server_->port(); }

  // An HTTPS client that checks the appliance's certificate against the CA; with `name`, it
  // presents that client's certificate.
  std::unique_ptr<httplib::SSLClient> client(const std::string& name = "") {
    auto c = name.empty() ? std::make_unique<httplib::SSLClient>("127.0.0.1", port())
                          : std::make_unique<httplib::SSLClient>("127.0.0.1", port(), pki_file(name + ".pem"), pki_file(name + ".key"));
    c->set_ca_cert_path(pki_file("ca.pem"));
    c->enable_server_certificate_verification(true);
    c->set_connection_timeout(5, 0);
    c->set_read_timeout(5, 0);
    return c;
  }
  static httplib::Result post(httplib::SSLClient& c, const std::string& path, const std::string& body, const std::string& token = "") {
    httplib::Headers headers;
    if (!token.empty()) headers.emplace("Authorization", std::string("Bearer ") + token);
    return c.Post(path.c_str(), headers, body, "application/json");
  }
  static std::string error_of(const httplib::Result& r) {
    const auto j = json::parse(r->body, nullptr, false);
    return j.is_object() && j.contains("error") ? j["error"].get<std::string>() : r->body;
  }
  std::vector<Command> queued() {
    std::vector<Command> out;
    Command c;
    while (channels_.commands.try_pop(c)) out.push_back(c);
    return out;
  }
  std::size_t log_lines_with(const std::string& text) {
    std::lock_guard lock(log_mutex_);
    return static_cast<std::size_t>(std::count_if(log_.begin(), log_.end(), [&](const std::string& l) { return l.find(text) != std::string::npos; }));
  }
  std::string log_text() {
    std::lock_guard lock(log_mutex_);
    std::string all;
    for (const auto& l : log_) all += l + "\n";
    return all;
  }
  void expect_status_answered() {
    auto res = client()->Get("/api/status");
    ASSERT_TRUE(res) << httplib::to_string(res.error());
    EXPECT_EQ(res->status, 200);
    EXPECT_EQ(json::parse(res->body)["mode"], "run");
  }

  int request_deadline_ms_ = 2000;
  int max_connections_per_address_ = 32;
  std::string chart_js_;  // "": Debian's
  epa::web::ClientCertificates client_certificates_ = epa::web::ClientCertificates::kOptional;
  epa::runtime::LoopChannels channels_{16};
  epa::runtime::RuntimeConfig limits_;
  epa::runtime::Snapshot snap_;
  Collecting sink_;
  epa::web::RecentAudit audit_{&sink_};
  std::unique_ptr<epa::points::WriteGate> gate_;
  epa::web::CommissionPort* commission_ = nullptr;
  std::unique_ptr<epa::web::WebServer> server_;
  std::mutex log_mutex_;
  std::vector<std::string> log_;
};

// The JSON API and the page over TLS, checked against the CA; a plain HTTP request on the port gets
// no answer (so a token never crosses the network in clear), and is logged as a refusal.
TEST_F(HttpsTest, TheApiAndThePageAreServedOverTlsOnly) {
  start(kToken);
  expect_status_answered();
  auto page = client()->Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("app.js"), std::string::npos);
  EXPECT_EQ(client("viewer")->Get("/api/trend")->status, 200);  // a certificate is not needed to read, nor in the way

  httplib::Client plain("127.0.0.1", port());
  plain.set_read_timeout(5, 0);
  httplib::Headers with_token{{"Authorization", std::string("Bearer ") + kToken}};
  auto in_clear = plain.Post("/api/setpoint", with_token, R"({"setpoint_mm": 150})", "application/json");
  EXPECT_FALSE(in_clear) << "plain HTTP answered " << in_clear->status;
  EXPECT_TRUE(queued().empty());
  EXPECT_TRUE(epa::test::wait_until([&] { return log_lines_with("127.0.0.1 refused in the TLS handshake") == 1; })) << log_text();
}

TEST_F(HttpsTest, TheStatusSaysWhoTheCertificateIsAndWhetherItsRoleCommands) {
  start();  // no token: only a certificate's role can enable commands
  auto status_of = [&](const std::string& name) { return json::parse(client(name)->Get("/api/status")->body); };
  const json op = status_of("operator");
  EXPECT_TRUE(op["commands_enabled"].get<bool>()) << "the page's command panel shows for a role that may command";
  EXPECT_EQ(op["client_certificate"]["subject"], "/CN=operator");
  EXPECT_EQ(op["client_certificate"]["role"], "operator");
  EXPECT_EQ(op["client_certificate"]["rights"], "operate");
  const json viewer = status_of("viewer");
  EXPECT_FALSE(viewer["commands_enabled"].get<bool>());
  EXPECT_EQ(viewer["client_certificate"]["rights"], "read");
  const json none = status_of("");
  EXPECT_FALSE(none["commands_enabled"].get<bool>());
  EXPECT_TRUE(none["client_certificate"].is_null());
}

TEST_F(HttpsTest, AViewersCommandIsRefused403NamingItsRoleEvenWithTheToken) {
  start(kToken);
  auto viewer = client("viewer");
  for (const std::string& token : {std::string(), std::string(kToken)}) {
    auto res = post(*viewer, "/api/setpoint", R"({"setpoint_mm": 150})", token);
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 403);
    EXPECT_EQ(error_of(res), "certificate /CN=viewer: role \"viewer\" has read rights only");
  }
  EXPECT_TRUE(queued().empty());
  EXPECT_TRUE(audit_.entries().empty());
  EXPECT_EQ(viewer->Get("/api/status")->status, 200);
}

TEST_F(HttpsTest, AnOperatorsCertificateCommandsWithoutATokenAuditedByItsSubject) {
  start();  // no token: commands come by certificate alone
  auto op = client("operator");
  auto res = post(*op, "/api/setpoint", R"({"setpoint_mm": 150})");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200) << res->body;
  const auto q = queued();
  ASSERT_EQ(q.size(), 1u);
  EXPECT_EQ(q[0].kind, CommandKind::kSetpoint);
  EXPECT_DOUBLE_EQ(q[0].value, 150.0);
  const auto entries = audit_.entries();
  ASSERT_EQ(entries.size(), 1u);
  EXPECT_EQ(entries[0].source, "web 127.0.0.1 /CN=operator (operator)");

  // Tuning is the engineer's: the operator's refusal names the role, as the gate gives it.
  auto tuning = post(*op, "/api/points", R"({"b_r": 1.3})");
  ASSERT_TRUE(tuning);
  EXPECT_EQ(tuning->status, 403);
  EXPECT_NE(error_of(tuning).find("role \"operator\" has no tuning rights"), std::string::npos) << tuning->body;
  auto engineer = client("engineer");
  auto tuned = post(*engineer, "/api/points", R"({"b_r": 1.3})");
  ASSERT_TRUE(tuned);
  EXPECT_EQ(tuned->status, 200) << tuned->body;
  EXPECT_EQ(audit_.entries().back().source, "web 127.0.0.1 /CN=engineer (engineer)");
}

TEST_F(HttpsTest, CommissioningNeedsACertificateWithTuningRights) {
  FakeCommission fake;
  commission_ = &fake;
  start();
  auto by_operator = post(*client("operator"), "/api/commission", "{}");
  ASSERT_TRUE(by_operator);
  EXPECT_EQ(by_operator->status, 403);
  EXPECT_EQ(error_of(by_operator), "certificate /CN=operator: role \"operator\" has no tuning rights");
  EXPECT_FALSE(fake.running);
  auto by_engineer = post(*client("engineer"), "/api/commission", "{}");
  ASSERT_TRUE(by_engineer);
  EXPECT_EQ(by_engineer->status, 202) << by_engineer->body;
  EXPECT_EQ(fake.last_source, "web 127.0.0.1 /CN=engineer (engineer)");
}

TEST_F(HttpsTest, WithoutACertificateTheTokenRuleHolds) {
  start(kToken);
  auto anonymous = client();
  auto missing = post(*anonymous, "/api/setpoint", R"({"setpoint_mm": 150})");
  ASSERT_TRUE(missing);
  EXPECT_EQ(missing->status, 401);
  auto right = post(*anonymous, "/api/setpoint", R"({"setpoint_mm": 150})", kToken);
  ASSERT_TRUE(right);
  EXPECT_EQ(right->status, 200) << right->body;
  ASSERT_EQ(audit_.entries().size(), 1u);
  EXPECT_EQ(audit_.entries()[0].source, "web 127.0.0.1");
  EXPECT_TRUE(json::parse(anonymous->Get("/api/status")->body)["commands_enabled"].get<bool>());
}

TEST_F(HttpsTest, WithoutATokenAClientWithoutACertificateIsTold403HowToCommand) {
  start();
  auto res = post(*client(), "/api/setpoint", R"({"setpoint_mm": 150})");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 403);
  EXPECT_EQ(error_of(res), "commands need a client certificate whose role may write, or a [web] token");
}

// client_certificates = "off": none is asked for, so one gives no rights; the token rule alone.
TEST_F(HttpsTest, WithClientCertificatesOffACertificateGivesNoRights) {
  client_certificates_ = epa::web::ClientCertificates::kOff;
  start(kToken);
  auto op = client("operator");
  auto without_token = post(*op, "/api/setpoint", R"({"setpoint_mm": 150})");
  ASSERT_TRUE(without_token) << httplib::to_string(without_token.error());
  EXPECT_EQ(without_token->status, 401);
  auto with_token = post(*op, "/api/setpoint", R"({"setpoint_mm": 150})", kToken);
  ASSERT_TRUE(with_token);
  EXPECT_EQ(with_token->status, 200);
  ASSERT_EQ(audit_.entries().size(), 1u);
  EXPECT_EQ(audit_.entries()[0].source, "web 127.0.0.1");
}

// A certificate signed by the CA whose role the table does not have gets no session at all.
TEST_F(HttpsTest, ACertificateWhoseRoleIsNotInTheTableIsRefusedInTheHandshake) {
  start(kToken);
  auto res = client("intruder")->Get("/api/status");
  EXPECT_FALSE(res);
  EXPECT_TRUE(epa::test::wait_until([&] { return log_lines_with("its role \"intruder\" is not in the role table") == 1; })) << log_text();
  expect_status_answered();
}

// Bytes that are no ClientHello end the connection at once (well before the handshake deadline),
// and the refusals of one address are logged once, the rest held back.
TEST_F(HttpsTest, GarbageBeforeTheClientHelloClosesTheConnectionAndTheServerServesOn) {
  request_deadline_ms_ = 30000;
  start();
  const std::vector<std::string> garbage = {
      "GARBAGE\r\n\r\n" + std::string(3000, 'x'),
      std::string("\x16\x03\x01\xff\xff", 5) + std::string(64, '\0'),           // a handshake record longer than TLS allows
      [] {  // empty handshake records: OpenSSL passes over a few, then calls it an attack
        std::string empty;
        for (int i = 0; i < 40; ++i) empty += std::string("\x16\x03\x03\x00\x00", 5);
        return empty;
      }(),
      std::string("\x16\x03\x01\x00\x08\x01\x00\x00\x04\xff\xff\xff\xff", 13),  // a ClientHello that is all wrong
      std::string("\x80\x2e\x01\x00\x02\x00\x15\x00\x00\x00\x10", 11) + std::string(37, '\x01'),  // SSLv2
      std::string(1, '\0') + std::string(5000, '\xff'),
  };
  for (const std::string& bytes : garbage) {
    const int fd = connect_to(port());
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL), static_cast<ssize_t>(bytes.size()));
    EXPECT_LT(time_to_close(fd, 10s), 10s) << "not closed after garbage of " << bytes.size() << " bytes";
    ::close(fd);
  }
  expect_status_answered();
  EXPECT_EQ(log_lines_with("refused in the TLS handshake"), 1u) << log_text();
}

TEST_F(HttpsTest, AHandshakeNotCompleteWithinTheDeadlineIsClosed) {
  request_deadline_ms_ = 300;
  start();
  const int silent = connect_to(port());
  const int slow = connect_to(port());
  ASSERT_GE(silent, 0);
  ASSERT_GE(slow, 0);
  const std::string half_hello("\x16\x03\x01\x00\x80\x01\x00\x00\x7c\x03\x03", 11);  // a record that promises 128 bytes, then silence
  ASSERT_EQ(::send(slow, half_hello.data(), half_hello.size(), MSG_NOSIGNAL), static_cast<ssize_t>(half_hello.size()));
  const auto t0 = std::chrono::steady_clock::now();
  for (const int fd : {silent, slow}) {
    EXPECT_LT(time_to_close(fd, 10s), 10s);
    EXPECT_GE(std::chrono::steady_clock::now() - t0, 250ms);  // both were given their deadline
    ::close(fd);
  }
  EXPECT_TRUE(epa::test::wait_until([&] { return log_lines_with("no handshake within the request deadline") == 1; })) << log_text();
  expect_status_answered();
}

// A TLS 1.2 client that asks to renegotiate is refused; the server serves on.
TEST_F(HttpsTest, ARenegotiationIsRefused) {
  start();
  RawTlsClient c(port(), 0, TLS1_2_VERSION);
  ASSERT_TRUE(c.connected());
  ASSERT_EQ(SSL_renegotiate(c.ssl()), 1);
  EXPECT_NE(SSL_do_handshake(c.ssl()), 1);
  ERR_clear_error();
  expect_status_answered();
}

// A TLS 1.2 client that reconnects offering its earlier session, as `openssl s_client -reconnect`
// does, gets a whole new handshake (its certificate checked again), not a failure (with a session
// ticket and no session id context, OpenSSL failed it with "internal error").
TEST_F(HttpsTest, ATls12ClientThatOffersToResumeGetsAWholeHandshake) {
  start();
  using SessionHandle = std::unique_ptr<SSL_SESSION, epa::tls::OpenSslDeleter<SSL_SESSION_free>>;
  SessionHandle earlier;
  {
    RawTlsClient first(port(), 0, TLS1_2_VERSION, "operator");
    ASSERT_TRUE(first.connected());
    earlier.reset(SSL_get1_session(first.ssl()));  // as a client keeps it to reconnect (openssl s_client -reconnect)
    SSL_shutdown(first.ssl());
  }
  ASSERT_TRUE(earlier);  // the appliance gives no ticket or session id to resume by; what the client kept is offered all the same
  RawTlsClient again(port(), 0, TLS1_2_VERSION, "operator", earlier.get());
  ASSERT_TRUE(again.connected()) << "the reconnect failed its handshake: " << log_text();
  EXPECT_EQ(SSL_session_reused(again.ssl()), 0);
  ASSERT_TRUE(again.send("GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n"));
  EXPECT_NE(again.read_all().find("HTTP/1.1 200 OK"), std::string::npos);
  EXPECT_EQ(log_lines_with("refused"), 0u) << log_text();
}

// Past the per-address cap a connection is closed at once, without a handshake (there is no
// session to say 503 in); the connections held are not disturbed.
TEST_F(HttpsTest, AnAddressPastItsConnectionCapIsClosedAtOnce) {
  request_deadline_ms_ = 30000;
  max_connections_per_address_ = 4;
  start();
  std::vector<int> held;
  for (int i = 0; i < 4; ++i) held.push_back(connect_to(port()));
  ASSERT_TRUE(epa::test::wait_until([&] { return epa::test::accept_queue_length(port()) == 0; }));
  const int over = connect_to(port());
  ASSERT_GE(over, 0);
  EXPECT_LT(time_to_close(over, 5s), 5s);
  ::close(over);
  EXPECT_TRUE(epa::test::wait_until([&] { return log_lines_with("too many from one address") == 1; })) << log_text();
  for (int fd : held) ::close(fd);
  // Served again once the front end has seen the held connections go.
  EXPECT_TRUE(epa::test::wait_until([&] { return static_cast<bool>(client()->Get("/api/status")); }, 5000ms, 20ms));
}

// An answer larger than the server socket's send buffer can grow to (4 MiB on Linux by default):
// Chart.js's file, served as it is read, swapped for 12 MiB of text.
class HttpsLargeAnswerTest : public HttpsTest {
 protected:
  void SetUp() override {
    for (std::size_t i = 0; big_.size() < 12 * 1024 * 1024; ++i) big_ += "// line " + std::to_string(i) + " of a large script\n";
    std::ofstream(dir_.path / "chart.js") << big_;
    chart_js_ = (dir_.path / "chart.js").string();
  }
  const std::string request_ = "GET /vendor/chart.js HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n";
  epa::test::TempDir dir_{"https-chart-js"};
  std::string big_;
};

// 12 MiB through a 4 KiB receive window: the server's TLS writes take what the socket takes and
// go on as the client reads, and every byte arrives in order.
TEST_F(HttpsLargeAnswerTest, ALargeAnswerReadThroughASmallWindowArrivesWhole) {
  start();
  RawTlsClient c(port(), 4096);
  ASSERT_TRUE(c.connected());
  ASSERT_TRUE(c.send(request_));
  // The stimulus: a client that has not begun to read, so the server's socket fills and its
  // writes stop part-way; then it reads on.
  std::this_thread::sleep_for(200ms);
  const std::string answer = c.read_all(4096);
  const auto body_at = answer.find("\r\n\r\n");
  ASSERT_NE(body_at, std::string::npos) << answer.substr(0, 200);
  EXPECT_EQ(answer.substr(0, answer.find("\r\n")), "HTTP/1.1 200 OK");
  EXPECT_EQ(answer.size() - body_at - 4, big_.size());
  EXPECT_TRUE(answer.compare(body_at + 4, std::string::npos, big_) == 0) << "the body differs from app.js";
}

// Clients that reset while their answers are written (OpenSSL then writes to a closed socket,
// which raises SIGPIPE) are closed, and the process and the server go on.
TEST_F(HttpsLargeAnswerTest, ClientsThatResetMidAnswerAreClosedAndTheServerServesOn) {
  start();
  for (int round = 0; round < 3; ++round) {
    std::vector<std::unique_ptr<RawTlsClient>> clients;
    for (int i = 0; i < 8; ++i) {
      clients.push_back(std::make_unique<RawTlsClient>(port(), 4096));
      ASSERT_TRUE(clients.back()->connected());
      ASSERT_TRUE(clients.back()->send(request_));
    }
    for (const auto& c : clients) {  // until each holds bytes of its answer it has not read
      int unread = 0;
      EXPECT_TRUE(epa::test::wait_until([&] { return ::ioctl(c->fd(), FIONREAD, &unread) == 0 && unread > 0; }));
    }
    for (const auto& c : clients) c->reset();
  }
  expect_status_answered();
}

}  // namespace https_test
