#include "hal/sim_daq.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/paper_reference.hpp"
#include "plant/plant_adapter.hpp"
#include "plant/pneumatic_plant.hpp"

namespace epa::hal {
namespace {

// A command sequence that crosses both dead-zone break points, stays inside, saturates the
// piston against an end stop and includes a NaN (the plant takes it as 0 V).
double command_v(int k) {
  if (k == 300) return std::nan("");
  if (k < 200) return 3.0;
  if (k < 400) return 1.0;   // inside the dead zone [b_l, b_r] = [-1.722, 1.232]
  if (k < 800) return -4.0;  // down to the end stop at 0 mm
  return 2.5 * std::sin(0.05 * k);
}

TEST(SimDaq, ReadWriteStepsThePlantExactlyLikeHammersteinPlant) {
  const plant::PlantOptions options{.initial_position_mm = 100.0, .noise_std_mm = 0.2, .seed = 42, .stroke_mm = 500.0};
  auto daq = SimDaq::make(core::paper::model(), options);
  auto reference = plant::HammersteinPlant::make(core::paper::model(), options);
  ASSERT_TRUE(daq.has_value());
  ASSERT_TRUE(reference.has_value());
  ASSERT_TRUE(daq->open().has_value());

  bool reached_end_stop = false;
  for (int k = 0; k < 1500; ++k) {
    const SensorReading r = daq->read_sensor();
    ASSERT_EQ(r.status, IoStatus::kOk) << "k = " << k;
    // Same model, options and seed: bit-identical, noise included.
    ASSERT_EQ(r.sensor_v, reference->measured_v()) << "k = " << k;
    ASSERT_EQ(daq->write_valve(command_v(k)), IoStatus::kOk) << "k = " << k;
    reference->step(command_v(k));
    ASSERT_EQ(daq->plant().position_mm(), reference->position_mm()) << "k = " << k;
    reached_end_stop = reached_end_stop || daq->plant().position_mm() == 0.0;
  }
  EXPECT_TRUE(reached_end_stop);                           // the sequence did exercise the clamp
  EXPECT_NE(daq->read_sensor().sensor_v, 100.0 / 50.0);    // and the plant did move
  daq->close();
}

TEST(SimDaq, StartsAtTheInitialPositionInSensorVolts) {
  auto daq = SimDaq::make(core::paper::model(), {.initial_position_mm = 150.0});
  ASSERT_TRUE(daq.has_value());
  const SensorReading r = daq->read_sensor();
  EXPECT_EQ(r.status, IoStatus::kOk);
  EXPECT_DOUBLE_EQ(r.sensor_v, 3.0);  // 150 mm / 50 mm/V
}

TEST(SimDaq, RejectsAnInvalidPlant) {
  auto daq = SimDaq::make(core::paper::model(), {.initial_position_mm = 600.0});
  ASSERT_FALSE(daq.has_value());
  EXPECT_NE(daq.error().message.find("initial position"), std::string::npos) << daq.error().message;
}

TEST(SimDaq, DescribesItsPlant) {
  auto hammerstein = SimDaq::make(core::paper::model(), {});
  ASSERT_TRUE(hammerstein.has_value());
  EXPECT_EQ(hammerstein->describe(), "sim (in-process Hammerstein plant)");
  auto physics = SimDaq::make(plant::make_pneumatic_simulator({}, {}).value());
  ASSERT_TRUE(physics.has_value());
  EXPECT_EQ(physics->describe(), "sim (in-process physics plant)");
  EXPECT_DOUBLE_EQ(physics->plant().sample_period_s(), 0.005);
}

// The physics plant behind the same backend: bit-identical to stepping PneumaticPlant directly.
TEST(SimDaq, StepsThePhysicsPlantExactlyLikePneumaticPlant) {
  const plant::PneumaticOptions options{.initial_position_mm = 100.0, .noise_std_mm = 0.2, .seed = 42, .sensor_bits = 16};
  auto simulator = plant::make_pneumatic_simulator({}, options);
  ASSERT_TRUE(simulator.has_value()) << simulator.error().message;
  auto daq = SimDaq::make(std::move(*simulator));
  auto reference = plant::PneumaticPlant::make({}, options);
  ASSERT_TRUE(daq.has_value());
  ASSERT_TRUE(reference.has_value());
  bool reached_end_stop = false;
  for (int k = 0; k < 1500; ++k) {
    const SensorReading r = daq->read_sensor();
    ASSERT_EQ(r.status, IoStatus::kOk);
    ASSERT_EQ(r.sensor_v, reference->measured_v()) << "k = " << k;
    ASSERT_EQ(daq->write_valve(command_v(k)), IoStatus::kOk);
    reference->step(command_v(k));
    ASSERT_EQ(daq->plant().position_mm(), reference->position_mm()) << "k = " << k;
    reached_end_stop = reached_end_stop || daq->plant().position_mm() == 0.0;
  }
  EXPECT_TRUE(reached_end_stop);
}

TEST(SimDaq, ACopyCarriesItsOwnPlantInTheSameState) {
  auto daq = SimDaq::make(plant::make_pneumatic_simulator({}, {.initial_position_mm = 100.0, .noise_std_mm = 0.3}).value());
  ASSERT_TRUE(daq.has_value());
  for (int k = 0; k < 50; ++k) daq->write_valve(4.0);
  SimDaq copy = *daq;
  for (int k = 0; k < 50; ++k) {
    ASSERT_EQ(copy.read_sensor().sensor_v, daq->read_sensor().sensor_v) << "k = " << k;  // noise state copied too
    daq->write_valve(4.0);
    copy.write_valve(4.0);
  }
  for (int k = 0; k < 50; ++k) daq->write_valve(4.0);  // the original moves on, the copy stays
  EXPECT_GT(daq->plant().position_mm(), copy.plant().position_mm() + 1.0);
}

TEST(SimDaq, RefusesANullPlant) {
  auto daq = SimDaq::make(std::unique_ptr<plant::PlantSimulator>());
  ASSERT_FALSE(daq.has_value());
  EXPECT_NE(daq.error().message.find("no plant"), std::string::npos);
}

}  // namespace
}  // namespace epa::hal
