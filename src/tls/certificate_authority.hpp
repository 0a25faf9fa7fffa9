#pragma once
// A small certificate authority for commissioning and tests (`epa certs`): one folder holds the CA
// (ca.pem, ca.key), the appliance's own certificate (device.pem, device.key), the client
// certificates it issued (NAME.pem, NAME.key, each with its Modbus/TCP Security role) and the
// revocation list (crl.pem). Keys are P-256, written 0600 from their first byte; every serial is
// 128 random bits. A plant with its own PKI does not need any of this: the TLS server only reads
// PEM files (docs/certificates.md says what they must contain).
#include <cstddef>
#include <string>
#include <vector>

#include "core/result.hpp"

namespace epa::tls::ca {

inline constexpr int kMaxValidityDays = 36500;  // beyond that a mistyped number, not a plan

struct InitOptions {
  std::string common_name;                // the device certificate's CN; empty: the host name
  std::vector<std::string> dns_names;     // its subjectAltName DNS names; empty: localhost and the host name
  std::vector<std::string> ip_addresses;  // its subjectAltName addresses; empty: 127.0.0.1 and ::1
  int ca_days = 3650;
  int device_days = 825;
  int crl_days = 30;   // the empty revocation list's nextUpdate
  bool force = false;  // replace files that exist; else refuse before writing anything
};

struct ClientOptions {
  int days = 825;
  bool force = false;
};

struct CrlOptions {
  int days = 30;  // nextUpdate: the TLS server refuses every client once it has passed
};

// One file written, and what it is, in a user's words ("the CA key: keep it on the
// commissioning machine").
struct WrittenFile {
  std::string path;
  std::string what;
};

struct Issued {
  std::vector<WrittenFile> files;
  std::string subject;     // "/CN=hmi-1"
  std::string serial_hex;  // as `openssl x509 -serial` prints it
};

struct CrlWritten {
  WrittenFile file;
  std::size_t revoked_count = 0;
};

struct Revocation {
  std::string subject;
  std::string serial_hex;
  bool already_revoked = false;  // it was on the list before: the list is signed again all the same
  CrlWritten crl;
};

// A new CA and device certificate in `dir` (made if missing): ca.pem, ca.key, device.pem,
// device.key and an empty crl.pem. Refuses, naming the file, when one of them exists and
// options.force is false; then nothing is written.
core::Result<std::vector<WrittenFile>> init(const std::string& dir, const InitOptions& options);

// A client certificate from the CA in `dir`: NAME.pem and NAME.key, CN=NAME, extendedKeyUsage
// clientAuth, the role extension carrying `role`. NAME is a file name of letters, digits, '-', '_'
// and '.', not starting with '.', and not one of the CA's own files (ca, device, crl).
core::Result<Issued> client(const std::string& dir, const std::string& name, const std::string& role, const ClientOptions& options);

// Puts the certificate in `cert_file` (issued by the CA in `dir`) on the CA's revocation list,
// `dir`/crl.pem, keeping the entries it had; lastUpdate now, nextUpdate options.days ahead.
core::Result<Revocation> revoke(const std::string& dir, const std::string& cert_file, const CrlOptions& options);

// Signs `dir`/crl.pem again with the entries it has and a new nextUpdate (before the old one
// passes). A CA without a list yet gets an empty one.
core::Result<CrlWritten> renew_crl(const std::string& dir, const CrlOptions& options);

// Whether `name` may name a client's files; the error says what a name may hold.
core::Status check_client_name(const std::string& name);

}  // namespace epa::tls::ca
