#pragma once
// The registers of the simulated module: the valve output and the sensor input where its
// RemoteIoLayout puts them, and nothing else, so any other address gets an illegal-address
// exception, as on a module with a fixed register set. The Modbus server answers from them; the
// plant thread reads the valve and writes the sensor. One mutex guards the values: a test rig,
// not the real-time loop.
#include <cstdint>
#include <memory>
#include <mutex>

#include <modbus.h>

#include "core/result.hpp"
#include "hal/remote_io_layout.hpp"

namespace epa::rig {

class ModuleRegisters {
 public:
  // The valve at 0 V and the sensor at `sensor_v`.
  static core::Result<std::unique_ptr<ModuleRegisters>> create(const hal::RemoteIoLayout& layout, double sensor_v);
  ~ModuleRegisters();
  ModuleRegisters(const ModuleRegisters&) = delete;
  ModuleRegisters& operator=(const ModuleRegisters&) = delete;

  // A Modbus request's answer from the registers (libmodbus' modbus_reply); -1: not sent.
  int reply(modbus_t* ctx, const std::uint8_t* query, int length);
  double valve_v();  // what the master wrote; undecodable: 0 V, the centred valve
  void write_sensor(hal::PointWords words);

 private:
  ModuleRegisters(const hal::RemoteIoLayout& layout, modbus_mapping_t* mapping) : layout_(layout), mapping_(mapping) {}
  std::uint16_t* registers(const hal::AnalogPoint& p);
  hal::PointWords read_point(const hal::AnalogPoint& p);
  void write_point(const hal::AnalogPoint& p, hal::PointWords w);

  const hal::RemoteIoLayout layout_;
  modbus_mapping_t* mapping_;
  std::mutex mutex_;  // guards the register values in mapping_
};

}  // namespace epa::rig
