#pragma once
// The Modbus exception codes this server answers with (Modbus Application Protocol v1.1b3,
// section 7), in one place for the request handler and the FC43 (device identification) answer.
#include <cstdint>

namespace epa::modbus {

inline constexpr std::uint8_t kIllegalFunction = 0x01;
inline constexpr std::uint8_t kIllegalAddress = 0x02;
inline constexpr std::uint8_t kIllegalValue = 0x03;
inline constexpr std::uint8_t kCannotApply = 0x04;  // server device failure: the value could not be applied
inline constexpr std::uint8_t kServerBusy = 0x06;   // server device busy: try again
inline constexpr std::uint8_t kOtherUnit = 0x0B;    // gateway target device failed to respond: not our unit id

}  // namespace epa::modbus
