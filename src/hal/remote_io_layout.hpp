#pragma once
// Where a remote analog I/O module (Modbus TCP) keeps the position sensor input and the valve
// output, and how volts are scaled into register words. Shared by the `modbus-io` DAQ backend
// (the client) and the remote I/O simulator behind `epa plant-server` (the server), so both ends
// always agree.
//
// int16 points: volts = counts * volts_per_count + offset_v, counts a signed 16-bit register,
// clamped to the symmetric full scale ±32767 (modules commonly report -32768 as "over range" or
// "broken wire", so we never write it). float32 points: two registers holding IEEE-754 volts in
// the point's word order; volts_per_count and offset_v are not used.
#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "core/result.hpp"
#include "core/word_order.hpp"

namespace epa::hal {

enum class RegisterTable { kInput, kHolding };  // input registers are read-only (function 4)
enum class AnalogEncoding { kInt16, kFloat32 };

const char* to_string(RegisterTable t);  // "input", "holding"
const char* to_string(AnalogEncoding e); // "int16", "float32"

inline constexpr int kInt16FullScaleCounts = 32767;
inline constexpr double kDefaultVoltsPerCount = 10.0 / kInt16FullScaleCounts;  // ±10 V = ±32767
inline constexpr int kMaxRegisterAddress = 65535;

struct AnalogPoint {
  RegisterTable table = RegisterTable::kInput;
  int address = 0;                                      // protocol address (0-based), first register
  AnalogEncoding encoding = AnalogEncoding::kInt16;
  core::WordOrder word_order = core::WordOrder::kABCD;  // float32 only
  double volts_per_count = kDefaultVoltsPerCount;       // int16 only, > 0
  double offset_v = 0.0;                                // int16 only
};

// 1 for int16, 2 for float32.
inline int register_count(const AnalogPoint& p) { return p.encoding == AnalogEncoding::kFloat32 ? 2 : 1; }

struct RemoteIoLayout {
  AnalogPoint sensor;  // position sensor input, V
  AnalogPoint valve;   // valve command output, V; always a holding register (outputs are writable)
};

// Sensor: input register 0, valve: holding register 0, both int16 with ±10 V = ±32767 counts.
RemoteIoLayout default_remote_io_layout();

// Addresses within 0..65535 (a float32 point needs two), volts_per_count > 0 and finite and
// offset_v finite for int16 points, the valve in the holding table, sensor and valve not
// overlapping when they share a table. Messages name the field, e.g. "valve.address".
core::Status validate(const RemoteIoLayout& layout);

// Register words of one point; words[0] is at point.address, words[1] is used by float32 only.
using PointWords = std::array<std::uint16_t, 2>;

// Volts -> words. int16 rounds to the nearest count and clamps to ±32767; float32 clamps to the
// float range. A non-finite input encodes 0 V (a centred valve), never NaN on the wire.
PointWords encode_volts(const AnalogPoint& point, double volts) noexcept;

// Words -> volts; empty when a float32 point holds NaN or infinity. Allocation-free, for the cycle.
std::optional<double> decode_volts(const AnalogPoint& point, PointWords words) noexcept;

// "input register 0 (int16)" / "holding registers 10-11 (float32 CDAB)", for messages and logs.
std::string describe(const AnalogPoint& point);

}  // namespace epa::hal
