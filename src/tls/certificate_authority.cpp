#include "tls/certificate_authority.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <openssl/crypto.h>
#include <openssl/ec.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/rand.h>
#include <openssl/x509v3.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <optional>
#include <string_view>
#include <utility>

#include <fmt/format.h>

#include "core/printable_name.hpp"
#include "core/text_file.hpp"
#include "tls/certificate_role.hpp"
#include "tls/openssl_handles.hpp"

namespace epa::tls::ca {

namespace {

// A certificate, key or CRL is a few KiB; a list of thousands of revocations stays far below.
constexpr std::size_t kPemFileCapBytes = core::kMiB;
// Certificates are valid from an hour before they are made, so that a client or appliance whose
// clock is a little behind the commissioning machine's does not refuse a new certificate.
constexpr long kBackdateS = 3600;
constexpr mode_t kKeyMode = 0600;
constexpr mode_t kPublicMode = 0644;

constexpr const char* kCaCert = "ca.pem";
constexpr const char* kCaKey = "ca.key";
constexpr const char* kDeviceCert = "device.pem";
constexpr const char* kDeviceKey = "device.key";
constexpr const char* kCrl = "crl.pem";

std::string in_dir(const std::string& dir, const std::string& file) { return (std::filesystem::path(dir) / file).string(); }

core::Error openssl_failure(const std::string& what) { return core::io_error(fmt::format("{}: {}", what, take_openssl_errors())); }

core::Status check_days(int days, const char* what) {
  if (days < 1 || days > kMaxValidityDays)
    return core::invalid_argument(fmt::format("{} is {} days: it must be 1 to {} days", what, days, kMaxValidityDays));
  return core::ok();
}

// --- the names a device certificate carries ---

std::string host_name() {
  char name[HOST_NAME_MAX + 1] = {};
  if (gethostname(name, sizeof name - 1) != 0) return "";
  return name;
}

// RFC 1123 host names: labels of letters, digits and '-' (not at either end), joined by '.'.
bool is_dns_name(std::string_view name) {
  if (name.empty() || name.size() > 253) return false;
  std::size_t start = 0;
  while (start <= name.size()) {
    const std::size_t end = std::min(name.find('.', start), name.size());
    const std::string_view label = name.substr(start, end - start);
    if (label.empty() || label.size() > 63 || label.front() == '-' || label.back() == '-') return false;
    for (const char c : label)
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-') return false;
    start = end + 1;
  }
  return true;
}

// An IPv4 or IPv6 address as inet_ntop writes it ("::1"); none when `text` is neither.
std::optional<std::string> canonical_ip(const std::string& text) {
  unsigned char bytes[16];
  char out[INET6_ADDRSTRLEN];
  for (const int family : {AF_INET, AF_INET6})
    if (inet_pton(family, text.c_str(), bytes) == 1 && inet_ntop(family, bytes, out, sizeof out)) return std::string(out);
  return std::nullopt;
}

void add_once(std::vector<std::string>& list, const std::string& item) {
  if (std::find(list.begin(), list.end(), item) == list.end()) list.push_back(item);
}

struct DeviceNames {
  std::string common_name;
  std::vector<std::string> dns, ip;
  std::string alt_names() const {  // the subjectAltName value: "DNS:localhost,IP:127.0.0.1"
    std::string text;
    for (const auto& d : dns) text += (text.empty() ? "DNS:" : ",DNS:") + d;
    for (const auto& a : ip) text += (text.empty() ? "IP:" : ",IP:") + a;
    return text;
  }
};

core::Result<DeviceNames> device_names(const InitOptions& o) {
  const std::string host = host_name();
  DeviceNames names;
  names.common_name = !o.common_name.empty() ? o.common_name : !host.empty() ? host : "epa";
  if (auto ok = core::check_printable_name(names.common_name, "the device's common name"); !ok) return ok.error();
  for (const auto& d : o.dns_names) {
    if (!is_dns_name(d))
      return core::invalid_argument(fmt::format("'{}' is not a DNS name: labels of letters, digits and '-' joined by '.'", core::visible_text(d)));
    add_once(names.dns, d);
  }
  if (o.dns_names.empty()) {
    names.dns.push_back("localhost");
    if (is_dns_name(host)) add_once(names.dns, host);  // a host name no DNS name can be is left out
  }
  for (const auto& a : o.ip_addresses) {
    const auto ip = canonical_ip(a);
    if (!ip) return core::invalid_argument(fmt::format("'{}' is not an IPv4 or IPv6 address", core::visible_text(a)));
    add_once(names.ip, *ip);
  }
  if (o.ip_addresses.empty()) names.ip = {"127.0.0.1", "::1"};
  return names;
}

// --- keys, certificates and lists in memory ---

core::Result<PrivateKeyHandle> new_p256_key() {
  PrivateKeyHandle key(EVP_EC_gen("P-256"));
  if (!key) return openssl_failure("cannot make a P-256 key");
  return key;
}

core::Result<Asn1IntegerHandle> random_serial() {
  unsigned char bytes[16];  // 128 bits: no two certificates of a CA share a serial, and none can be guessed
  if (RAND_bytes(bytes, sizeof bytes) != 1) return openssl_failure("no random serial number");
  BignumHandle number(BN_bin2bn(bytes, sizeof bytes, nullptr));
  if (number && BN_is_zero(number.get())) BN_one(number.get());  // a serial is positive
  Asn1IntegerHandle serial(number ? BN_to_ASN1_INTEGER(number.get(), nullptr) : nullptr);
  if (!serial) return openssl_failure("no random serial number");
  return serial;
}

std::string hex_of(const ASN1_INTEGER* serial) {
  BignumHandle number(ASN1_INTEGER_to_BN(serial, nullptr));
  char* hex = number ? BN_bn2hex(number.get()) : nullptr;
  std::string text = hex ? hex : "?";
  OPENSSL_free(hex);
  return text;
}

std::string time_text(const ASN1_TIME* t) {
  std::tm tm{};
  if (!t || ASN1_TIME_to_tm(t, &tm) != 1) return "?";
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M UTC", &tm);
  return text;
}

struct CertificateSpec {
  std::string common_name;
  int days = 0;
  std::vector<std::pair<int, std::string>> extensions;  // in order: the subject's key id before the authority's
  std::optional<std::string> role;
};

core::Status add_extension(X509* cert, X509* issuer, int nid, const std::string& value) {
  X509V3_CTX ctx;
  X509V3_set_ctx_nodb(&ctx);
  X509V3_set_ctx(&ctx, issuer, cert, nullptr, nullptr, 0);
  X509ExtensionHandle ext(X509V3_EXT_conf_nid(nullptr, &ctx, nid, value.c_str()));
  if (!ext || X509_add_ext(cert, ext.get(), -1) != 1) return openssl_failure(fmt::format("extension {} = {}", OBJ_nid2sn(nid), value));
  return core::ok();
}

// A certificate for `subject_key`, signed by `issuer` with `issuer_key` (self-signed when `issuer`
// is null).
core::Result<X509Handle> make_certificate(const CertificateSpec& spec, EVP_PKEY* subject_key, X509* issuer, EVP_PKEY* issuer_key) {
  X509Handle cert(X509_new());
  if (!cert) return openssl_failure("no certificate");
  auto serial = random_serial();
  if (!serial) return serial.error();
  X509_NAME* subject = X509_get_subject_name(cert.get());
  const auto* cn = reinterpret_cast<const unsigned char*>(spec.common_name.data());
  if (X509_set_version(cert.get(), X509_VERSION_3) != 1 || X509_set_serialNumber(cert.get(), serial->get()) != 1 ||
      X509_NAME_add_entry_by_NID(subject, NID_commonName, MBSTRING_UTF8, cn, static_cast<int>(spec.common_name.size()), -1, 0) != 1 ||
      X509_set_issuer_name(cert.get(), issuer ? X509_get_subject_name(issuer) : subject) != 1 ||
      !X509_gmtime_adj(X509_getm_notBefore(cert.get()), -kBackdateS) ||
      !X509_time_adj_ex(X509_getm_notAfter(cert.get()), spec.days, 0, nullptr) || X509_set_pubkey(cert.get(), subject_key) != 1)
    return openssl_failure(fmt::format("certificate CN={}", spec.common_name));
  for (const auto& [nid, value] : spec.extensions)
    if (auto ok = add_extension(cert.get(), issuer ? issuer : cert.get(), nid, value); !ok) return ok.error();
  if (spec.role)
    if (auto ok = add_role(cert.get(), *spec.role); !ok) return ok.error();
  if (X509_sign(cert.get(), issuer_key, EVP_sha256()) <= 0) return openssl_failure(fmt::format("signing CN={}", spec.common_name));
  return cert;
}

template <typename Write>
core::Result<std::string> pem_text(Write write, const BIO_METHOD* method, const char* what) {
  BioHandle bio(BIO_new(method));
  if (!bio || write(bio.get()) != 1) return openssl_failure(what);
  char* data = nullptr;
  const long length = BIO_get_mem_data(bio.get(), &data);
  return std::string(data, static_cast<std::size_t>(length));
}

core::Result<std::string> certificate_pem(X509* cert) {
  return pem_text([cert](BIO* b) { return PEM_write_bio_X509(b, cert); }, BIO_s_mem(), "certificate as PEM");
}
core::Result<std::string> crl_pem(X509_CRL* crl) {
  return pem_text([crl](BIO* b) { return PEM_write_bio_X509_CRL(b, crl); }, BIO_s_mem(), "CRL as PEM");
}
// PKCS#8 without a passphrase: the appliance starts unattended. Secure memory, cleared when freed.
core::Result<std::string> key_pem(EVP_PKEY* key) {
  return pem_text([key](BIO* b) { return PEM_write_bio_PrivateKey(b, key, nullptr, nullptr, 0, nullptr, nullptr); }, BIO_s_secmem(),
                  "key as PEM");
}

// --- files ---

bool write_all(int fd, std::string_view text) {
  while (!text.empty()) {
    const ssize_t n = ::write(fd, text.data(), text.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    text.remove_prefix(static_cast<std::size_t>(n));
  }
  return true;
}

// Moves `from` to `to`; without `replace`, fails with EEXIST when `to` exists, atomically (a file
// made there meanwhile is not lost).
bool move_into_place(const std::string& from, const std::string& to, bool replace) {
  if (replace) return std::rename(from.c_str(), to.c_str()) == 0;
  if (renameat2(AT_FDCWD, from.c_str(), AT_FDCWD, to.c_str(), RENAME_NOREPLACE) == 0) return true;
  if (errno != EINVAL && errno != ENOSYS) return false;
  if (::link(from.c_str(), to.c_str()) != 0) return false;  // a file system without renameat2: link() refuses an existing name too
  ::unlink(from.c_str());
  return true;
}

// Writes `text` as `path`: into a new file beside it, created with `mode` (so a key is never
// readable by others, not even half-written), flushed, then moved into place, so a reader finds
// no file or the whole one.
core::Status write_file(const std::string& path, std::string_view text, mode_t mode, bool replace) {
  static std::atomic<unsigned> counter{0};
  const std::string tmp = fmt::format("{}.tmp-{}-{}", path, getpid(), counter++);
  const int fd = ::open(tmp.c_str(), O_CREAT | O_EXCL | O_WRONLY | O_CLOEXEC | O_NOFOLLOW, mode);
  if (fd < 0) return core::io_error(fmt::format("{}: cannot create it: {}", path, std::strerror(errno)));
  const bool complete = write_all(fd, text) && ::fsync(fd) == 0;
  int reason = complete ? 0 : errno;
  ::close(fd);
  if (complete && move_into_place(tmp, path, replace)) return core::ok();
  if (complete) reason = errno;
  ::unlink(tmp.c_str());
  if (reason == EEXIST) return core::invalid_argument(fmt::format("{} exists: give --force to replace it", path));
  return core::io_error(fmt::format("{}: cannot write it: {}", path, std::strerror(reason != 0 ? reason : EIO)));
}

core::Status write_key(const std::string& path, EVP_PKEY* key, bool replace) {
  auto pem = key_pem(key);
  if (!pem) return pem.error();
  auto written = write_file(path, *pem, kKeyMode, replace);
  OPENSSL_cleanse(pem->data(), pem->size());
  return written;
}

core::Status write_certificate(const std::string& path, X509* cert, bool replace) {
  auto pem = certificate_pem(cert);
  if (!pem) return pem.error();
  return write_file(path, *pem, kPublicMode, replace);
}

// Refused before anything is made, so that a refusal leaves the folder as it was.
core::Status refuse_existing(const std::vector<std::string>& paths) {
  struct stat st {};
  for (const auto& p : paths)
    if (::lstat(p.c_str(), &st) == 0) return core::invalid_argument(fmt::format("{} exists: give --force to replace it", p));
  return core::ok();
}

bool file_exists(const std::string& path) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0;
}

// An encrypted key is refused, never prompted for: the tools run unattended.
int no_passphrase(char*, int, int, void*) { return -1; }

// `read` of the PEM text in `path`; `what` names it in messages ("CA key"), `rule` adds what it must be.
template <typename Handle, typename Read>
core::Result<Handle> read_pem(const std::string& path, const std::string& what, Read read, const std::string& rule = "") {
  auto text = core::read_text_file(path, what, kPemFileCapBytes);
  if (!text) return text.error();
  BioHandle bio(BIO_new_mem_buf(text->data(), static_cast<int>(text->size())));
  Handle object(bio ? read(bio.get()) : nullptr);
  OPENSSL_cleanse(text->data(), text->size());
  if (!object) return core::parse_error(fmt::format("{}: not a PEM {}{} ({})", path, what, rule, take_openssl_errors()));
  return object;
}

core::Result<X509Handle> read_certificate(const std::string& path, const std::string& what) {
  return read_pem<X509Handle>(path, what, [](BIO* b) { return PEM_read_bio_X509(b, nullptr, nullptr, nullptr); });
}

struct Authority {
  X509Handle cert;
  PrivateKeyHandle key;
  std::string cert_path;
};

core::Result<Authority> read_authority(const std::string& dir) {
  Authority ca{nullptr, nullptr, in_dir(dir, kCaCert)};
  const std::string key_path = in_dir(dir, kCaKey);
  auto cert = read_certificate(ca.cert_path, "CA certificate");
  if (!cert) return cert.error();
  ca.cert = std::move(*cert);
  auto key = read_pem<PrivateKeyHandle>(
      key_path, "CA key", [](BIO* b) { return PEM_read_bio_PrivateKey(b, nullptr, no_passphrase, nullptr); }, " without a passphrase");
  if (!key) return key.error();
  ca.key = std::move(*key);
  if (X509_check_ca(ca.cert.get()) == 0)
    return core::invalid_argument(fmt::format("{}: not a CA certificate (no basicConstraints CA:TRUE)", ca.cert_path));
  if (X509_check_private_key(ca.cert.get(), ca.key.get()) != 1) {
    ERR_clear_error();
    return core::invalid_argument(fmt::format("{}: the key does not match the CA certificate {}", key_path, ca.cert_path));
  }
  if (X509_cmp_current_time(X509_get0_notAfter(ca.cert.get())) <= 0)
    return core::invalid_argument(
        fmt::format("{}: the CA certificate expired on {}: make a new CA (epa certs init --force)", ca.cert_path, time_text(X509_get0_notAfter(ca.cert.get()))));
  return ca;
}

// --- the revocation list ---

// The CA's list as it is on disk: none when there is no file yet; refused when the CA did not sign it.
core::Result<X509CrlHandle> read_own_crl(const Authority& ca, const std::string& path) {
  if (!file_exists(path)) return X509CrlHandle{};
  auto crl = read_pem<X509CrlHandle>(path, "CRL", [](BIO* b) { return PEM_read_bio_X509_CRL(b, nullptr, nullptr, nullptr); });
  if (!crl) return crl.error();
  if (X509_NAME_cmp(X509_CRL_get_issuer(crl->get()), X509_get_subject_name(ca.cert.get())) != 0 ||
      X509_CRL_verify(crl->get(), X509_get0_pubkey(ca.cert.get())) != 1) {
    ERR_clear_error();
    return core::invalid_argument(fmt::format("{}: not signed by the CA in {}", path, ca.cert_path));
  }
  return crl;
}

struct NewCrl {
  X509CrlHandle crl;
  bool already_revoked = false;
  std::size_t count = 0;
};

// A list signed by `ca`: the entries of `previous` (if any) and `serial` (if given and not on it
// already), lastUpdate an hour back (as the certificates' notBefore: an appliance whose clock is a
// little behind must not find the list "not yet valid" and refuse every client), nextUpdate `days`
// ahead, its number one above the previous one's.
core::Result<NewCrl> make_crl(const Authority& ca, X509_CRL* previous, const ASN1_INTEGER* serial, int days) {
  NewCrl out{X509CrlHandle(X509_CRL_new())};
  X509_CRL* crl = out.crl.get();
  Asn1TimeHandle now(X509_time_adj_ex(nullptr, 0, -kBackdateS, nullptr));
  Asn1TimeHandle next(X509_time_adj_ex(nullptr, days, 0, nullptr));
  if (!crl || !now || !next || X509_CRL_set_version(crl, X509_CRL_VERSION_2) != 1 ||
      X509_CRL_set_issuer_name(crl, X509_get_subject_name(ca.cert.get())) != 1 || X509_CRL_set1_lastUpdate(crl, now.get()) != 1 ||
      X509_CRL_set1_nextUpdate(crl, next.get()) != 1)
    return openssl_failure("CRL");
  const STACK_OF(X509_REVOKED)* entries = previous ? X509_CRL_get_REVOKED(previous) : nullptr;
  for (int i = 0; i < sk_X509_REVOKED_num(entries); ++i) {
    const X509_REVOKED* entry = sk_X509_REVOKED_value(entries, i);
    if (serial && ASN1_INTEGER_cmp(X509_REVOKED_get0_serialNumber(entry), serial) == 0) out.already_revoked = true;
    X509RevokedHandle copy(X509_REVOKED_dup(entry));
    if (!copy || X509_CRL_add0_revoked(crl, copy.get()) != 1) return openssl_failure("CRL entry");
    copy.release();  // the list owns it now
  }
  if (serial && !out.already_revoked) {
    X509RevokedHandle entry(X509_REVOKED_new());
    auto* copied = const_cast<ASN1_INTEGER*>(serial);  // the setter copies it; its parameter lacks the const
    if (!entry || X509_REVOKED_set_serialNumber(entry.get(), copied) != 1 || X509_REVOKED_set_revocationDate(entry.get(), now.get()) != 1 ||
        X509_CRL_add0_revoked(crl, entry.get()) != 1)
      return openssl_failure("CRL entry");
    entry.release();
  }
  out.count = static_cast<std::size_t>(std::max(0, sk_X509_REVOKED_num(X509_CRL_get_REVOKED(crl))));  // -1: no list yet

  const Asn1IntegerHandle last(previous ? static_cast<ASN1_INTEGER*>(X509_CRL_get_ext_d2i(previous, NID_crl_number, nullptr, nullptr)) : nullptr);
  BignumHandle n(last ? ASN1_INTEGER_to_BN(last.get(), nullptr) : BN_new());
  const bool counted = n && BN_add_word(n.get(), 1) == 1;
  const Asn1IntegerHandle number(counted ? BN_to_ASN1_INTEGER(n.get(), nullptr) : nullptr);
  if (!number || X509_CRL_add1_ext_i2d(crl, NID_crl_number, number.get(), 0, 0) != 1) return openssl_failure("CRL number");
  X509V3_CTX ctx;
  X509V3_set_ctx_nodb(&ctx);
  X509V3_set_ctx(&ctx, ca.cert.get(), nullptr, nullptr, crl, 0);
  X509ExtensionHandle key_id(X509V3_EXT_conf_nid(nullptr, &ctx, NID_authority_key_identifier, "keyid:always"));
  if (!key_id || X509_CRL_add_ext(crl, key_id.get(), -1) != 1) return openssl_failure("CRL authorityKeyIdentifier");
  if (X509_CRL_sort(crl) != 1 || X509_CRL_sign(crl, ca.key.get(), EVP_sha256()) <= 0) return openssl_failure("signing the CRL");
  return out;
}

core::Result<CrlWritten> write_crl(const std::string& path, const NewCrl& made) {
  auto pem = crl_pem(made.crl.get());
  if (!pem) return pem.error();
  if (auto ok = write_file(path, *pem, kPublicMode, true); !ok) return ok.error();
  const std::string what = made.count == 0 ? "empty" : fmt::format("{} revoked", made.count);
  return CrlWritten{{path, fmt::format("the revocation list, {}, next update {}", what, time_text(X509_CRL_get0_nextUpdate(made.crl.get())))},
                    made.count};
}

// Eight hex digits that tell one CA from the next in a subject ("epa CA 916c1a1e"); not a secret.
std::string ca_tag() {
  unsigned char raw[4] = {};
  RAND_bytes(raw, sizeof raw);  // all zeros if it failed: the name is only less telling
  return fmt::format("{:02x}{:02x}{:02x}{:02x}", raw[0], raw[1], raw[2], raw[3]);
}

}  // namespace

core::Status check_client_name(const std::string& name) {
  const auto safe = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.'; };
  const std::string rule = "a client's name is 1 to 64 letters, digits, '-', '_' and '.', not starting with '.'";
  if (name.empty() || name.size() > core::kMaxNameChars || name.front() == '.' || !std::all_of(name.begin(), name.end(), safe))
    return core::invalid_argument(fmt::format("'{}' is not a safe file name: {}", core::visible_text(name), rule));
  for (const char* own : {"ca", "device", "crl"})
    if (name == own) return core::invalid_argument(fmt::format("'{}' names the CA's own files ({}.pem): choose another name", name, own));
  return core::ok();
}

core::Result<std::vector<WrittenFile>> init(const std::string& dir, const InitOptions& o) {
  const std::pair<int, const char*> validities[] = {
      {o.ca_days, "the CA's validity"}, {o.device_days, "the device certificate's validity"}, {o.crl_days, "the revocation list's validity"}};
  for (const auto& [days, what] : validities)
    if (auto ok = check_days(days, what); !ok) return ok.error();
  auto names = device_names(o);
  if (!names) return names.error();
  const std::string ca_cert = in_dir(dir, kCaCert), ca_key = in_dir(dir, kCaKey), device_cert = in_dir(dir, kDeviceCert),
                    device_key = in_dir(dir, kDeviceKey), crl = in_dir(dir, kCrl);
  if (!o.force)
    if (auto ok = refuse_existing({ca_cert, ca_key, device_cert, device_key, crl}); !ok) return ok.error();
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return core::io_error(fmt::format("{}: cannot make the folder: {}", dir, ec.message()));

  auto ca_private = new_p256_key();
  if (!ca_private) return ca_private.error();
  const CertificateSpec ca_spec{"epa CA " + ca_tag(),
                                o.ca_days,
                                {{NID_basic_constraints, "critical,CA:TRUE"},
                                 {NID_key_usage, "critical,keyCertSign,cRLSign"},
                                 {NID_subject_key_identifier, "hash"}},
                                std::nullopt};
  auto ca = make_certificate(ca_spec, ca_private->get(), nullptr, ca_private->get());
  if (!ca) return ca.error();
  auto device_private = new_p256_key();
  if (!device_private) return device_private.error();
  const CertificateSpec device_spec{names->common_name,
                                    o.device_days,
                                    {{NID_basic_constraints, "critical,CA:FALSE"},
                                     {NID_key_usage, "critical,digitalSignature,keyEncipherment"},
                                     {NID_ext_key_usage, "serverAuth"},
                                     {NID_subject_alt_name, names->alt_names()},
                                     {NID_subject_key_identifier, "hash"},
                                     {NID_authority_key_identifier, "keyid:always"}},
                                    std::nullopt};
  auto device = make_certificate(device_spec, device_private->get(), ca->get(), ca_private->get());
  if (!device) return device.error();
  const Authority authority{std::move(*ca), std::move(*ca_private), ca_cert};
  auto list = make_crl(authority, nullptr, nullptr, o.crl_days);
  if (!list) return list.error();

  const bool replace = o.force;
  if (auto ok = write_key(ca_key, authority.key.get(), replace); !ok) return ok.error();
  if (auto ok = write_certificate(ca_cert, authority.cert.get(), replace); !ok) return ok.error();
  if (auto ok = write_key(device_key, device_private->get(), replace); !ok) return ok.error();
  if (auto ok = write_certificate(device_cert, device->get(), replace); !ok) return ok.error();
  auto written_crl = write_crl(crl, *list);
  if (!written_crl) return written_crl.error();
  return std::vector<WrittenFile>{
      {ca_key, "the CA key (mode 0600): keep it on the commissioning machine, never on the appliance"},
      {ca_cert, fmt::format("the CA certificate, {}, valid {} days: the appliance and its clients trust it", subject_of(authority.cert.get()), o.ca_days)},
      {device_key, "the appliance's key (mode 0600)"},
      {device_cert, fmt::format("the appliance's certificate, {}, {}, valid {} days", subject_of(device->get()), names->alt_names(), o.device_days)},
      written_crl->file};
}

core::Result<Issued> client(const std::string& dir, const std::string& name, const std::string& role, const ClientOptions& o) {
  if (auto ok = check_client_name(name); !ok) return ok.error();
  if (auto ok = core::check_printable_name(role, "the role"); !ok) return ok.error();
  if (auto ok = check_days(o.days, "the client certificate's validity"); !ok) return ok.error();
  const std::string cert_path = in_dir(dir, name + ".pem"), key_path = in_dir(dir, name + ".key");
  if (!o.force)
    if (auto ok = refuse_existing({cert_path, key_path}); !ok) return ok.error();
  auto ca = read_authority(dir);
  if (!ca) return ca.error();
  auto key = new_p256_key();
  if (!key) return key.error();
  const CertificateSpec spec{name,
                             o.days,
                             {{NID_basic_constraints, "critical,CA:FALSE"},
                              {NID_key_usage, "critical,digitalSignature"},
                              {NID_ext_key_usage, "clientAuth"},
                              {NID_subject_key_identifier, "hash"},
                              {NID_authority_key_identifier, "keyid:always"}},
                             role};
  auto cert = make_certificate(spec, key->get(), ca->cert.get(), ca->key.get());
  if (!cert) return cert.error();
  if (auto ok = write_key(key_path, key->get(), o.force); !ok) return ok.error();
  if (auto ok = write_certificate(cert_path, cert->get(), o.force); !ok) return ok.error();
  return Issued{{{key_path, "the client's key (mode 0600): for that client only"},
                 {cert_path, fmt::format("the client's certificate, valid {} days", o.days)}},
                subject_of(cert->get()),
                hex_of(X509_get0_serialNumber(cert->get()))};
}

core::Result<Revocation> revoke(const std::string& dir, const std::string& cert_file, const CrlOptions& o) {
  if (auto ok = check_days(o.days, "the revocation list's validity"); !ok) return ok.error();
  auto ca = read_authority(dir);
  if (!ca) return ca.error();
  auto cert = read_certificate(cert_file, "certificate");
  if (!cert) return cert.error();
  if (X509_cmp(cert->get(), ca->cert.get()) == 0)
    return core::invalid_argument(fmt::format("{}: that is the CA certificate itself: to retire a CA, make a new one", cert_file));
  if (X509_check_issued(ca->cert.get(), cert->get()) != X509_V_OK || X509_verify(cert->get(), X509_get0_pubkey(ca->cert.get())) != 1) {
    ERR_clear_error();
    return core::invalid_argument(fmt::format("{}: not issued by the CA in {}", cert_file, ca->cert_path));
  }
  const std::string crl_path = in_dir(dir, kCrl);
  auto previous = read_own_crl(*ca, crl_path);
  if (!previous) return previous.error();
  auto list = make_crl(*ca, previous->get(), X509_get0_serialNumber(cert->get()), o.days);
  if (!list) return list.error();
  auto written = write_crl(crl_path, *list);
  if (!written) return written.error();
  return Revocation{subject_of(cert->get()), hex_of(X509_get0_serialNumber(cert->get())), list->already_revoked, *written};
}

core::Result<CrlWritten> renew_crl(const std::string& dir, const CrlOptions& o) {
  if (auto ok = check_days(o.days, "the revocation list's validity"); !ok) return ok.error();
  auto ca = read_authority(dir);
  if (!ca) return ca.error();
  const std::string crl_path = in_dir(dir, kCrl);
  auto previous = read_own_crl(*ca, crl_path);
  if (!previous) return previous.error();
  auto list = make_crl(*ca, previous->get(), nullptr, o.days);
  if (!list) return list.error();
  return write_crl(crl_path, *list);
}

}  // namespace epa::tls::ca
