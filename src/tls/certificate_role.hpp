#pragma once
// The Modbus/TCP Security role: an X.509 extension (OID 1.3.6.1.4.1.50316.802.1) whose value is
// one ASN.1 UTF8String naming the client's role ("operator"). The server maps the role to rights
// (tls/role_rights.hpp); the certificate only says who the client is.
#include <openssl/x509.h>

#include <optional>
#include <string>

#include "core/result.hpp"

namespace epa::tls {

inline constexpr const char* kModbusRoleOid = "1.3.6.1.4.1.50316.802.1";

// The role `cert` carries: none when it has no role extension; an error when the extension is there
// but is not one UTF8String of printable text.
core::Result<std::optional<std::string>> role_of(X509* cert);

// Adds the role extension (not critical) carrying `role` to `cert`, before it is signed.
core::Status add_role(X509* cert, const std::string& role);

// The certificate's subject, one line ("CN=hmi-1,O=Plant"), for the log and the audit trail.
std::string subject_of(X509* cert);

}  // namespace epa::tls
