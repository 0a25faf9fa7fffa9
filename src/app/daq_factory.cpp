#include "app/daq_factory.hpp"

#include "hal/comedi_daq.hpp"
#include "hal/modbus_io_daq.hpp"
#include "hal/sim_daq.hpp"

namespace epa::app {

core::Result<std::unique_ptr<hal::Daq>> make_daq(const ApplianceConfig& config, const core::HammersteinModel& model) {
  switch (config.backend) {
    case HalBackend::kSim: {
      auto daq = hal::SimDaq::make(model, config.sim);
      if (!daq) return core::invalid_argument("[hal.sim] " + daq.error().message);
      return std::unique_ptr<hal::Daq>(std::make_unique<hal::SimDaq>(std::move(*daq)));
    }
    case HalBackend::kModbusIo: return std::unique_ptr<hal::Daq>(std::make_unique<hal::ModbusIoDaq>(config.modbus_io));
    case HalBackend::kComedi: return std::unique_ptr<hal::Daq>(std::make_unique<hal::ComediDaq>(config.comedi));
  }
  return core::invalid_argument("unknown DAQ backend");
}

}  // namespace epa::app
