#include "rig/remote_io_simulator.hpp"

#include <arpa/inet.h>

#include <atomic>
#include <exception>
#include <thread>

#include "hal/realtime.hpp"
#include "plant/plant_adapter.hpp"
#include "rig/module_registers.hpp"
#include "rig/module_server.hpp"
#include "rig/plant_loop.hpp"

namespace epa::rig {

namespace {
constexpr double kMinTs = 1e-4, kMaxTs = 10.0;
static_assert(RemoteIoSimulator::kMaxClients == ModuleServer::kMaxClients);

core::Status validate_config(const RemoteIoSimulatorConfig& c) {
  in_addr addr{};
  if (inet_pton(AF_INET, c.address.c_str(), &addr) != 1)
    return core::invalid_argument("remote I/O simulator: address '" + c.address + "' is not an IPv4 address");
  if (c.port < 0 || c.port > 65535)
    return core::invalid_argument("remote I/O simulator: port " + std::to_string(c.port) + " is outside 0..65535");
  if (c.unit_id < 0 || c.unit_id > 247)
    return core::invalid_argument("remote I/O simulator: unit id " + std::to_string(c.unit_id) + " is outside 0..247");
  return validate(c.layout);
}

core::Status validate_period(double Ts) {
  if (!(Ts >= kMinTs && Ts <= kMaxTs))
    return core::invalid_argument("remote I/O simulator: Ts " + std::to_string(Ts) + " s is outside the real-time range 0.0001..10 s");
  return core::ok();
}
}  // namespace

struct RemoteIoSimulator::Impl {
  ~Impl() { stop(); }

  std::unique_ptr<ModuleRegisters> registers;
  InjectedFaults faults;
  MasterActivity activity;
  std::unique_ptr<ModuleServer> server;
  std::unique_ptr<PlantLoop> plant;
  std::atomic<bool> running{false};
  std::thread server_thread, plant_thread;

  void stop() {
    running.store(false);
    if (server_thread.joinable()) server_thread.join();
    if (plant_thread.joinable()) plant_thread.join();
    if (server) server->close_listener();
  }
};

core::Result<std::unique_ptr<RemoteIoSimulator>> RemoteIoSimulator::start(const RemoteIoSimulatorConfig& c) {
  // The model's Ts is checked first, so a bad Ts is reported as such rather than as a plant error.
  if (auto s = validate_period(c.model.Ts); !s) return s.error();
  auto plant = plant::make_hammerstein_simulator(c.model, c.plant);
  if (!plant) return core::invalid_argument("remote I/O simulator: " + plant.error().message);
  return start(c, std::move(*plant));
}

core::Result<std::unique_ptr<RemoteIoSimulator>> RemoteIoSimulator::start(const RemoteIoSimulatorConfig& c,
                                                                          std::unique_ptr<plant::PlantSimulator> plant) {
  if (auto s = validate_config(c); !s) return s.error();
  if (plant == nullptr) return core::invalid_argument("remote I/O simulator: no plant given");
  if (auto s = validate_period(plant->sample_period_s()); !s) return s.error();

  auto impl = std::make_unique<Impl>();
  auto registers = ModuleRegisters::create(c.layout, plant->measured_v());
  if (!registers) return registers.error();
  impl->registers = std::move(*registers);
  const ModuleServer::Setup server_setup{.unit_id = c.unit_id, .valve = c.layout.valve, .record_valve_writes = c.sync_to_valve_writes};
  auto server = ModuleServer::listen(c.address, c.port, server_setup, *impl->registers, impl->faults, impl->activity);
  if (!server) return server.error();
  impl->server = std::move(*server);
  const PlantLoop::Setup plant_setup{.sensor = c.layout.sensor, .sync_to_valve_writes = c.sync_to_valve_writes, .watchdog_ms = c.watchdog_ms};
  impl->plant = std::make_unique<PlantLoop>(plant_setup, std::move(plant), *impl->registers, impl->faults, impl->activity);

  impl->running.store(true);
  try {
    Impl* self = impl.get();
    const hal::RealtimeRequest rt{.fifo_priority = c.realtime_priority, .lock_memory = false, .cpu_dma_latency_us = -1};
    impl->server_thread = std::thread([self, rt] {
      if (rt.fifo_priority > 0) hal::request_realtime(rt);
      self->server->serve(self->running);
    });
    impl->plant_thread = std::thread([self, rt] {
      if (rt.fifo_priority > 0) hal::request_realtime(rt);
      self->plant->run(self->running);
    });
  } catch (const std::exception& e) {
    impl->stop();
    return core::io_error(std::string("remote I/O simulator: cannot start: ") + e.what());
  }
  return std::unique_ptr<RemoteIoSimulator>(new RemoteIoSimulator(std::move(impl)));
}

RemoteIoSimulator::RemoteIoSimulator(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RemoteIoSimulator::~RemoteIoSimulator() = default;  // Impl's destructor stops, the parts free their own

int RemoteIoSimulator::port() const { return impl_->server->port(); }
double RemoteIoSimulator::position_mm() const { return impl_->plant->position_mm(); }
std::uint64_t RemoteIoSimulator::steps() const { return impl_->plant->steps(); }
std::uint64_t RemoteIoSimulator::overruns() const { return impl_->plant->overruns(); }
std::chrono::steady_clock::time_point RemoteIoSimulator::next_step_due() const {
  return std::chrono::steady_clock::time_point(std::chrono::nanoseconds(impl_->plant->next_step_due_ns()));
}
std::uint64_t RemoteIoSimulator::requests() const { return impl_->server->requests(); }
int RemoteIoSimulator::clients() const { return impl_->server->clients(); }
void RemoteIoSimulator::stop() { impl_->stop(); }

double RemoteIoSimulator::valve_v() const { return impl_->plant->valve_v(); }
long RemoteIoSimulator::steps_to_safe_valve() const { return impl_->faults.steps_to_safe_valve(); }
bool RemoteIoSimulator::watchdog_tripped() const { return impl_->plant->watchdog_tripped(); }

void RemoteIoSimulator::inject(const ModuleFaults& f) { impl_->faults.inject(f, impl_->plant->steps()); }

core::Status RemoteIoSimulator::change_physics(std::string_view key, double value) { return impl_->plant->change_physics(key, value); }

}  // namespace epa::rig
