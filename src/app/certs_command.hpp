#pragma once
// `epa certs`: a small certificate authority for commissioning and tests (tls/certificate_authority.hpp).
// `init DIR` makes the CA, the appliance's certificate and an empty revocation list; `client DIR
// NAME --role ROLE` a client certificate carrying its Modbus/TCP Security role; `revoke DIR
// CERT.pem` puts a certificate on the revocation list; `crl DIR` signs the list again before its
// next update. Each written file is one line on standard output. Exit status 0, or 1 with the
// reason (the file and what was wrong).
#include <CLI/CLI.hpp>
#include <ostream>
#include <string>
#include <vector>

namespace epa::app {

enum class CertsAction { kNone, kInit, kClient, kRevoke, kCrl };

struct CertsOptions {
  CertsAction action = CertsAction::kNone;  // set by the subcommand given
  std::string dir;
  std::string common_name;                // init --cn; empty: the host name
  std::vector<std::string> dns_names;     // init --dns; empty: localhost and the host name
  std::vector<std::string> ip_addresses;  // init --ip; empty: 127.0.0.1 and ::1
  int ca_days = 3650;
  int days = 825;  // the device (init) or client certificate
  int crl_days = 30;
  bool force = false;
  std::string name, role;  // client
  std::string cert_file;   // revoke
};

// Returns the subcommand (main asks it whether it was given).
CLI::App* add_certs_command(CLI::App& app, CertsOptions& options);
int run_certs(const CertsOptions& options, std::ostream& out, std::ostream& err);

}  // namespace epa::app
