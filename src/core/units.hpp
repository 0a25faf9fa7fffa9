#pragma once
// Units shared by the model, the controller and the tools. The model's output y is in sensor
// volts (0-10 V over the 500 mm stroke), as NOTES.md chooses: a user-facing position is in mm.

namespace epa::core {

inline constexpr double kMmPerSensorVolt = 50.0;  // magnetic position sensor: 0-10 V = 0-500 mm
inline constexpr double kStrokeMm = 500.0;        // FESTO cylinder stroke

constexpr double mm_to_sensor_v(double position_mm) { return position_mm / kMmPerSensorVolt; }
constexpr double sensor_v_to_mm(double sensor_v) { return sensor_v * kMmPerSensorVolt; }

}  // namespace epa::core
