#include "rig/remote_io_simulator.hpp"

#include "core/word_order.hpp"
#include "hal/realtime.hpp"
#include "plant/plant_adapter.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <exception>
#include <thread>
#include <vector>

namespace epa::rig {

using hal::AnalogEncoding;
using hal::AnalogPoint;
using hal::PointWords;
using hal::RegisterTable;
using hal::RemoteIoLayout;

namespace {

constexpr long kSelectTimeoutUs = 50'000;  // the server loop notices stop() at least this often
constexpr long kByteTimeoutUs = 100'000;   // a client stalled mid-frame longer than this is dropped
constexpr double kMinTs = 1e-4, kMaxTs = 10.0;
constexpr long kMaxLagPeriods = 10;        // plant thread: start a fresh schedule beyond this lag

struct Span {
  int start = 0;
  int count = 0;
};

// The registers of one table that the layout uses, so that the mapping answers exactly those
// and gives an illegal-address exception for the rest, like a module with a fixed register set.
Span span_of(const RemoteIoLayout& layout, RegisterTable table) {
  int lo = INT_MAX, hi = -1;
  for (const AnalogPoint* p : {&layout.sensor, &layout.valve}) {
    if (p->table != table) continue;
    lo = std::min(lo, p->address);
    hi = std::max(hi, p->address + register_count(*p));
  }
  return hi < 0 ? Span{} : Span{lo, hi - lo};
}

std::int64_t to_ns(const timespec& t) { return std::int64_t{t.tv_sec} * 1'000'000'000 + t.tv_nsec; }
timespec from_ns(std::int64_t ns) {
  return {static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
}

}  // namespace

struct RemoteIoSimulator::Impl {
  Impl(const RemoteIoSimulatorConfig& c, std::unique_ptr<plant::PlantSimulator> p) : config(c), plant(std::move(p)) {}
  ~Impl() {
    stop();
    if (mapping != nullptr) modbus_mapping_free(mapping);
    if (ctx != nullptr) modbus_free(ctx);
  }

  RemoteIoSimulatorConfig config;
  std::unique_ptr<plant::PlantSimulator> plant;  // never null; the plant thread's alone once started
  modbus_t* ctx = nullptr;        // the server thread's alone once started
  modbus_mapping_t* mapping = nullptr;
  std::mutex mapping_mutex;       // guards the register values in mapping
  int listen_fd = -1;
  int bound_port = 0;
  std::atomic<bool> running{false};
  std::atomic<double> position_mm{0.0};
  std::atomic<std::uint64_t> steps{0}, overruns{0}, requests{0};
  std::atomic<int> clients{0};
  std::atomic<double> last_valve_v{0.0};
  std::atomic<std::int64_t> last_request_ns{0};       // 0: no request yet (the watchdog waits for one)
  std::atomic<std::int64_t> last_valve_write_ns{0};   // when the last write to the valve arrived; 0: none yet
  std::atomic<std::int64_t> next_step_due_ns{0};      // when the step the plant thread waits for is due
  std::atomic<bool> watchdog_tripped{false};
  std::atomic<std::int64_t> sensor_fault_step{-1};    // plant step at which a sensor fault was injected
  std::atomic<long> steps_to_safe{-1};
  // Injected faults (ModuleFaults), one atomic each so neither thread ever waits for the injector.
  std::atomic<ModuleFaults::Answers> answers{ModuleFaults::Answers::kNormal};
  std::atomic<int> late_ms{0};
  std::atomic<ModuleFaults::Sensor> sensor_fault{ModuleFaults::Sensor::kNormal};
  std::atomic<double> fixed_sensor_v{0.0};
  std::vector<int> client_fds;  // the server thread's; reserved in start(), so it never allocates
  std::thread server_thread, plant_thread;

  std::uint16_t* registers(const AnalogPoint& p) {
    if (p.table == RegisterTable::kInput)
      return mapping->tab_input_registers + (p.address - mapping->start_input_registers);
    return mapping->tab_registers + (p.address - mapping->start_registers);
  }
  PointWords read_point(const AnalogPoint& p) {
    const std::uint16_t* r = registers(p);
    return {r[0], register_count(p) == 2 ? r[1] : std::uint16_t{0}};
  }
  void write_point(const AnalogPoint& p, PointWords w) {
    std::uint16_t* r = registers(p);
    r[0] = w[0];
    if (register_count(p) == 2) r[1] = w[1];
  }

  void stop() {
    running.store(false);
    if (server_thread.joinable()) server_thread.join();
    if (plant_thread.joinable()) plant_thread.join();
    if (listen_fd >= 0) ::close(listen_fd);
    listen_fd = -1;
  }

  void serve() noexcept;
  bool serve_request(int fd, std::uint8_t* query) noexcept;
  bool writes_valve(const std::uint8_t* query, int length) const noexcept;
  void run_plant() noexcept;
};

void RemoteIoSimulator::Impl::serve() noexcept {
  std::vector<int>& fds = client_fds;
  std::uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
  while (running.load()) {
    fd_set read_set;
    FD_ZERO(&read_set);
    FD_SET(listen_fd, &read_set);
    int max_fd = listen_fd;
    for (int fd : fds) {
      FD_SET(fd, &read_set);
      max_fd = std::max(max_fd, fd);
    }
    timeval tv{0, kSelectTimeoutUs};
    const int n = select(max_fd + 1, &read_set, nullptr, nullptr, &tv);
    if (n == -1 && errno == EINTR) continue;
    if (n == -1) break;  // only a bug of ours (a closed descriptor) gets here
    if (n == 0) continue;
    for (std::size_t i = 0; i < fds.size();) {
      if (FD_ISSET(fds[i], &read_set) && !serve_request(fds[i], query)) {
        ::close(fds[i]);
        fds.erase(fds.begin() + static_cast<std::ptrdiff_t>(i));
        clients.store(static_cast<int>(fds.size()));
      } else {
        ++i;
      }
    }
    if (FD_ISSET(listen_fd, &read_set)) {
      const int fd = accept4(listen_fd, nullptr, nullptr, SOCK_CLOEXEC);
      if (fd < 0) continue;  // the client gave up already; nothing to do
      if (fds.size() >= static_cast<std::size_t>(kMaxClients) || fd >= FD_SETSIZE) {
        ::close(fd);  // refused: select() cannot watch it, or too many clients
        continue;
      }
      const int one = 1;
      setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);  // answers leave at once
      fds.push_back(fd);
      clients.store(static_cast<int>(fds.size()));
    }
  }
  for (int fd : fds) ::close(fd);
  fds.clear();
  clients.store(0);
}

// false: drop this client (it closed, sent garbage or stalled, or its answer could not be sent).
bool RemoteIoSimulator::Impl::serve_request(int fd, std::uint8_t* query) noexcept {
  modbus_set_socket(ctx, fd);
  const int length = modbus_receive(ctx, query);
  if (length == -1) return false;
  if (length == 0) return true;  // libmodbus ignored it
  if (config.sync_to_valve_writes && writes_valve(query, length)) {
    timespec received{};
    clock_gettime(CLOCK_MONOTONIC, &received);  // the master's phase: when it sent, not when answered
    last_valve_write_ns.store(to_ns(received));
  }
  switch (answers.load()) {
    case ModuleFaults::Answers::kNormal: break;
    case ModuleFaults::Answers::kSilent: return true;  // read, never answered: the client times out
    case ModuleFaults::Answers::kLate: std::this_thread::sleep_for(std::chrono::milliseconds(late_ms.load())); break;
    case ModuleFaults::Answers::kGarbage: {
      // A frame that is no answer to anything: wrong transaction id, protocol id and length.
      static constexpr std::uint8_t kGarbage[] = {0xDE, 0xAD, 0xBE, 0xEF, 0x00, 0x03, 0x01, 0x83, 0x7F};
      return ::send(fd, kGarbage, sizeof kGarbage, MSG_NOSIGNAL) == static_cast<ssize_t>(sizeof kGarbage);
    }
  }
  const int unit = query[modbus_get_header_length(ctx) - 1];
  int rc;
  // 0xFF is the Modbus TCP "unit id not used" value for a device addressed by IP alone (and
  // libmodbus' default), so it is answered too.
  if (unit != config.unit_id && unit != MODBUS_TCP_SLAVE) {
    rc = modbus_reply_exception(ctx, query, MODBUS_EXCEPTION_GATEWAY_TARGET);
  } else {
    std::lock_guard lock(mapping_mutex);
    rc = modbus_reply(ctx, query, length, mapping);
  }
  if (rc == -1) return false;
  requests.fetch_add(1);
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  last_request_ns.store(to_ns(now));
  return true;
}

// Whether the request writes a register of the valve point (FC 6, 16 or 23); the frame was checked
// by modbus_receive, and each field read here is inside its length.
bool RemoteIoSimulator::Impl::writes_valve(const std::uint8_t* query, int length) const noexcept {
  const AnalogPoint& valve = config.layout.valve;
  if (valve.table != RegisterTable::kHolding) return false;
  const int h = modbus_get_header_length(ctx);
  const auto word = [&](int at) { return at + 1 < length ? (query[at] << 8) | query[at + 1] : -1; };
  int first = -1, count = 0;
  switch (h < length ? query[h] : 0) {
    case 0x06: first = word(h + 1), count = 1; break;
    case 0x10: first = word(h + 1), count = word(h + 3); break;
    case 0x17: first = word(h + 5), count = word(h + 7); break;  // read/write multiple: the write part
    default: return false;
  }
  return first >= 0 && count > 0 && first <= valve.address && valve.address < first + count;
}

void RemoteIoSimulator::Impl::run_plant() noexcept {
  const auto period_ns = static_cast<std::int64_t>(std::llround(plant->sample_period_s() * 1e9));
  const AnalogPoint& valve = config.layout.valve;
  const AnalogPoint& sensor = config.layout.sensor;
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  std::int64_t next_ns = to_ns(now);
  std::int64_t step_before_ns = next_ns - period_ns;
  while (running.load()) {
    // next_ns is when the last step was due. Synchronised: the master wrote the valve since the
    // step before it, so its next write comes a period after that one; step half a period after
    // it, within half a period of the free schedule. Locked after one write; without writes the
    // schedule runs free.
    const std::int64_t write_ns = last_valve_write_ns.load();
    const std::int64_t last_step_ns = next_ns;
    next_ns += period_ns;
    if (config.sync_to_valve_writes && write_ns > step_before_ns)
      next_ns = std::clamp(write_ns + period_ns + period_ns / 2, last_step_ns + period_ns / 2, last_step_ns + period_ns * 3 / 2);
    step_before_ns = last_step_ns;
    next_step_due_ns.store(next_ns);
    const timespec deadline = from_ns(next_ns);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) == EINTR) {
    }
    if (!running.load()) break;
    double valve_v;
    {
      std::lock_guard lock(mapping_mutex);
      valve_v = decode_volts(valve, read_point(valve)).value_or(0.0);  // undecodable: centred valve
    }
    if (config.watchdog_ms > 0) {
      const std::int64_t last = last_request_ns.load();
      const bool tripped = last != 0 && next_ns - last > static_cast<std::int64_t>(config.watchdog_ms) * 1'000'000;
      watchdog_tripped.store(tripped);
      if (tripped) valve_v = 0.0;  // the module's own safe output: the valve centred
    }
    plant->step(valve_v);
    last_valve_v.store(valve_v);
    if (const std::int64_t at = sensor_fault_step.load(); at >= 0 && steps_to_safe.load() < 0 && valve_v == 0.0)
      steps_to_safe.store(static_cast<long>(static_cast<std::int64_t>(steps.load()) - at));
    {
      std::lock_guard lock(mapping_mutex);
      switch (sensor_fault.load()) {
        case ModuleFaults::Sensor::kNormal: write_point(sensor, encode_volts(sensor, plant->measured_v())); break;
        case ModuleFaults::Sensor::kFrozen: break;  // the last reading stays
        case ModuleFaults::Sensor::kFixed: write_point(sensor, encode_volts(sensor, fixed_sensor_v.load())); break;
        case ModuleFaults::Sensor::kNotANumber:
          // float32: NaN on the wire; int16: -32768, the broken-wire code of analog modules.
          write_point(sensor, sensor.encoding == AnalogEncoding::kFloat32
                                  ? core::encode_f32(std::numeric_limits<float>::quiet_NaN(), sensor.word_order)
                                  : PointWords{0x8000, 0});
          break;
      }
    }
    position_mm.store(plant->position_mm());
    steps.fetch_add(1);
    clock_gettime(CLOCK_MONOTONIC, &now);
    if (to_ns(now) - next_ns > kMaxLagPeriods * period_ns) {
      next_ns = to_ns(now);
      overruns.fetch_add(1);
    }
  }
}

core::Result<std::unique_ptr<RemoteIoSimulator>> RemoteIoSimulator::start(const RemoteIoSimulatorConfig& c) {
  // The model's Ts is checked first, so a bad Ts is reported as such rather than as a plant error.
  if (!(c.model.Ts >= kMinTs && c.model.Ts <= kMaxTs))
    return core::invalid_argument("remote I/O simulator: Ts " + std::to_string(c.model.Ts) +
                                  " s is outside the real-time range 0.0001..10 s");
  auto plant = plant::make_hammerstein_simulator(c.model, c.plant);
  if (!plant) return core::invalid_argument("remote I/O simulator: " + plant.error().message);
  return start(c, std::move(*plant));
}

core::Result<std::unique_ptr<RemoteIoSimulator>> RemoteIoSimulator::start(const RemoteIoSimulatorConfig& c,
                                                                          std::unique_ptr<plant::PlantSimulator> plant) {
  const std::string where = c.address + ":" + std::to_string(c.port);
  in_addr addr{};
  if (inet_pton(AF_INET, c.address.c_str(), &addr) != 1)
    return core::invalid_argument("remote I/O simulator: address '" + c.address + "' is not an IPv4 address");
  if (c.port < 0 || c.port > 65535)
    return core::invalid_argument("remote I/O simulator: port " + std::to_string(c.port) + " is outside 0..65535");
  if (c.unit_id < 0 || c.unit_id > 247)
    return core::invalid_argument("remote I/O simulator: unit id " + std::to_string(c.unit_id) + " is outside 0..247");
  if (auto s = validate(c.layout); !s) return s.error();
  if (plant == nullptr) return core::invalid_argument("remote I/O simulator: no plant given");
  const double Ts = plant->sample_period_s();
  if (!(Ts >= kMinTs && Ts <= kMaxTs))
    return core::invalid_argument("remote I/O simulator: Ts " + std::to_string(Ts) +
                                  " s is outside the real-time range 0.0001..10 s");

  auto impl = std::make_unique<Impl>(c, std::move(plant));
  impl->ctx = modbus_new_tcp(c.address.c_str(), c.port);
  if (impl->ctx == nullptr)
    return core::io_error("remote I/O simulator: cannot create a Modbus TCP context for " + where + ": " +
                          modbus_strerror(errno));
  // The response timeout is what modbus_reply sleeps before flushing a malformed request.
  modbus_set_response_timeout(impl->ctx, 0, 1000);
  modbus_set_byte_timeout(impl->ctx, 0, kByteTimeoutUs);
  modbus_set_indication_timeout(impl->ctx, 0, kByteTimeoutUs);
  impl->listen_fd = modbus_tcp_listen(impl->ctx, kMaxClients);
  if (impl->listen_fd < 0)
    return core::io_error("remote I/O simulator: cannot listen on " + where + ": " + std::strerror(errno));
  fcntl(impl->listen_fd, F_SETFD, FD_CLOEXEC);
  sockaddr_in bound{};
  socklen_t bound_len = sizeof bound;
  if (getsockname(impl->listen_fd, reinterpret_cast<sockaddr*>(&bound), &bound_len) != 0)
    return core::io_error("remote I/O simulator: cannot read the port bound for " + where + ": " +
                          std::strerror(errno));
  impl->bound_port = ntohs(bound.sin_port);

  const Span holding = span_of(c.layout, RegisterTable::kHolding), input = span_of(c.layout, RegisterTable::kInput);
  impl->mapping = modbus_mapping_new_start_address(
      0, 0, 0, 0, static_cast<unsigned>(holding.start), static_cast<unsigned>(holding.count),
      static_cast<unsigned>(input.start), static_cast<unsigned>(input.count));
  if (impl->mapping == nullptr)
    return core::io_error("remote I/O simulator: cannot allocate the register mapping: " +
                          std::string(modbus_strerror(errno)));
  impl->write_point(c.layout.valve, encode_volts(c.layout.valve, 0.0));
  impl->write_point(c.layout.sensor, encode_volts(c.layout.sensor, impl->plant->measured_v()));
  impl->position_mm.store(impl->plant->position_mm());

  impl->running.store(true);
  try {
    impl->client_fds.reserve(kMaxClients);  // push_back in the server loop stays within capacity
    Impl* self = impl.get();
    const hal::RealtimeRequest rt{.fifo_priority = c.realtime_priority, .lock_memory = false, .cpu_dma_latency_us = -1};
    impl->server_thread = std::thread([self, rt] {
      if (rt.fifo_priority > 0) hal::request_realtime(rt);
      self->serve();
    });
    impl->plant_thread = std::thread([self, rt] {
      if (rt.fifo_priority > 0) hal::request_realtime(rt);
      self->run_plant();
    });
  } catch (const std::exception& e) {
    impl->stop();
    return core::io_error(std::string("remote I/O simulator: cannot start: ") + e.what());
  }
  return std::unique_ptr<RemoteIoSimulator>(new RemoteIoSimulator(std::move(impl)));
}

RemoteIoSimulator::RemoteIoSimulator(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RemoteIoSimulator::~RemoteIoSimulator() = default;  // Impl's destructor stops and frees

int RemoteIoSimulator::port() const { return impl_->bound_port; }
double RemoteIoSimulator::position_mm() const { return impl_->position_mm.load(); }
std::uint64_t RemoteIoSimulator::steps() const { return impl_->steps.load(); }
std::uint64_t RemoteIoSimulator::overruns() const { return impl_->overruns.load(); }
std::chrono::steady_clock::time_point RemoteIoSimulator::next_step_due() const {
  return std::chrono::steady_clock::time_point(std::chrono::nanoseconds(impl_->next_step_due_ns.load()));
}
std::uint64_t RemoteIoSimulator::requests() const { return impl_->requests.load(); }
int RemoteIoSimulator::clients() const { return impl_->clients.load(); }
void RemoteIoSimulator::stop() { impl_->stop(); }

double RemoteIoSimulator::valve_v() const { return impl_->last_valve_v.load(); }
long RemoteIoSimulator::steps_to_safe_valve() const { return impl_->steps_to_safe.load(); }
bool RemoteIoSimulator::watchdog_tripped() const { return impl_->watchdog_tripped.load(); }

void RemoteIoSimulator::inject(const ModuleFaults& f) {
  impl_->late_ms.store(f.late_ms);
  impl_->answers.store(f.answers);
  impl_->fixed_sensor_v.store(f.sensor_v);
  if (f.sensor != ModuleFaults::Sensor::kNormal && impl_->sensor_fault.load() == ModuleFaults::Sensor::kNormal) {
    impl_->steps_to_safe.store(-1);
    impl_->sensor_fault_step.store(static_cast<std::int64_t>(impl_->steps.load()));
  }
  impl_->sensor_fault.store(f.sensor);
}

}  // namespace epa::rig
