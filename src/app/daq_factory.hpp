#pragma once
// Chooses the DAQ backend from the configuration: the only place that knows all three.
#include <memory>

#include "app/appliance_config.hpp"
#include "core/hammerstein_model.hpp"
#include "hal/daq.hpp"

namespace epa::app {

core::Result<std::unique_ptr<hal::Daq>> make_daq(const ApplianceConfig& config, const core::HammersteinModel& model);

}  // namespace epa::app
