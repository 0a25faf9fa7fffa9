#include "appliance/interfaces.hpp"

#include <spdlog/spdlog.h>

#include <string>

namespace epa::appliance {

namespace {

// Where Modbus/TCP Security listens, whom it trusts and what each role may do.
void log_modbus_tls(const modbus::SecureConfig& s, const std::string& bound, bool read_only) {
  std::string roles;
  for (const modbus::RoleRights& r : s.roles) roles += (roles.empty() ? "" : ", ") + r.role + " " + std::string(points::to_string(r.rights));
  spdlog::info("modbus-tls: listening on {} (TLS 1.2/1.3, client certificates of CA {}, {}; roles: {}{})", bound, s.files.ca,
               s.files.crl.empty() ? "no CRL" : "CRL " + s.files.crl, roles, read_only ? "; read-only: every write refused" : "");
}

// How the web port speaks, for its start line: "" for plain HTTP.
std::string web_tls_text(const config::ApplianceConfig& c) {
  if (!c.web.tls) return "";
  if (c.web.client_certificates == web::ClientCertificates::kOff) return "HTTPS only, no client certificates; ";
  std::string roles;
  for (const modbus::RoleRights& r : c.modbus.secure.roles) roles += (roles.empty() ? "" : ", ") + r.role + " " + std::string(points::to_string(r.rights));
  return "HTTPS only, client certificates of CA " + c.modbus.secure.files.ca + " log in by role: " + roles + "; ";
}

// The status page's address as FC43 names it: https:// when the web port speaks HTTPS.
std::string status_page_url(const config::ApplianceConfig& c, int web_port) {
  std::string url = modbus::status_page_url(web_port);
  if (c.web.tls && url.starts_with("http://")) url.insert(4, "s");
  return url;
}

// `status_page_url`: the status page's address (FC43's VendorUrl), "" with none.
core::Result<std::unique_ptr<modbus::ModbusServer>> start_modbus(const config::ApplianceConfig& c, const modbus::RegisterMap& map,
                                                                 Axis& axis, std::string status_page_url) {
  modbus::ServerConfig mc = c.modbus;
  mc.status_page_url = std::move(status_page_url);
  auto server = modbus::ModbusServer::start(mc, map, axis.gate(), axis.channels(), [](const std::string& line) { spdlog::info("{}", line); });
  if (!server) return server.error();
  const auto& p = c.modbus.policy;
  std::string aliases;
  for (const int id : c.modbus.alias_unit_ids) aliases += (aliases.empty() ? ", also " : " and ") + std::to_string(id);
  if (c.modbus.plain_enabled)
    spdlog::info("modbus: listening on {} (unit {}{}, map {}, {} points, {})", (*server)->bound_address(),
                 c.modbus.unit_id, aliases, c.register_map_path, map.entries().size(),
                 p.read_only ? "read-only" : p.unlock_key ? "tuning locked until unlocked" : "tuning locked (no unlock key)");
  if (c.modbus.secure.enabled) log_modbus_tls(c.modbus.secure, (*server)->secure_bound_address(), p.read_only);
  if (const std::string notice = config::any_address_notice(c); !notice.empty()) spdlog::warn("{}", notice);
  return server;
}

// `modbus`: the Modbus server once it has started, null while it has not or without one.
core::Result<std::unique_ptr<web::WebServer>> start_web(const config::ApplianceConfig& c, Axis& axis, web::RecentAudit& audit,
                                                        const std::atomic<const modbus::ModbusServer*>& modbus,
                                                        const store::StoreWriter& store) {
  auto modbus_stats = [&modbus, any_address = config::any_address_may_command(c)] {
    const modbus::ModbusServer* mb = modbus.load();
    return mb ? web::ModbusStats{true, mb->clients(), mb->requests(), mb->exceptions(), any_address} : web::ModbusStats{};
  };
  auto store_stats = [&store] {
    const auto counters = store.counters();
    const auto health = store.health();
    return web::StoreStats{true, health.ok, counters.accepted, counters.saved, health.last_error, store.running_set().name,
                           counters.disk_low};
  };
  web::WebConfig web_config = c.web;
  web_config.log = [](const std::string& line) { spdlog::warn("{}", line); };
  // HTTPS: the certificate files and the role table of [modbus_tls], whether or not Modbus/TCP Security runs.
  web_config.tls_files = c.modbus.secure.files;
  for (const modbus::RoleRights& r : c.modbus.secure.roles) web_config.roles.push_back({r.role, r.rights});
  auto server = web::WebServer::start(web_config, axis.channels(), &axis.gate(), &audit, modbus_stats, store_stats, &axis.commissioning());
  if (!server) return server.error();
  spdlog::info("web: listening on {} ({}static files {}, commands {})", (*server)->bound_address(), web_tls_text(c), c.web.static_dir,
               c.web.token.empty() ? "disabled: no token configured" : "enabled with the token");
  return server;
}

}  // namespace

core::Status Interfaces::start(const config::ApplianceConfig& c, const std::optional<modbus::RegisterMap>& map, Axis& axis,
                               web::RecentAudit& audit, const store::StoreWriter& store) {
  if (c.web_enabled) {
    auto server = start_web(c, axis, audit, modbus_for_web_, store);
    if (!server) return server.error();
    web_ = std::move(*server);
  }
  if (map) {
    auto server = start_modbus(c, *map, axis, web_ ? status_page_url(c, web_->port()) : std::string());
    if (!server) return server.error();
    modbus_ = std::move(*server);
    modbus_for_web_ = modbus_.get();
  }
  return core::ok();
}

void Interfaces::stop() {
  if (web_) web_->stop();
  if (modbus_) modbus_->stop();
}

}  // namespace epa::appliance
