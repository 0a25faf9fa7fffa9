#pragma once
// The Modbus exception a refused write is answered with.
#include <cstdint>

#include "points/gate_result.hpp"

namespace epa::modbus {

// 02 not writable, 03 invalid value, 04 forbidden or not now, 06 busy; 0 when not refused.
std::uint8_t exception_code(points::Refusal r);

}  // namespace epa::modbus
