#include "hal/comedi_daq.hpp"

#include <cmath>
#include <cstdio>
#include <vector>

#include "core/format.hpp"
#include "core/paper_reference.hpp"

#ifdef EPA_HAVE_COMEDI
#include <comedilib.h>
#endif

namespace epa::hal {
namespace {

std::string range_text(double min_v, double max_v) {
  return "[" + core::format_number(min_v) + ", " + core::format_number(max_v) + "] V";
}

core::Status validate_channel(const ComediChannel& c, const std::string& name) {
  if (c.subdevice < -1) {
    return core::invalid_argument(name + ".subdevice must be >= 0 (or -1 for the first suitable one), got " +
                                  std::to_string(c.subdevice));
  }
  if (c.channel < 0) {
    return core::invalid_argument(name + ".channel must be >= 0, got " + std::to_string(c.channel));
  }
  if (!std::isfinite(c.range_min_v) || !std::isfinite(c.range_max_v)) {
    return core::invalid_argument(name + ".range_min_v/" + name + ".range_max_v must be finite");
  }
  if (!(c.range_min_v < c.range_max_v)) {
    return core::invalid_argument(name + ".range_min_v (" + core::format_number(c.range_min_v) + ") must be below " + name +
                                  ".range_max_v (" + core::format_number(c.range_max_v) + ")");
  }
  return core::ok();
}

}  // namespace

core::Status validate(const ComediConfig& config) {
  if (config.device.empty()) return core::invalid_argument("device must name a comedi device, e.g. /dev/comedi0");
  if (auto s = validate_channel(config.sensor, "sensor"); !s) return s;
  if (auto s = validate_channel(config.valve, "valve"); !s) return s;
  // The controller saturates at +-5 V (paper section 4.1); a narrower output would clip it again.
  constexpr double kLimitV = core::paper::kValveLimitV;
  if (config.valve.range_min_v > -kLimitV || config.valve.range_max_v < kLimitV) {
    return core::invalid_argument("valve.range_min_v/valve.range_max_v " +
                                  range_text(config.valve.range_min_v, config.valve.range_max_v) +
                                  " must cover the controller's output " + range_text(-kLimitV, kLimitV));
  }
  return core::ok();
}

std::optional<int> choose_range(std::span<const VoltRange> ranges, double min_v, double max_v) {
  std::optional<int> best;
  double best_span_v = 0.0;
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    const VoltRange& r = ranges[i];
    if (!std::isfinite(r.min_v) || !std::isfinite(r.max_v)) continue;  // non-volt range
    if (r.min_v > min_v + kRangeToleranceV || r.max_v < max_v - kRangeToleranceV) continue;
    const double span_v = r.max_v - r.min_v;
    if (!best || span_v < best_span_v) {
      best = static_cast<int>(i);
      best_span_v = span_v;
    }
  }
  return best;
}

double counts_to_volts(std::uint32_t counts, VoltRange range, std::uint32_t maxdata) noexcept {
  if (maxdata == 0) return std::nan("");
  return range.min_v + static_cast<double>(counts) / maxdata * (range.max_v - range.min_v);
}

std::uint32_t volts_to_counts(double volts, VoltRange range, std::uint32_t maxdata) noexcept {
  if (maxdata == 0 || !(range.max_v > range.min_v)) return 0;
  if (std::isnan(volts)) volts = 0.0;
  const double s = (volts - range.min_v) / (range.max_v - range.min_v) * maxdata;
  if (!(s > 0.0)) return 0;
  if (s >= maxdata) return maxdata;
  return static_cast<std::uint32_t>(std::floor(s + 0.5));
}

std::string format_ranges(std::span<const VoltRange> ranges) {
  std::string out;
  for (const VoltRange& r : ranges) {
    if (!out.empty()) out += ", ";
    const bool volts = std::isfinite(r.min_v) && std::isfinite(r.max_v);
    out += volts ? range_text(r.min_v, r.max_v) : "non-volt range";
  }
  return out.empty() ? "none" : out;
}

std::string ComediDaq::describe() const {
  auto channel_text = [&](const char* name, const char* kind, const ComediChannel& c,
                          const ComediResolvedChannel& r) {
    std::string s = std::string(name) + " " + kind;
    if (is_open()) {
      s += " subdevice " + std::to_string(r.subdevice) + " channel " + std::to_string(r.channel) + " range " +
           range_text(r.card_range.min_v, r.card_range.max_v) + " (#" + std::to_string(r.range_index) +
           ", maxdata " + std::to_string(r.maxdata) + ")";
    } else {
      s += " subdevice " + (c.subdevice < 0 ? std::string("auto") : std::to_string(c.subdevice)) + " channel " +
           std::to_string(c.channel) + " needs " + range_text(c.range_min_v, c.range_max_v);
    }
    return s;
  };
  return "comedi " + config_.device + (is_open() ? "" : " (not open)") + ": " +
         channel_text("sensor", "AI", config_.sensor, sensor_) + "; " +
         channel_text("valve", "AO", config_.valve, valve_);
}

#ifdef EPA_HAVE_COMEDI

namespace {

std::string last_comedi_error() { return comedi_strerror(comedi_errno()); }

unsigned aref_code(AnalogReference a) {
  switch (a) {
    case AnalogReference::kGround: return AREF_GROUND;
    case AnalogReference::kCommon: return AREF_COMMON;
    case AnalogReference::kDiff: return AREF_DIFF;
    case AnalogReference::kOther: return AREF_OTHER;
  }
  return AREF_GROUND;
}

const char* subdevice_kind(int type) {
  switch (type) {
    case COMEDI_SUBD_AI: return "an analog input";
    case COMEDI_SUBD_AO: return "an analog output";
    case COMEDI_SUBD_DI: return "a digital input";
    case COMEDI_SUBD_DO: return "a digital output";
    case COMEDI_SUBD_DIO: return "a digital I/O";
    case COMEDI_SUBD_COUNTER: return "a counter";
    case COMEDI_SUBD_UNUSED: return "an unused";
    default: return "another kind of";
  }
}

// Finds the subdevice, checks the channel, picks the range and caches maxdata for one signal.
// `name` is "sensor" or "valve"; `where` prefixes every message with the device.
core::Result<ComediResolvedChannel> resolve(comedi_t* dev, const std::string& where, const char* name,
                                            const ComediChannel& c, int wanted_type) {
  const std::string field = name;
  const int n_subdevices = comedi_get_n_subdevices(dev);
  if (n_subdevices < 0) return core::io_error(where + ": cannot list subdevices: " + last_comedi_error());
  int subd = c.subdevice;
  if (subd < 0) {
    for (int i = 0; i < n_subdevices && subd < 0; ++i) {
      if (comedi_get_subdevice_type(dev, i) == wanted_type) subd = i;
    }
    if (subd < 0) {
      return core::invalid_argument(where + ": " + field + ": the card has no " +
                                    (wanted_type == COMEDI_SUBD_AI ? "analog input" : "analog output") +
                                    " subdevice");
    }
  } else if (subd >= n_subdevices) {
    return core::invalid_argument(where + ": " + field + ".subdevice " + std::to_string(subd) +
                                  " does not exist (the card has " + std::to_string(n_subdevices) + ")");
  } else if (const int type = comedi_get_subdevice_type(dev, subd); type != wanted_type) {
    return core::invalid_argument(where + ": " + field + ".subdevice " + std::to_string(subd) + " is " +
                                  subdevice_kind(type) + " subdevice, not " + subdevice_kind(wanted_type) + " one");
  }
  const auto usubd = static_cast<unsigned>(subd);
  const auto chan = static_cast<unsigned>(c.channel);
  const int n_channels = comedi_get_n_channels(dev, usubd);
  if (n_channels < 0) return core::io_error(where + ": cannot count channels: " + last_comedi_error());
  if (c.channel >= n_channels) {
    return core::invalid_argument(where + ": " + field + ".channel " + std::to_string(c.channel) +
                                  " does not exist (subdevice " + std::to_string(subd) + " has channels 0-" +
                                  std::to_string(n_channels - 1) + ")");
  }
  const int n_ranges = comedi_get_n_ranges(dev, usubd, chan);
  if (n_ranges <= 0) return core::io_error(where + ": cannot list ranges: " + last_comedi_error());
  std::vector<VoltRange> ranges;
  for (int i = 0; i < n_ranges; ++i) {
    const comedi_range* r = comedi_get_range(dev, usubd, chan, static_cast<unsigned>(i));
    const bool volts = r != nullptr && r->unit == UNIT_volt;
    ranges.push_back(volts ? VoltRange{r->min, r->max} : VoltRange{std::nan(""), std::nan("")});
  }
  const auto index = choose_range(ranges, c.range_min_v, c.range_max_v);
  if (!index) {
    return core::invalid_argument(where + ": no range of " + field + " subdevice " + std::to_string(subd) +
                                  " channel " + std::to_string(c.channel) + " covers " + field + ".range_min_v/" +
                                  "range_max_v " + range_text(c.range_min_v, c.range_max_v) +
                                  "; the card offers " + format_ranges(ranges));
  }
  const lsampl_t maxdata = comedi_get_maxdata(dev, usubd, chan);
  if (maxdata == 0) return core::io_error(where + ": cannot read maxdata: " + last_comedi_error());
  return ComediResolvedChannel{usubd, chan, static_cast<unsigned>(*index), aref_code(c.aref), maxdata,
                               ranges[static_cast<std::size_t>(*index)]};
}

}  // namespace

bool comedi_support_built() noexcept { return true; }

core::Status ComediDaq::open() {
  if (auto s = validate(config_); !s) return s;
  const std::string where = "comedi " + config_.device;
  if (is_open()) return core::invalid_argument(where + ": already open");
  comedi_t* dev = comedi_open(config_.device.c_str());
  if (dev == nullptr) return core::io_error(where + ": cannot open: " + last_comedi_error());
  auto sensor = resolve(dev, where, "sensor", config_.sensor, COMEDI_SUBD_AI);
  auto valve = sensor ? resolve(dev, where, "valve", config_.valve, COMEDI_SUBD_AO) : sensor;
  if (!sensor || !valve) {
    comedi_close(dev);
    return sensor ? valve.error() : sensor.error();
  }
  device_ = dev;
  sensor_ = *sensor;
  valve_ = *valve;
  if (write_valve(0.0) != IoStatus::kOk) {
    const std::string reason = last_comedi_error();
    comedi_close(device_);
    device_ = nullptr;
    return core::io_error(where + ": cannot set the valve output to 0 V: " + reason);
  }
  return core::ok();
}

SensorReading ComediDaq::read_sensor() noexcept {
  if (device_ == nullptr) return {IoStatus::kError, 0.0};
  lsampl_t counts = 0;
  const ComediResolvedChannel& s = sensor_;
  if (comedi_data_read(device_, s.subdevice, s.channel, s.range_index, s.aref, &counts) < 0) {
    return {IoStatus::kError, 0.0};
  }
  if (is_rail(counts, s.maxdata)) return {IoStatus::kError, 0.0};  // open or shorted sensor wire
  const double sensor_v = counts_to_volts(counts, s.card_range, s.maxdata);
  if (!std::isfinite(sensor_v)) return {IoStatus::kError, 0.0};
  return {IoStatus::kOk, sensor_v};
}

IoStatus ComediDaq::write_valve(double valve_v) noexcept {
  if (device_ == nullptr) return IoStatus::kError;
  const bool finite = std::isfinite(valve_v);
  double v = finite ? valve_v : 0.0;  // a broken command centres the valve rather than holding the last one
  v = v < config_.valve.range_min_v ? config_.valve.range_min_v : v;
  v = v > config_.valve.range_max_v ? config_.valve.range_max_v : v;
  const ComediResolvedChannel& o = valve_;
  const lsampl_t counts = volts_to_counts(v, o.card_range, o.maxdata);
  if (comedi_data_write(device_, o.subdevice, o.channel, o.range_index, o.aref, counts) < 0) return IoStatus::kError;
  return finite ? IoStatus::kOk : IoStatus::kError;
}

void ComediDaq::close() noexcept {
  if (device_ == nullptr) return;
  (void)write_valve(0.0);  // best effort: nothing more to do if the card no longer answers
  comedi_close(device_);
  device_ = nullptr;
}

#else  // no comedilib: the backend exists so configurations parse, but cannot open

bool comedi_support_built() noexcept { return false; }

core::Status ComediDaq::open() {
  if (auto s = validate(config_); !s) return s;
  return core::io_error("comedi " + config_.device +
                        ": this build has no comedi support (install libcomedi-dev and rebuild)");
}

SensorReading ComediDaq::read_sensor() noexcept { return {IoStatus::kError, 0.0}; }
IoStatus ComediDaq::write_valve(double) noexcept { return IoStatus::kError; }
void ComediDaq::close() noexcept {}

#endif

}  // namespace epa::hal
