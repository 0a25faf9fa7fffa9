#pragma once
// A number too small to be meant: non-zero and below the smallest normal float32 (1.18e-38).
// A client with the wrong word order writes one (100.0 sent as CDAB reads 2.4e-41): within most
// ranges, and as a setpoint it moves the piston to 0 mm. Modbus and HTTP refuse it alike; for a
// float32 register it is exactly a subnormal float.
#include <cfloat>
#include <cmath>

namespace epa::core {

inline bool is_tiny_number(double v) { return v != 0.0 && std::abs(v) < static_cast<double>(FLT_MIN); }

}  // namespace epa::core
