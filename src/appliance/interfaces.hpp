#pragma once
// The appliance's two interfaces to its axis: the status page's HTTP server and the Modbus server.
// The web server starts first, so the Modbus identity names the port it bound (VendorUrl; with
// `port = 0` only the bind knows it), and stops first: its status reads the Modbus server's
// counters once that runs.
#include <atomic>
#include <memory>
#include <optional>

#include "appliance/axis.hpp"
#include "config/appliance_config.hpp"
#include "core/result.hpp"
#include "modbus/modbus_server.hpp"
#include "modbus/register_map.hpp"
#include "store/store_writer.hpp"
#include "web/recent_audit.hpp"
#include "web/web_server.hpp"

namespace epa::appliance {

class Interfaces {
 public:
  Interfaces() = default;
  Interfaces(const Interfaces&) = delete;
  Interfaces& operator=(const Interfaces&) = delete;

  // Starts what the configuration enables (the Modbus server when there is a register map), each
  // logging where it listens. `audit`: the recent entries the page shows.
  core::Status start(const config::ApplianceConfig& c, const std::optional<modbus::RegisterMap>& map, Axis& axis,
                     web::RecentAudit& audit, const store::StoreWriter& store);
  // No more commands from either interface.
  void stop();

 private:
  std::atomic<const modbus::ModbusServer*> modbus_for_web_{nullptr};  // null until the Modbus server runs
  std::unique_ptr<modbus::ModbusServer> modbus_;
  std::unique_ptr<web::WebServer> web_;  // after modbus_: destroyed first
};

}  // namespace epa::appliance
