#include "rig/module_registers.hpp"

#include <algorithm>
#include <cerrno>
#include <climits>
#include <string>

namespace epa::rig {

namespace {

struct Span {
  int start = 0;
  int count = 0;
};

// The registers of one table that the layout uses.
Span span_of(const hal::RemoteIoLayout& layout, hal::RegisterTable table) {
  int lo = INT_MAX, hi = -1;
  for (const hal::AnalogPoint* p : {&layout.sensor, &layout.valve}) {
    if (p->table != table) continue;
    lo = std::min(lo, p->address);
    hi = std::max(hi, p->address + register_count(*p));
  }
  return hi < 0 ? Span{} : Span{lo, hi - lo};
}

}  // namespace

core::Result<std::unique_ptr<ModuleRegisters>> ModuleRegisters::create(const hal::RemoteIoLayout& layout, double sensor_v) {
  const Span holding = span_of(layout, hal::RegisterTable::kHolding), input = span_of(layout, hal::RegisterTable::kInput);
  modbus_mapping_t* mapping = modbus_mapping_new_start_address(
      0, 0, 0, 0, static_cast<unsigned>(holding.start), static_cast<unsigned>(holding.count),
      static_cast<unsigned>(input.start), static_cast<unsigned>(input.count));
  if (mapping == nullptr)
    return core::io_error("remote I/O simulator: cannot allocate the register mapping: " + std::string(modbus_strerror(errno)));
  std::unique_ptr<ModuleRegisters> registers(new ModuleRegisters(layout, mapping));
  registers->write_point(layout.valve, encode_volts(layout.valve, 0.0));
  registers->write_point(layout.sensor, encode_volts(layout.sensor, sensor_v));
  return registers;
}

ModuleRegisters::~ModuleRegisters() { modbus_mapping_free(mapping_); }

int ModuleRegisters::reply(modbus_t* ctx, const std::uint8_t* query, int length) {
  std::lock_guard lock(mutex_);
  return modbus_reply(ctx, query, length, mapping_);
}

double ModuleRegisters::valve_v() {
  std::lock_guard lock(mutex_);
  return decode_volts(layout_.valve, read_point(layout_.valve)).value_or(0.0);
}

void ModuleRegisters::write_sensor(hal::PointWords words) {
  std::lock_guard lock(mutex_);
  write_point(layout_.sensor, words);
}

std::uint16_t* ModuleRegisters::registers(const hal::AnalogPoint& p) {
  if (p.table == hal::RegisterTable::kInput) return mapping_->tab_input_registers + (p.address - mapping_->start_input_registers);
  return mapping_->tab_registers + (p.address - mapping_->start_registers);
}

hal::PointWords ModuleRegisters::read_point(const hal::AnalogPoint& p) {
  const std::uint16_t* r = registers(p);
  return {r[0], register_count(p) == 2 ? r[1] : std::uint16_t{0}};
}

void ModuleRegisters::write_point(const hal::AnalogPoint& p, hal::PointWords w) {
  std::uint16_t* r = registers(p);
  r[0] = w[0];
  if (register_count(p) == 2) r[1] = w[1];
}

}  // namespace epa::rig
