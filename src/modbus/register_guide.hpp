#pragma once
// The part of docs/registers.md an integrator reads first: the control and status words bit by
// bit, the record table's layout, and a "first 10 minutes with your HMI" walk-through. Written
// from the map it documents, so every address it names is the one this map serves (a site map
// that moves or leaves out a point gets a guide that says so, never a stale address).
#include <ostream>

#include "modbus/register_map.hpp"

namespace epa::modbus {

void write_positioning_guide(std::ostream& out, const RegisterMap& map);

}  // namespace epa::modbus
