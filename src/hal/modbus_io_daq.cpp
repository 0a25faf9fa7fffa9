#include "hal/modbus_io_daq.hpp"

#include <algorithm>

#include <arpa/inet.h>
#include <modbus.h>

#include <cerrno>
#include <limits>
#include <cmath>
#include <utility>

namespace epa::hal {

core::Status validate(const ModbusIoConfig& c) {
  in_addr addr{};
  if (inet_pton(AF_INET, c.host.c_str(), &addr) != 1)
    return core::invalid_argument("modbus-io: host '" + c.host + "' is not an IPv4 address like 192.168.0.10");
  if (c.port < 1 || c.port > 65535)
    return core::invalid_argument("modbus-io: port " + std::to_string(c.port) + " is outside 1..65535");
  if (c.unit_id < 0 || c.unit_id > 247)
    return core::invalid_argument("modbus-io: unit id " + std::to_string(c.unit_id) + " is outside 0..247");
  if (c.response_timeout_ms < 1 || c.response_timeout_ms > 1000)
    return core::invalid_argument("modbus-io: response timeout " + std::to_string(c.response_timeout_ms) +
                                  " ms is outside 1..1000 ms");
  if (c.reconnect_interval_cycles < 1)
    return core::invalid_argument("modbus-io: reconnect interval must be >= 1 cycle, got " +
                                  std::to_string(c.reconnect_interval_cycles));
  return validate(c.layout);
}

ModbusIoDaq::ModbusIoDaq(ModbusIoConfig config) : config_(std::move(config)) {}

ModbusIoDaq::~ModbusIoDaq() { close(); }

std::string ModbusIoDaq::where() const {
  return config_.host + ":" + std::to_string(config_.port) + " (unit " + std::to_string(config_.unit_id) + ")";
}

std::string ModbusIoDaq::describe() const {
  return "modbus-io " + where() + ", sensor " + hal::describe(config_.layout.sensor) + ", valve " +
         hal::describe(config_.layout.valve);
}

core::Status ModbusIoDaq::open() {
  if (auto s = validate(config_); !s) return s;
  close();  // open() after open() starts over
  ctx_ = modbus_new_tcp(config_.host.c_str(), config_.port);
  if (ctx_ == nullptr)
    return core::io_error("modbus-io: cannot create a Modbus TCP context for " + where() + ": " +
                          modbus_strerror(errno));
  const auto timeout_ms = static_cast<std::uint32_t>(config_.response_timeout_ms);
  // Byte timeout 0 disables it: the whole answer must then arrive within the response timeout,
  // which is what bounds each call (modbus_set_byte_timeout(3)).
  if (modbus_set_slave(ctx_, config_.unit_id) == -1 ||
      modbus_set_response_timeout(ctx_, timeout_ms / 1000, (timeout_ms % 1000) * 1000) == -1 ||
      modbus_set_byte_timeout(ctx_, 0, 0) == -1) {
    const std::string reason = modbus_strerror(errno);
    close();
    return core::io_error("modbus-io: cannot configure the context for " + where() + ": " + reason);
  }
  if (modbus_connect(ctx_) == -1) {
    // libmodbus' connect gives up after the response timeout and leaves errno at EINPROGRESS.
    const std::string reason = errno == EINPROGRESS
                                   ? "no answer within " + std::to_string(config_.response_timeout_ms) + " ms"
                                   : std::string(modbus_strerror(errno));
    close();
    return core::io_error("modbus-io: cannot connect to " + where() + ": " + reason);
  }
  connected_.store(true, std::memory_order_relaxed);
  const AnalogPoint& sensor = config_.layout.sensor;
  if (read_point_words(sensor) == -1) {
    const std::string reason = errno == ETIMEDOUT
                                   ? "no answer within " + std::to_string(config_.response_timeout_ms) + " ms"
                                   : std::string(modbus_strerror(errno));
    close();
    return core::io_error("modbus-io: " + where() + " connected, but reading the sensor at " +
                          hal::describe(sensor) + " failed: " + reason);
  }
  cycles_disconnected_ = 0;
  return core::ok();
}

void ModbusIoDaq::flush_if_needed() noexcept {
  if (!flush_before_next_request_) return;
  modbus_flush(ctx_);  // non-blocking: drops whatever answers arrived late
  flush_before_next_request_ = false;
}

int ModbusIoDaq::read_point_words(const AnalogPoint& point) noexcept {
  flush_if_needed();
  const int n = register_count(point);
  const int rc = point.table == RegisterTable::kInput
                     ? modbus_read_input_registers(ctx_, point.address, n, words_.data())
                     : modbus_read_registers(ctx_, point.address, n, words_.data());
  if (rc != -1 && rc != n) {
    errno = EMBMDATA;  // libmodbus checks the count already; keep a short answer an error anyway
    return -1;
  }
  return rc;
}

IoStatus ModbusIoDaq::fail_request(int saved_errno) noexcept {
  failed_requests_.fetch_add(1, std::memory_order_relaxed);
  // A Modbus exception is a complete, well-framed answer: the link stays usable.
  if (saved_errno > MODBUS_ENOBASE && saved_errno <= EMBXGTAR) return IoStatus::kError;
  // Late, malformed or mismatched answers keep the link. The late answer may still be on its
  // way, so flushing now would miss it and the next request would read it (a mismatch, then the
  // same again): the socket is flushed when the next request starts instead.
  if (saved_errno == ETIMEDOUT || saved_errno == EMBBADDATA || saved_errno == EMBMDATA || saved_errno == EMBBADCRC ||
      saved_errno == EMBBADEXC || saved_errno == EMBBADSLAVE) {
    flush_before_next_request_ = true;
    return saved_errno == ETIMEDOUT ? IoStatus::kTimeout : IoStatus::kError;
  }
  modbus_close(ctx_);  // the link itself broke
  connected_.store(false, std::memory_order_relaxed);
  cycles_disconnected_ = 0;
  reconnect_wait_ = 1;
  return IoStatus::kError;
}

SensorReading ModbusIoDaq::read_sensor() noexcept {
  if (ctx_ == nullptr) return {IoStatus::kError, 0.0};  // not opened
  if (!connected()) {
    if (++cycles_disconnected_ < reconnect_wait_) return {IoStatus::kError, 0.0};
    cycles_disconnected_ = 0;
    reconnect_wait_ = std::min(2 * reconnect_wait_, config_.reconnect_interval_cycles);
    connect_attempts_.fetch_add(1, std::memory_order_relaxed);
    if (modbus_connect(ctx_) == -1) return {IoStatus::kError, 0.0};  // libmodbus closed the socket already
    connected_.store(true, std::memory_order_relaxed);
    reconnects_.fetch_add(1, std::memory_order_relaxed);
    return {IoStatus::kError, 0.0};  // this call's time went to the connect; read from the next one
  }
  if (read_point_words(config_.layout.sensor) == -1) return {fail_request(errno), 0.0};
  const auto volts = decode_volts(config_.layout.sensor, words_);
  if (!volts) {
    // The link is fine, the sensor is not (the module reports NaN or infinity): a reading the
    // loop's sensor check faults on in this very cycle, not an I/O error that takes three.
    return {IoStatus::kOk, std::numeric_limits<double>::quiet_NaN()};
  }
  return {IoStatus::kOk, *volts};
}

IoStatus ModbusIoDaq::write_valve(double valve_v) noexcept {
  if (ctx_ == nullptr || !connected()) return IoStatus::kError;
  const AnalogPoint& valve = config_.layout.valve;
  words_ = encode_volts(valve, valve_v);  // non-finite is encoded as 0 V
  flush_if_needed();
  const int rc = register_count(valve) == 1 ? modbus_write_register(ctx_, valve.address, words_[0])
                                            : modbus_write_registers(ctx_, valve.address, 2, words_.data());
  if (rc == -1) return fail_request(errno);
  return std::isfinite(valve_v) ? IoStatus::kOk : IoStatus::kError;
}

void ModbusIoDaq::close() noexcept {
  if (ctx_ != nullptr) {
    modbus_close(ctx_);
    modbus_free(ctx_);
    ctx_ = nullptr;
  }
  connected_.store(false, std::memory_order_relaxed);
}

}  // namespace epa::hal
