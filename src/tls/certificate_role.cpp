#include "tls/certificate_role.hpp"

#include <openssl/asn1.h>
#include <openssl/objects.h>
#include <openssl/x509v3.h>

#include <memory>

#include "core/printable_name.hpp"
#include "tls/openssl_handles.hpp"

namespace epa::tls {

namespace {
using ObjectHandle = std::unique_ptr<ASN1_OBJECT, OpenSslDeleter<ASN1_OBJECT_free>>;
using Utf8Handle = std::unique_ptr<ASN1_UTF8STRING, OpenSslDeleter<ASN1_UTF8STRING_free>>;
using OctetsHandle = std::unique_ptr<ASN1_OCTET_STRING, OpenSslDeleter<ASN1_OCTET_STRING_free>>;
using ExtensionHandle = std::unique_ptr<X509_EXTENSION, OpenSslDeleter<X509_EXTENSION_free>>;

ObjectHandle role_object() { return ObjectHandle(OBJ_txt2obj(kModbusRoleOid, 1)); }
}  // namespace

core::Result<std::optional<std::string>> role_of(X509* cert) {
  const ObjectHandle oid = role_object();
  const int at = X509_get_ext_by_OBJ(cert, oid.get(), -1);
  if (at < 0) return std::optional<std::string>{};
  const ASN1_OCTET_STRING* der = X509_EXTENSION_get_data(X509_get_ext(cert, at));
  const unsigned char* p = ASN1_STRING_get0_data(der);
  const long length = ASN1_STRING_length(der);
  Utf8Handle text(d2i_ASN1_UTF8STRING(nullptr, &p, length));
  if (!text || p != ASN1_STRING_get0_data(der) + length)
    return core::parse_error(std::string("the role extension (") + kModbusRoleOid + ") is not one UTF8String");
  std::string role(reinterpret_cast<const char*>(ASN1_STRING_get0_data(text.get())), static_cast<std::size_t>(ASN1_STRING_length(text.get())));
  if (auto ok = core::check_printable_name(role, "the certificate's role"); !ok) return ok.error();
  return std::optional<std::string>{role};
}

core::Status add_role(X509* cert, const std::string& role) {
  Utf8Handle text(ASN1_UTF8STRING_new());
  if (!text || !ASN1_STRING_set(text.get(), role.data(), static_cast<int>(role.size())))
    return core::io_error("role extension: " + take_openssl_errors());
  unsigned char* der = nullptr;
  const int length = i2d_ASN1_UTF8STRING(text.get(), &der);
  if (length <= 0) return core::io_error("role extension: " + take_openssl_errors());
  OctetsHandle value(ASN1_OCTET_STRING_new());
  const bool set = value && ASN1_OCTET_STRING_set(value.get(), der, length);
  OPENSSL_free(der);
  if (!set) return core::io_error("role extension: " + take_openssl_errors());
  ExtensionHandle ext(X509_EXTENSION_create_by_OBJ(nullptr, role_object().get(), 0, value.get()));
  if (!ext || !X509_add_ext(cert, ext.get(), -1)) return core::io_error("role extension: " + take_openssl_errors());
  return core::ok();
}

std::string subject_of(X509* cert) {
  char* line = X509_NAME_oneline(X509_get_subject_name(cert), nullptr, 0);
  // A subject is the client's own text: shown as printable ASCII, so it cannot forge a log line.
  std::string text = core::visible_text(line ? line : "", 200);
  OPENSSL_free(line);
  return text;
}

}  // namespace epa::tls
