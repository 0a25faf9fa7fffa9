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

}  // namespace
