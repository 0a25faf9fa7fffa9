#include "diag/sensor_resolution.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/random.hpp"

namespace {

epa::core::Run ramp(double step_mm, double noise_mm) {
  epa::core::Run r;
  epa::core::Random rng(3);
  for (int k = 0; k < 2000; ++k) {
    double y = 100.0 + 0.05 * k + noise_mm * rng.normal();
    if (step_mm > 0) y = std::round(y / step_mm) * step_mm;
    r.t_s.push_back(0.005 * k), r.y_mm.push_back(y), r.u_V.push_back(0.0);
  }
  return r;
}

TEST(SensorResolution, AQuantisedSensorsStepIsFoundAndAContinuousOneHasNone) {
  const auto coarse = ramp(1.5, 0.1), fine = ramp(0.0, 0.1), adc = ramp(500.0 / 4096, 0.0);
  ASSERT_TRUE(epa::diag::reading_resolution_mm({&coarse}).has_value());
  EXPECT_NEAR(*epa::diag::reading_resolution_mm({&coarse}), 1.5, 1e-9);
  EXPECT_NEAR(*epa::diag::reading_resolution_mm({&adc}), 500.0 / 4096, 1e-9);
  EXPECT_FALSE(epa::diag::reading_resolution_mm({&fine}).has_value());
  EXPECT_FALSE(epa::diag::reading_resolution_mm({&coarse, &fine}).has_value());  // every run must lie on it
}

TEST(SensorResolution, AStepWrittenWithFewDecimalsIsFoundOverTheWholeStroke) {
  // A 10-bit sensor over 500 mm (0.48876 mm) in a file of 4 decimals, readings across 400 mm:
  // the smallest change is 0.4887 or 0.4888, whose error adds up to a fifth of a step out there.
  const double step = 500.0 / 1023;
  epa::core::Run r;
  for (int k = 0; k < 2000; ++k) {
    const double y = std::round(std::round((50.0 + 0.2 * k) / step) * step * 1e4) / 1e4;
    r.t_s.push_back(0.005 * k), r.y_mm.push_back(y), r.u_V.push_back(0.0);
  }
  const auto found = epa::diag::reading_resolution_mm({&r});
  ASSERT_TRUE(found.has_value());
  EXPECT_NEAR(*found, step, 1e-5);
}

}  // namespace
