#pragma once
// The `comedi` backend: a National Instruments card (the paper's rig: NI card + SCB-68) driven
// through comedilib. One analog input reads the position sensor, one analog output drives the
// valve; both are single-sample (comedi_data_read / comedi_data_write), which is what a 5 ms scan
// cycle needs.
//
// open() resolves subdevices, channels, ranges and maxdata once; the cycle path only does the
// ioctl and the arithmetic below. The arithmetic lives in free functions (no comedilib types) so
// that it is tested without a card; this header does not include comedilib.h, so it means the
// same with and without EPA_HAVE_COMEDI.
#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "core/result.hpp"
#include "hal/daq.hpp"

struct comedi_t_struct;  // comedilib's opaque device handle (comedi_t)

namespace epa::hal {

enum class AnalogReference { kGround, kCommon, kDiff, kOther };  // AREF_GROUND, _COMMON, _DIFF, _OTHER

struct ComediChannel {
  int subdevice = -1;  // -1: the first analog input (sensor) / analog output (valve) subdevice
  int channel = 0;
  double range_min_v = -10.0;  // the voltage span this signal needs; the card range must cover it
  double range_max_v = 10.0;
  AnalogReference aref = AnalogReference::kGround;
};

struct ComediConfig {
  std::string device = "/dev/comedi0";
  ComediChannel sensor{-1, 0, 0.0, 10.0, AnalogReference::kGround};
  ComediChannel valve{-1, 0, -10.0, 10.0, AnalogReference::kGround};
};

// Field names in messages are those of ComediConfig: "device", "sensor.channel",
// "valve.range_min_v", ... The valve range must cover the controller's +-5 V saturation.
core::Status validate(const ComediConfig& config);

// ---- Pure parts (no comedilib) ----

// A card range in volts. Ranges the card reports in other units (mA, none) are entered as NaN so
// that indices stay those of comedilib and they are never chosen.
struct VoltRange {
  double min_v = 0.0;
  double max_v = 0.0;
};

// comedilib stores range limits as integer microvolts times 1e-6, so -0.05 V arrives as
// -0.049999999999999996; a covering test needs this much slack (well under 1 uV).
inline constexpr double kRangeToleranceV = 1e-9;

// Index of the narrowest range covering [min_v, max_v] (best resolution); the first one on a
// tie; none if no range covers it. Same rule as comedi_find_range, plus the tolerance above and
// skipping non-volt ranges (comedi_find_range ignores its unit argument).
std::optional<int> choose_range(std::span<const VoltRange> ranges, double min_v, double max_v);

// Counts -> volts, linear over [0, maxdata] -> [min_v, max_v] (comedi_to_phys's formula).
// NaN when maxdata is 0.
double counts_to_volts(std::uint32_t counts, VoltRange range, std::uint32_t maxdata) noexcept;

// Volts -> counts, the inverse, clamped to [0, maxdata] and rounded half up (floor(s + 0.5), as
// comedi_from_phys does): 0 V on a 16-bit +-10 V range is 32767.5 counts and becomes 32768.
// A NaN input gives the count of 0 V clamped into the range (the safe valve output).
std::uint32_t volts_to_counts(double volts, VoltRange range, std::uint32_t maxdata) noexcept;

// A sample at either end of the converter's scale: the input is beyond the range, which for a
// 0-10 V sensor means an open or shorted wire.
constexpr bool is_rail(std::uint32_t counts, std::uint32_t maxdata) noexcept {
  return counts == 0 || counts >= maxdata;
}

// "[-10, 10] V, [-5, 5] V, non-volt range" for messages.
std::string format_ranges(std::span<const VoltRange> ranges);

// Whether this build was compiled against comedilib (EPA_HAVE_COMEDI).
bool comedi_support_built() noexcept;

// What open() resolved for one channel; the cycle path uses only this.
struct ComediResolvedChannel {
  unsigned subdevice = 0;
  unsigned channel = 0;
  unsigned range_index = 0;
  unsigned aref = 0;  // AREF_* code
  std::uint32_t maxdata = 0;
  VoltRange card_range;
};

class ComediDaq final : public Daq {
 public:
  explicit ComediDaq(ComediConfig config) : config_(std::move(config)) {}
  ~ComediDaq() override { close(); }
  ComediDaq(const ComediDaq&) = delete;
  ComediDaq& operator=(const ComediDaq&) = delete;

  std::string describe() const override;
  // Validates the configuration, opens the device, resolves both channels and sets the valve to
  // 0 V, so a valve left driven by an earlier run is centred before the loop starts.
  core::Status open() override;
  // kError before open(), when the driver reports an error, or on a rail sample.
  SensorReading read_sensor() noexcept override;
  // Clamps to the configured valve range; a non-finite command writes 0 V and returns kError.
  IoStatus write_valve(double valve_v) noexcept override;
  // Sets the valve to 0 V (5/3 valve centred), then closes. Safe to call more than once.
  void close() noexcept override;

  bool is_open() const noexcept { return device_ != nullptr; }
  const ComediConfig& config() const noexcept { return config_; }

 private:
  ComediConfig config_;
  comedi_t_struct* device_ = nullptr;
  ComediResolvedChannel sensor_;
  ComediResolvedChannel valve_;
};

}  // namespace epa::hal
