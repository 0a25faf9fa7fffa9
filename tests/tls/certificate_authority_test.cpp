// The certificate authority of `epa certs`, judged by OpenSSL itself: the files are read back
// with OpenSSL's PEM readers and checked with X509_verify_cert (purposes sslserver and sslclient,
// the CRL check), X509_check_host and X509_check_ip_asc, and the role extension's bytes are read
// as DER, not through our reader alone.
#include "tls/certificate_authority.hpp"

#include <gtest/gtest.h>
#include <openssl/pem.h>
#include <openssl/x509v3.h>
#include <sys/stat.h>
#include <unistd.h>

#include <climits>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "../support/temp_path.hpp"
#include "tls/certificate_role.hpp"
#include "tls/openssl_handles.hpp"

// A named namespace, not an anonymous one: the executable's files share unity batches.
namespace certificate_authority_test {

namespace ca = epa::tls::ca;
using epa::test::TempDir;
using epa::tls::PrivateKeyHandle;
using epa::tls::X509CrlHandle;
using epa::tls::X509Handle;
using ObjectHandle = std::unique_ptr<ASN1_OBJECT, epa::tls::OpenSslDeleter<ASN1_OBJECT_free>>;

std::string file_text(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

X509Handle read_cert(const std::filesystem::path& p) {
  FILE* f = std::fopen(p.c_str(), "r");
  if (!f) return nullptr;
  X509Handle cert(PEM_read_X509(f, nullptr, nullptr, nullptr));
  std::fclose(f);
  return cert;
}

PrivateKeyHandle read_key(const std::filesystem::path& p) {
  FILE* f = std::fopen(p.c_str(), "r");
  if (!f) return nullptr;
  PrivateKeyHandle key(PEM_read_PrivateKey(f, nullptr, nullptr, nullptr));
  std::fclose(f);
  return key;
}

X509CrlHandle read_crl(const std::filesystem::path& p) {
  FILE* f = std::fopen(p.c_str(), "r");
  if (!f) return nullptr;
  X509CrlHandle crl(PEM_read_X509_CRL(f, nullptr, nullptr, nullptr));
  std::fclose(f);
  return crl;
}

// X509_verify_cert of `leaf` against `ca` alone for `purpose`, with the leaf's CRL checked when
// `crl` is given: X509_V_OK or OpenSSL's error.
int verify(X509* ca_cert, X509* leaf, int purpose, X509_CRL* crl = nullptr) {
  epa::tls::X509StoreHandle store(X509_STORE_new());
  X509_STORE_add_cert(store.get(), ca_cert);
  if (crl) {
    X509_STORE_add_crl(store.get(), crl);
    X509_STORE_set_flags(store.get(), X509_V_FLAG_CRL_CHECK);
  }
  epa::tls::X509StoreContextHandle ctx(X509_STORE_CTX_new());
  X509_STORE_CTX_init(ctx.get(), store.get(), leaf, nullptr);
  X509_STORE_CTX_set_purpose(ctx.get(), purpose);
  const int ok = X509_verify_cert(ctx.get());
  const int error = X509_STORE_CTX_get_error(ctx.get());
  return ok == 1 ? X509_V_OK : error;
}

std::string common_name(X509* cert) {
  char text[256] = {};
  X509_NAME_get_text_by_NID(X509_get_subject_name(cert), NID_commonName, text, sizeof text);
  return text;
}

int validity_days(X509* cert, int* seconds) {
  int days = 0;
  ASN1_TIME_diff(&days, seconds, X509_get0_notBefore(cert), X509_get0_notAfter(cert));
  return days;
}

bool is_critical(X509* cert, int nid) {
  const int at = X509_get_ext_by_NID(cert, nid, -1);
  return at >= 0 && X509_EXTENSION_get_critical(X509_get_ext(cert, at)) == 1;
}

int serial_bits(X509* cert) {
  epa::tls::BignumHandle n(ASN1_INTEGER_to_BN(X509_get0_serialNumber(cert), nullptr));
  return BN_num_bits(n.get());
}

mode_t mode_of(const std::filesystem::path& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0 ? st.st_mode & 07777 : 0;
}

std::string host_name() {
  char name[HOST_NAME_MAX + 1] = {};
  gethostname(name, sizeof name - 1);
  return name;
}

class CertificateAuthority : public ::testing::Test {
 protected:
  TempDir tmp{"certs"};
  std::filesystem::path dir = tmp.path / "pki";
  std::string d = dir.string();

  void init(ca::InitOptions o = {}) {
    auto written = ca::init(d, o);
    ASSERT_TRUE(written) << written.error().message;
  }
  void client(const std::string& name, const std::string& role) {
    auto issued = ca::client(d, name, role, {});
    ASSERT_TRUE(issued) << issued.error().message;
  }
};

TEST_F(CertificateAuthority, InitMakesACaAndADeviceCertificateThatVerifiesForServers) {
  ca::InitOptions o;
  o.common_name = "plc-7";
  auto written = ca::init(d, o);
  ASSERT_TRUE(written) << written.error().message;
  ASSERT_EQ(written->size(), 5u);
  for (const char* f : {"ca.pem", "ca.key", "device.pem", "device.key", "crl.pem"}) EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;

  const X509Handle ca_cert = read_cert(dir / "ca.pem"), device = read_cert(dir / "device.pem");
  ASSERT_TRUE(ca_cert && device);
  EXPECT_EQ(X509_check_ca(ca_cert.get()), 1);
  EXPECT_TRUE(is_critical(ca_cert.get(), NID_basic_constraints));
  EXPECT_EQ(X509_get_key_usage(ca_cert.get()), static_cast<uint32_t>(KU_KEY_CERT_SIGN | KU_CRL_SIGN));
  ASSERT_NE(X509_get0_subject_key_id(ca_cert.get()), nullptr);

  EXPECT_EQ(verify(ca_cert.get(), device.get(), X509_PURPOSE_SSL_SERVER), X509_V_OK);
  EXPECT_NE(verify(ca_cert.get(), device.get(), X509_PURPOSE_SSL_CLIENT), X509_V_OK) << "serverAuth only";
  EXPECT_EQ(common_name(device.get()), "plc-7");
  EXPECT_EQ(X509_check_ca(device.get()), 0);
  EXPECT_EQ(X509_check_host(device.get(), "localhost", 0, 0, nullptr), 1);
  EXPECT_EQ(X509_check_ip_asc(device.get(), "127.0.0.1", 0), 1);
  EXPECT_EQ(X509_check_ip_asc(device.get(), "::1", 0), 1);
  EXPECT_EQ(X509_get_extended_key_usage(device.get()), static_cast<uint32_t>(XKU_SSL_SERVER));
  EXPECT_EQ(X509_get_key_usage(device.get()), static_cast<uint32_t>(KU_DIGITAL_SIGNATURE | KU_KEY_ENCIPHERMENT));
  ASSERT_NE(X509_get0_authority_key_id(device.get()), nullptr);
  EXPECT_EQ(ASN1_OCTET_STRING_cmp(X509_get0_authority_key_id(device.get()), X509_get0_subject_key_id(ca_cert.get())), 0);

  // P-256 keys that belong to their certificates; 128-bit random serials.
  const PrivateKeyHandle ca_key = read_key(dir / "ca.key"), device_key = read_key(dir / "device.key");
  ASSERT_TRUE(ca_key && device_key);
  EXPECT_EQ(X509_check_private_key(ca_cert.get(), ca_key.get()), 1);
  EXPECT_EQ(X509_check_private_key(device.get(), device_key.get()), 1);
  EXPECT_TRUE(EVP_PKEY_is_a(device_key.get(), "EC"));
  EXPECT_EQ(EVP_PKEY_get_bits(device_key.get()), 256);
  EXPECT_GT(serial_bits(ca_cert.get()), 64);
  EXPECT_GT(serial_bits(device.get()), 64);
  EXPECT_LE(serial_bits(device.get()), 128);
  EXPECT_NE(ASN1_INTEGER_cmp(X509_get0_serialNumber(ca_cert.get()), X509_get0_serialNumber(device.get())), 0);

  // The defaults: 3650 and 825 days, from an hour before they were made.
  int seconds = 0;
  EXPECT_EQ(validity_days(ca_cert.get(), &seconds), 3650);
  EXPECT_EQ(seconds, 3600);
  EXPECT_EQ(validity_days(device.get(), &seconds), 825);
  EXPECT_EQ(X509_cmp_current_time(X509_get0_notBefore(device.get())), -1);
}

TEST_F(CertificateAuthority, TheDeviceIsNamedAfterTheHostByDefault) {
  init();
  const X509Handle device = read_cert(dir / "device.pem");
  ASSERT_TRUE(device);
  const std::string host = host_name();
  EXPECT_EQ(common_name(device.get()), host);
  EXPECT_EQ(X509_check_host(device.get(), host.c_str(), 0, 0, nullptr), 1) << host;
  EXPECT_EQ(X509_check_host(device.get(), "localhost", 0, 0, nullptr), 1);
  EXPECT_EQ(X509_check_ip_asc(device.get(), "127.0.0.1", 0), 1);
}

TEST_F(CertificateAuthority, TheNamesAndValiditiesGivenAreTheOnesInTheCertificates) {
  ca::InitOptions o;
  o.dns_names = {"plc-7.plant.example", "plc-7"};
  o.ip_addresses = {"10.0.0.5", "fd00::5"};
  o.device_days = 10;
  o.ca_days = 20;
  init(o);
  const X509Handle ca_cert = read_cert(dir / "ca.pem"), device = read_cert(dir / "device.pem");
  ASSERT_TRUE(ca_cert && device);
  EXPECT_EQ(X509_check_host(device.get(), "plc-7.plant.example", 0, 0, nullptr), 1);
  EXPECT_EQ(X509_check_host(device.get(), "plc-7", 0, 0, nullptr), 1);
  EXPECT_EQ(X509_check_host(device.get(), "localhost", 0, 0, nullptr), 0) << "names given replace the default names";
  EXPECT_EQ(X509_check_ip_asc(device.get(), "10.0.0.5", 0), 1);
  EXPECT_EQ(X509_check_ip_asc(device.get(), "fd00::5", 0), 1);
  EXPECT_EQ(X509_check_ip_asc(device.get(), "127.0.0.1", 0), 0);
  int seconds = 0;
  EXPECT_EQ(validity_days(device.get(), &seconds), 10);
  EXPECT_EQ(validity_days(ca_cert.get(), &seconds), 20);
}

TEST_F(CertificateAuthority, BadNamesAddressesAndValiditiesAreRefusedBeforeAnythingIsWritten) {
  const auto refused = [this](ca::InitOptions o, const std::string& says) {
    auto r = ca::init(d, o);
    ASSERT_FALSE(r) << says;
    EXPECT_NE(r.error().message.find(says), std::string::npos) << r.error().message;
  };
  refused({.dns_names = {"bad_name"}}, "'bad_name' is not a DNS name");
  refused({.dns_names = {"a,DNS:evil.example"}}, "is not a DNS name");
  refused({.ip_addresses = {"1.2.3"}}, "'1.2.3' is not an IPv4 or IPv6 address");
  refused({.ip_addresses = {"::1%lo"}}, "is not an IPv4 or IPv6 address");
  refused({.common_name = "plc\n7"}, "common name");
  refused({.device_days = 0}, "1 to 36500 days");
  refused({.ca_days = 40000}, "1 to 36500 days");
  EXPECT_FALSE(std::filesystem::exists(dir));
}

TEST_F(CertificateAuthority, KeysAreReadableByTheirOwnerOnlyWhateverTheUmask) {
  const mode_t old = ::umask(0);
  init();
  client("hmi-1", "operator");
  ::umask(old);
  EXPECT_EQ(mode_of(dir / "ca.key"), 0600u);
  EXPECT_EQ(mode_of(dir / "device.key"), 0600u);
  EXPECT_EQ(mode_of(dir / "hmi-1.key"), 0600u);
  EXPECT_EQ(mode_of(dir / "ca.pem"), 0644u);
  EXPECT_EQ(mode_of(dir / "hmi-1.pem"), 0644u);
  EXPECT_EQ(mode_of(dir / "crl.pem"), 0644u);
  // Nothing left beside them (no temporary file).
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), {}), 7);
}

TEST_F(CertificateAuthority, ExistingFilesAreKeptUnlessForced) {
  init();
  const std::string ca_before = file_text(dir / "ca.pem"), key_before = file_text(dir / "ca.key");
  auto again = ca::init(d, {});
  ASSERT_FALSE(again);
  EXPECT_NE(again.error().message.find((dir / "ca.pem").string() + " exists"), std::string::npos) << again.error().message;
  EXPECT_NE(again.error().message.find("--force"), std::string::npos) << again.error().message;
  EXPECT_EQ(file_text(dir / "ca.pem"), ca_before);
  EXPECT_EQ(file_text(dir / "ca.key"), key_before);

  // One file in the way names that file, and nothing else is written.
  const std::filesystem::path other = tmp.path / "other";
  std::filesystem::create_directories(other);
  std::ofstream(other / "device.key") << "mine";
  auto blocked = ca::init(other.string(), {});
  ASSERT_FALSE(blocked);
  EXPECT_NE(blocked.error().message.find((other / "device.key").string()), std::string::npos) << blocked.error().message;
  EXPECT_FALSE(std::filesystem::exists(other / "ca.pem"));
  EXPECT_EQ(file_text(other / "device.key"), "mine");

  ASSERT_TRUE(ca::init(d, {.force = true}));
  EXPECT_NE(file_text(dir / "ca.pem"), ca_before);
  EXPECT_NE(file_text(dir / "ca.key"), key_before);
  EXPECT_EQ(mode_of(dir / "ca.key"), 0600u);

  client("hmi-1", "operator");
  const std::string client_before = file_text(dir / "hmi-1.pem");
  auto twice = ca::client(d, "hmi-1", "viewer", {});
  ASSERT_FALSE(twice);
  EXPECT_NE(twice.error().message.find((dir / "hmi-1.pem").string() + " exists"), std::string::npos) << twice.error().message;
  EXPECT_EQ(file_text(dir / "hmi-1.pem"), client_before);
  ASSERT_TRUE(ca::client(d, "hmi-1", "viewer", {.force = true}));
  const X509Handle replaced = read_cert(dir / "hmi-1.pem");
  ASSERT_TRUE(replaced);
  EXPECT_EQ(epa::tls::role_of(replaced.get())->value_or(""), "viewer");
}

TEST_F(CertificateAuthority, AClientCertificateVerifiesForClientsAndCarriesItsRole) {
  init();
  auto issued = ca::client(d, "hmi-1", "operator", {.days = 30});
  ASSERT_TRUE(issued) << issued.error().message;
  EXPECT_EQ(issued->subject, "/CN=hmi-1");
  const X509Handle ca_cert = read_cert(dir / "ca.pem"), cert = read_cert(dir / "hmi-1.pem");
  const PrivateKeyHandle key = read_key(dir / "hmi-1.key");
  ASSERT_TRUE(ca_cert && cert && key);
  EXPECT_EQ(verify(ca_cert.get(), cert.get(), X509_PURPOSE_SSL_CLIENT), X509_V_OK);
  EXPECT_EQ(verify(ca_cert.get(), cert.get(), X509_PURPOSE_SSL_SERVER), X509_V_ERR_INVALID_PURPOSE);
  EXPECT_EQ(X509_check_private_key(cert.get(), key.get()), 1);
  EXPECT_EQ(common_name(cert.get()), "hmi-1");
  EXPECT_EQ(X509_get_extended_key_usage(cert.get()), static_cast<uint32_t>(XKU_SSL_CLIENT));
  EXPECT_EQ(X509_check_ca(cert.get()), 0);
  int seconds = 0;
  EXPECT_EQ(validity_days(cert.get(), &seconds), 30);
  epa::tls::BignumHandle serial(ASN1_INTEGER_to_BN(X509_get0_serialNumber(cert.get()), nullptr));
  char* hex = BN_bn2hex(serial.get());
  EXPECT_EQ(issued->serial_hex, hex);
  OPENSSL_free(hex);

  // The role through our reader, and as the bytes on the wire: a non-critical extension whose
  // value is the DER of one UTF8String (tag 0x0c, length, text).
  auto role = epa::tls::role_of(cert.get());
  ASSERT_TRUE(role) << role.error().message;
  EXPECT_EQ(role->value_or(""), "operator");
  ObjectHandle oid(OBJ_txt2obj(epa::tls::kModbusRoleOid, 1));
  const int at = X509_get_ext_by_OBJ(cert.get(), oid.get(), -1);
  ASSERT_GE(at, 0);
  X509_EXTENSION* ext = X509_get_ext(cert.get(), at);
  EXPECT_EQ(X509_EXTENSION_get_critical(ext), 0);
  const ASN1_OCTET_STRING* value = X509_EXTENSION_get_data(ext);
  const std::string der(reinterpret_cast<const char*>(ASN1_STRING_get0_data(value)), static_cast<std::size_t>(ASN1_STRING_length(value)));
  EXPECT_EQ(der, std::string("\x0c\x08operator"));
}

TEST_F(CertificateAuthority, AClientNameMustBeASafeFileName) {
  init();
  for (const std::string& bad : std::vector<std::string>{"../hmi", ".hidden", "a/b", "", "with space", "hmi;rm", std::string(65, 'a'), "hmi\n1"}) {
    auto r = ca::client(d, bad, "operator", {});
    ASSERT_FALSE(r) << bad;
    EXPECT_NE(r.error().message.find("is not a safe file name: a client's name is 1 to 64 letters, digits"), std::string::npos)
        << r.error().message;
  }
  for (const std::string own : {"ca", "device", "crl"}) {
    auto r = ca::client(d, own, "operator", {.force = true});
    ASSERT_FALSE(r) << own;
    EXPECT_NE(r.error().message.find("names the CA's own files"), std::string::npos) << r.error().message;
  }
  EXPECT_FALSE(std::filesystem::exists(tmp.path / "hmi.pem"));
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), {}), 5) << "nothing was written";
  client("hmi-1_b.2", "operator");
  EXPECT_TRUE(std::filesystem::exists(dir / "hmi-1_b.2.pem"));
}

TEST_F(CertificateAuthority, ARoleMustBeAPrintableName) {
  init();
  for (const std::string& bad : std::vector<std::string>{"", " ", "op\x1b[2J", std::string(65, 'r')}) {
    auto r = ca::client(d, "hmi-1", bad, {});
    ASSERT_FALSE(r) << bad;
    EXPECT_NE(r.error().message.find("the role"), std::string::npos) << r.error().message;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "hmi-1.pem"));
}

TEST_F(CertificateAuthority, TheCaFilesMustBeReadableAndBelongTogether) {
  const auto says = [this](const std::string& what) {
    auto r = ca::client(d, "hmi-1", "operator", {});
    if (r) return std::string("(issued)");
    EXPECT_NE(r.error().message.find(what), std::string::npos) << r.error().message;
    return r.error().message;
  };
  says((dir / "ca.pem").string() + ": cannot open the CA certificate");  // no CA yet
  init();
  const std::filesystem::path other = tmp.path / "other";
  ASSERT_TRUE(ca::init(other.string(), {}));

  std::filesystem::copy_file(other / "ca.key", dir / "ca.key", std::filesystem::copy_options::overwrite_existing);
  says((dir / "ca.key").string() + ": the key does not match the CA certificate " + (dir / "ca.pem").string());

  std::ofstream(dir / "ca.key") << "not a key\n";
  says((dir / "ca.key").string() + ": not a PEM CA key");

  // A key with a passphrase is refused, never prompted for.
  const PrivateKeyHandle key = read_key(other / "ca.key");
  FILE* f = std::fopen((dir / "ca.key").c_str(), "w");
  ASSERT_TRUE(f);
  static char passphrase[] = "secret";
  PEM_write_PrivateKey(f, key.get(), EVP_aes_256_cbc(), nullptr, 0, nullptr, passphrase);
  std::fclose(f);
  says((dir / "ca.key").string() + ": not a PEM CA key without a passphrase");

  std::filesystem::copy_file(other / "ca.key", dir / "ca.key", std::filesystem::copy_options::overwrite_existing);
  std::filesystem::copy_file(other / "device.pem", dir / "ca.pem", std::filesystem::copy_options::overwrite_existing);
  says((dir / "ca.pem").string() + ": not a CA certificate");
  EXPECT_FALSE(std::filesystem::exists(dir / "hmi-1.pem"));
}

TEST_F(CertificateAuthority, InitWritesAnEmptyListThatPassesEveryClient) {
  init();
  client("hmi-1", "operator");
  const X509Handle ca_cert = read_cert(dir / "ca.pem"), cert = read_cert(dir / "hmi-1.pem");
  const X509CrlHandle crl = read_crl(dir / "crl.pem");
  ASSERT_TRUE(ca_cert && cert && crl);
  EXPECT_EQ(X509_CRL_verify(crl.get(), X509_get0_pubkey(ca_cert.get())), 1);
  EXPECT_EQ(X509_NAME_cmp(X509_CRL_get_issuer(crl.get()), X509_get_subject_name(ca_cert.get())), 0);
  EXPECT_EQ(sk_X509_REVOKED_num(X509_CRL_get_REVOKED(crl.get())), -1) << "no entries";
  int days = 0, seconds = 0;
  ASSERT_TRUE(ASN1_TIME_diff(&days, &seconds, X509_CRL_get0_lastUpdate(crl.get()), X509_CRL_get0_nextUpdate(crl.get())));
  EXPECT_EQ(days, 30);
  EXPECT_EQ(verify(ca_cert.get(), cert.get(), X509_PURPOSE_SSL_CLIENT, crl.get()), X509_V_OK);
}

TEST_F(CertificateAuthority, ARevokedClientFailsTheCrlCheckAndAnotherPasses) {
  init();
  client("hmi-1", "operator");
  client("hmi-2", "operator");
  client("scada", "engineer");
  auto revoked = ca::revoke(d, (dir / "hmi-1.pem").string(), {});
  ASSERT_TRUE(revoked) << revoked.error().message;
  EXPECT_EQ(revoked->subject, "/CN=hmi-1");
  EXPECT_FALSE(revoked->already_revoked);
  EXPECT_EQ(revoked->crl.revoked_count, 1u);

  const X509Handle ca_cert = read_cert(dir / "ca.pem"), one = read_cert(dir / "hmi-1.pem"), two = read_cert(dir / "hmi-2.pem"),
                   three = read_cert(dir / "scada.pem");
  X509CrlHandle crl = read_crl(dir / "crl.pem");
  ASSERT_TRUE(ca_cert && one && two && three && crl);
  X509_REVOKED* entry = nullptr;
  EXPECT_EQ(X509_CRL_get0_by_serial(crl.get(), &entry, X509_get0_serialNumber(one.get())), 1);
  EXPECT_EQ(X509_CRL_get0_by_serial(crl.get(), &entry, X509_get0_serialNumber(two.get())), 0);
  EXPECT_EQ(verify(ca_cert.get(), one.get(), X509_PURPOSE_SSL_CLIENT, crl.get()), X509_V_ERR_CERT_REVOKED);
  EXPECT_EQ(verify(ca_cert.get(), two.get(), X509_PURPOSE_SSL_CLIENT, crl.get()), X509_V_OK);
  EXPECT_EQ(verify(ca_cert.get(), one.get(), X509_PURPOSE_SSL_CLIENT), X509_V_OK) << "without the CRL, nothing tells";

  // A second revocation keeps the first; revoking one again changes nothing but the dates.
  ASSERT_TRUE(ca::revoke(d, (dir / "scada.pem").string(), {}));
  auto again = ca::revoke(d, (dir / "hmi-1.pem").string(), {});
  ASSERT_TRUE(again) << again.error().message;
  EXPECT_TRUE(again->already_revoked);
  EXPECT_EQ(again->crl.revoked_count, 2u);
  crl = read_crl(dir / "crl.pem");
  ASSERT_TRUE(crl);
  EXPECT_EQ(sk_X509_REVOKED_num(X509_CRL_get_REVOKED(crl.get())), 2);
  EXPECT_EQ(verify(ca_cert.get(), one.get(), X509_PURPOSE_SSL_CLIENT, crl.get()), X509_V_ERR_CERT_REVOKED);
  EXPECT_EQ(verify(ca_cert.get(), three.get(), X509_PURPOSE_SSL_CLIENT, crl.get()), X509_V_ERR_CERT_REVOKED);
  EXPECT_EQ(verify(ca_cert.get(), two.get(), X509_PURPOSE_SSL_CLIENT, crl.get()), X509_V_OK);
}

TEST_F(CertificateAuthority, RenewingTheListKeepsItsEntriesAndMovesItsNextUpdate) {
  init();
  client("hmi-1", "operator");
  ASSERT_TRUE(ca::revoke(d, (dir / "hmi-1.pem").string(), {.days = 1}));
  const X509CrlHandle before = read_crl(dir / "crl.pem");
  auto renewed = ca::renew_crl(d, {.days = 60});
  ASSERT_TRUE(renewed) << renewed.error().message;
  EXPECT_EQ(renewed->revoked_count, 1u);
  const X509CrlHandle after = read_crl(dir / "crl.pem");
  const X509Handle cert = read_cert(dir / "hmi-1.pem");
  ASSERT_TRUE(before && after && cert);
  X509_REVOKED* entry = nullptr;
  EXPECT_EQ(X509_CRL_get0_by_serial(after.get(), &entry, X509_get0_serialNumber(cert.get())), 1);
  int days = 0, seconds = 0;
  ASSERT_TRUE(ASN1_TIME_diff(&days, &seconds, X509_CRL_get0_lastUpdate(after.get()), X509_CRL_get0_nextUpdate(after.get())));
  EXPECT_EQ(days, 60);
  const epa::tls::Asn1IntegerHandle n_before(static_cast<ASN1_INTEGER*>(X509_CRL_get_ext_d2i(before.get(), NID_crl_number, nullptr, nullptr)));
  const epa::tls::Asn1IntegerHandle n_after(static_cast<ASN1_INTEGER*>(X509_CRL_get_ext_d2i(after.get(), NID_crl_number, nullptr, nullptr)));
  ASSERT_TRUE(n_before && n_after);
  EXPECT_EQ(ASN1_INTEGER_get(n_after.get()), ASN1_INTEGER_get(n_before.get()) + 1);
}

TEST_F(CertificateAuthority, OnlyTheCasOwnCertificatesAndListAreTakenForRevocation) {
  init();
  const std::filesystem::path other = tmp.path / "other";
  ASSERT_TRUE(ca::init(other.string(), {}));
  auto foreign = ca::revoke(d, (other / "device.pem").string(), {});
  ASSERT_FALSE(foreign);
  EXPECT_NE(foreign.error().message.find((other / "device.pem").string() + ": not issued by the CA in " + (dir / "ca.pem").string()),
            std::string::npos)
      << foreign.error().message;
  auto itself = ca::revoke(d, (dir / "ca.pem").string(), {});
  ASSERT_FALSE(itself);
  EXPECT_NE(itself.error().message.find("the CA certificate itself"), std::string::npos) << itself.error().message;
  auto missing = ca::revoke(d, (dir / "nobody.pem").string(), {});
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find((dir / "nobody.pem").string() + ": cannot open the certificate"), std::string::npos)
      << missing.error().message;

  // A list another CA signed is not extended (its entries would vouch for nothing here).
  client("hmi-1", "operator");
  std::filesystem::copy_file(other / "crl.pem", dir / "crl.pem", std::filesystem::copy_options::overwrite_existing);
  auto wrong_list = ca::revoke(d, (dir / "hmi-1.pem").string(), {});
  ASSERT_FALSE(wrong_list);
  EXPECT_NE(wrong_list.error().message.find((dir / "crl.pem").string() + ": not signed by the CA"), std::string::npos)
      << wrong_list.error().message;
  EXPECT_EQ(file_text(dir / "crl.pem"), file_text(other / "crl.pem"));
}

}  // namespace certificate_authority_test
