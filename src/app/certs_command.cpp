#include "app/certs_command.hpp"

#include "tls/certificate_authority.hpp"

namespace epa::app {

CLI::App* add_certs_command(CLI::App& app, CertsOptions& o) {
  auto* cmd = app.add_subcommand("certs", "A small certificate authority for TLS: the appliance's certificate, client certificates with their role, revocation");
  cmd->require_subcommand(1);
  const auto days = CLI::Range(1, tls::ca::kMaxValidityDays);
  const std::string crl_days_help = "Days until the revocation list's next update: renew it before then (epa certs crl)";

  auto* init = cmd->add_subcommand("init", "Make a CA, the appliance's certificate and key, and an empty revocation list in DIR");
  init->add_option("dir", o.dir, "The folder (made if missing): ca.pem, ca.key, device.pem, device.key, crl.pem")->required();
  init->add_option("--cn", o.common_name, "The appliance certificate's common name (default: the host name)");
  init->add_option("--dns", o.dns_names, "A DNS name clients reach the appliance by; repeat it or separate by commas (default: localhost and the host name)")
      ->delimiter(',')
      ->allow_extra_args(false);  // one value a --dns: `--dns a DIR` leaves DIR to the positional
  init->add_option("--ip", o.ip_addresses, "An IPv4 or IPv6 address clients reach the appliance at; repeat it or separate by commas (default: 127.0.0.1 and ::1)")
      ->delimiter(',')
      ->allow_extra_args(false);
  init->add_option("--days", o.days, "Days the appliance's certificate is valid")->capture_default_str()->check(days);
  init->add_option("--ca-days", o.ca_days, "Days the CA is valid")->capture_default_str()->check(days);
  init->add_option("--crl-days", o.crl_days, crl_days_help)->capture_default_str()->check(days);
  init->add_flag("--force", o.force, "Replace the files if they exist (a new CA: every client certificate must be issued again)");
  init->callback([&o] { o.action = CertsAction::kInit; });

  auto* client = cmd->add_subcommand("client", "Issue a client certificate NAME.pem and its key NAME.key from the CA in DIR");
  client->add_option("dir", o.dir, "The folder of epa certs init")->required();
  client->add_option("name", o.name, "The client's name: its common name and file name (letters, digits, '-', '_', '.')")->required();
  client->add_option("--role", o.role, "The Modbus/TCP Security role the certificate carries (operator, viewer, ...)")->required();
  client->add_option("--days", o.days, "Days the certificate is valid")->capture_default_str()->check(days);
  client->add_flag("--force", o.force, "Replace NAME.pem and NAME.key if they exist (revoke the old certificate too)");
  client->callback([&o] { o.action = CertsAction::kClient; });

  auto* revoke = cmd->add_subcommand("revoke", "Put a certificate the CA in DIR issued on its revocation list, DIR/crl.pem");
  revoke->add_option("dir", o.dir, "The folder of epa certs init")->required();
  revoke->add_option("cert", o.cert_file, "The certificate to revoke (a PEM file, e.g. DIR/NAME.pem)")->required();
  revoke->add_option("--crl-days", o.crl_days, crl_days_help)->capture_default_str()->check(days);
  revoke->callback([&o] { o.action = CertsAction::kRevoke; });

  auto* crl = cmd->add_subcommand("crl", "Sign DIR/crl.pem again with a new next update, keeping its entries");
  crl->add_option("dir", o.dir, "The folder of epa certs init")->required();
  crl->add_option("--crl-days", o.crl_days, crl_days_help)->capture_default_str()->check(days);
  crl->callback([&o] { o.action = CertsAction::kCrl; });
  return cmd;
}

namespace {

void print_written(const tls::ca::WrittenFile& f, std::ostream& out) { out << "wrote " << f.path << ": " << f.what << "\n"; }

}  // namespace

int run_certs(const CertsOptions& o, std::ostream& out, std::ostream& err) {
  auto fail = [&err](const std::string& message) { return err << "epa certs: " << message << "\n", 1; };
  switch (o.action) {
    case CertsAction::kInit: {
      const tls::ca::InitOptions options{o.common_name, o.dns_names, o.ip_addresses, o.ca_days, o.days, o.crl_days, o.force};
      auto written = tls::ca::init(o.dir, options);
      if (!written) return fail(written.error().message);
      for (const auto& f : *written) print_written(f, out);
      return 0;
    }
    case CertsAction::kClient: {
      auto issued = tls::ca::client(o.dir, o.name, o.role, {o.days, o.force});
      if (!issued) return fail(issued.error().message);
      for (const auto& f : issued->files) print_written(f, out);
      out << "subject " << issued->subject << ", role " << o.role << ", serial " << issued->serial_hex << "\n";
      return 0;
    }
    case CertsAction::kRevoke: {
      auto revoked = tls::ca::revoke(o.dir, o.cert_file, {o.crl_days});
      if (!revoked) return fail(revoked.error().message);
      out << (revoked->already_revoked ? "already revoked: " : "revoked: ") << revoked->subject << ", serial " << revoked->serial_hex << "\n";
      print_written(revoked->crl.file, out);
      out << "give the appliance the new crl.pem and restart it; sign it again before its next update (epa certs crl " << o.dir << ")\n";
      return 0;
    }
    case CertsAction::kCrl: {
      auto renewed = tls::ca::renew_crl(o.dir, {o.crl_days});
      if (!renewed) return fail(renewed.error().message);
      print_written(renewed->file, out);
      return 0;
    }
    case CertsAction::kNone: break;
  }
  return fail("no subcommand: init, client, revoke or crl");
}

}  // namespace epa::app
