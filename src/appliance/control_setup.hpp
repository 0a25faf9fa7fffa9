#pragma once
// What the control law starts with: the active tuning set from the store (seeded from the
// configuration's model and design files on first start), the configuration's model for the sim
// backend's plant, and the one set of write limits every interface is held to.
#include <optional>
#include <string>

#include "appliance/store_setup.hpp"
#include "config/appliance_config.hpp"
#include "control/controller.hpp"
#include "core/model_file.hpp"
#include "modbus/register_map.hpp"
#include "points/write_limits.hpp"
#include "runtime/tuning.hpp"

namespace epa::appliance {

struct ControlSetup {
  core::ModelFile plant_model;            // the configuration's model: what the sim backend simulates
  StoreStartup store;                     // the active tuning set, its model, the store thread
  control::ControllerConfig tuning_base;  // the running tuning, handed to its owner, the write gate
  runtime::Tuning tuning;
};

// The catalog's write limits, narrowed by the configuration and the register map; the start-up
// setpoint (configuration or --setpoint) must lie within them too.
core::Result<points::WriteLimits> write_limits(const config::ApplianceConfig& c, const std::string& config_path,
                                               const std::optional<modbus::RegisterMap>& map);

// Opens the store (with the configuration's disk limits) and takes the loop's sensor scale,
// controller, start-up fault and retained setpoint (unless `setpoint_given`) from it into
// `c.runtime`.
core::Result<ControlSetup> prepare_control(config::ApplianceConfig& c, const std::optional<modbus::RegisterMap>& map,
                                           bool setpoint_given);

}  // namespace epa::appliance
