#include "hal/remote_io_layout.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "core/format.hpp"

namespace epa::hal {

const char* to_string(RegisterTable t) {
  switch (t) {
    case RegisterTable::kInput: return "input";
    case RegisterTable::kHolding: return "holding";
  }
  return "?";
}

const char* to_string(AnalogEncoding e) {
  switch (e) {
    case AnalogEncoding::kInt16: return "int16";
    case AnalogEncoding::kFloat32: return "float32";
  }
  return "?";
}

RemoteIoLayout default_remote_io_layout() {
  RemoteIoLayout layout;
  layout.sensor = {.table = RegisterTable::kInput, .address = 0, .encoding = AnalogEncoding::kInt16,
                   .word_order = core::WordOrder::kABCD, .volts_per_count = kDefaultVoltsPerCount, .offset_v = 0.0};
  layout.valve = layout.sensor;
  layout.valve.table = RegisterTable::kHolding;
  return layout;
}

namespace {

core::Status validate_point(const AnalogPoint& p, const std::string& name) {
  const int last = p.address + register_count(p) - 1;
  if (p.address < 0 || last > kMaxRegisterAddress)
    return core::invalid_argument("remote I/O layout: " + name + ".address " + std::to_string(p.address) +
                                  " is outside 0.." + std::to_string(kMaxRegisterAddress - register_count(p) + 1) +
                                  " (a " + to_string(p.encoding) + " point takes " +
                                  std::to_string(register_count(p)) + " register(s))");
  if (p.encoding == AnalogEncoding::kInt16) {
    if (!(p.volts_per_count > 0.0) || !std::isfinite(p.volts_per_count))
      return core::invalid_argument("remote I/O layout: " + name + ".volts_per_count must be > 0 and finite, got " +
                                    core::format_number(p.volts_per_count));
    if (!std::isfinite(p.offset_v))
      return core::invalid_argument("remote I/O layout: " + name + ".offset_v must be finite, got " +
                                    core::format_number(p.offset_v));
  }
  return core::ok();
}

}  // namespace

core::Status validate(const RemoteIoLayout& layout) {
  if (auto s = validate_point(layout.sensor, "sensor"); !s) return s;
  if (auto s = validate_point(layout.valve, "valve"); !s) return s;
  if (layout.valve.table != RegisterTable::kHolding)
    return core::invalid_argument(
        "remote I/O layout: valve.table must be holding (an output has to be writable), got input");
  if (layout.sensor.table == layout.valve.table) {
    const int s0 = layout.sensor.address, s1 = s0 + register_count(layout.sensor);
    const int v0 = layout.valve.address, v1 = v0 + register_count(layout.valve);
    if (s0 < v1 && v0 < s1)
      return core::invalid_argument("remote I/O layout: sensor (" + describe(layout.sensor) + ") and valve (" +
                                    describe(layout.valve) + ") overlap");
  }
  return core::ok();
}

PointWords encode_volts(const AnalogPoint& p, double volts) noexcept {
  if (!std::isfinite(volts)) volts = 0.0;
  if (p.encoding == AnalogEncoding::kFloat32) {
    constexpr double kMax = std::numeric_limits<float>::max();
    return core::encode_f32(static_cast<float>(std::clamp(volts, -kMax, kMax)), p.word_order);
  }
  const double counts = std::clamp(std::round((volts - p.offset_v) / p.volts_per_count),
                                   -static_cast<double>(kInt16FullScaleCounts),
                                   static_cast<double>(kInt16FullScaleCounts));
  const auto c = static_cast<std::int16_t>(counts);
  return {static_cast<std::uint16_t>(c), 0};
}

std::optional<double> decode_volts(const AnalogPoint& p, PointWords words) noexcept {
  if (p.encoding == AnalogEncoding::kFloat32) {
    const float v = core::decode_f32(words, p.word_order);
    if (!std::isfinite(v)) return std::nullopt;
    return static_cast<double>(v);
  }
  const auto counts = static_cast<std::int16_t>(words[0]);
  return counts * p.volts_per_count + p.offset_v;
}

std::string describe(const AnalogPoint& p) {
  std::string text = std::string(to_string(p.table)) + " register";
  if (register_count(p) == 1) {
    text += " " + std::to_string(p.address) + " (int16)";
  } else {
    text += "s " + std::to_string(p.address) + "-" + std::to_string(p.address + 1) + " (float32 " +
            std::string(core::to_string(p.word_order)) + ")";
  }
  return text;
}

}  // namespace epa::hal
