#pragma once
// The answer PDU to a read (FC1-FC4) from the register image the request handler filled, as
// libmodbus' modbus_reply builds it, without a socket: the secure port encrypts its answers, and
// libmodbus can only write them to a socket (a detour through a socket pair cost two system calls
// of the seven a TLS request took). Other function codes are left to modbus_reply.
#include <cstdint>
#include <optional>
#include <vector>

struct _modbus_mapping_t;

namespace epa::modbus {

// The response PDU to the read request `pdu` (function code first) of `length` bytes; none when
// it is not a read of FC1-FC4, or its range is outside the image (the handler has checked it).
std::optional<std::vector<std::uint8_t>> read_answer(const std::uint8_t* pdu, int length, const _modbus_mapping_t* image);

}  // namespace epa::modbus
