#pragma once
// The `modbus-io` backend: the sensor and valve live on a remote analog I/O module reached over
// Modbus TCP (libmodbus client). One request per read_sensor() and one per write_valve().
//
// Time bound per call: libmodbus is configured so that the whole response must arrive within
// response_timeout_ms (byte timeout disabled), and its TCP connect waits for the handshake at most
// that long too (libmodbus 3.1.6 _connect: non-blocking socket + select on the response timeout;
// a test checks it against a listener that never completes the handshake, errno EINPROGRESS). Every read_sensor()
// and write_valve() therefore makes at most one blocking network call bounded by
// response_timeout_ms, plus system-call overhead.
//
// Failures: a timeout or a malformed or mismatched answer keeps the connection; the socket is
// flushed before the next request (libmodbus checks the TCP transaction id, so a late answer is
// never taken for another): one late answer costs a sample or two, which the scan cycle bridges,
// instead of a reconnect.
// A Modbus exception answer (e.g. illegal address) is an error and keeps the connection too.
// A broken link (reset, refused, closed) closes it. While disconnected, write_valve() returns
// kError at once, and read_sensor() returns kError and retries the connect after 1, 2, 4, ...
// calls, at most reconnect_interval_cycles apart (a brief glitch heals within the scan cycle's
// I/O-error tolerance; a dead module is not hammered). The reconnecting call does not also read,
// to stay within the bound, so the first good reading comes one call later.
// The cycle calls allocate nothing (libmodbus uses stack buffers; a test counts operator new).
#include <array>
#include <atomic>
#include <cstdint>
#include <string>

#include "core/result.hpp"
#include "hal/daq.hpp"
#include "hal/remote_io_layout.hpp"

struct _modbus;  // libmodbus' context (modbus_t); libmodbus stays private to epa::hal

namespace epa::hal {

struct ModbusIoConfig {
  std::string host = "127.0.0.1";  // IPv4 address of the module (libmodbus' TCP backend takes no names)
  int port = 1502;
  int unit_id = 1;                 // Modbus unit (slave) id, 0..247
  int response_timeout_ms = 2;     // bound on each request and on each connect attempt
  int reconnect_interval_cycles = 200;  // longest wait between connect attempts, in read_sensor() calls (1 s)
  RemoteIoLayout layout = default_remote_io_layout();
};

// port 1..65535, unit id 0..247, timeout 1..1000 ms, reconnect interval >= 1, host an IPv4
// address, layout valid. Messages name the field.
core::Status validate(const ModbusIoConfig& config);

class ModbusIoDaq final : public Daq {
 public:
  explicit ModbusIoDaq(ModbusIoConfig config);
  ~ModbusIoDaq() override;
  ModbusIoDaq(const ModbusIoDaq&) = delete;
  ModbusIoDaq& operator=(const ModbusIoDaq&) = delete;

  std::string describe() const override;  // "modbus-io 127.0.0.1:1502 unit 1, sensor ..., valve ..."
  // Validates the config, connects, and reads the sensor once so that a wrong unit id or address
  // fails here with the module's answer rather than as I/O faults in the loop.
  core::Status open() override;
  SensorReading read_sensor() noexcept override;
  IoStatus write_valve(double valve_v) noexcept override;  // non-finite: writes 0 V, returns kError
  void close() noexcept override;

  // Statistics; safe to read from another thread.
  bool connected() const { return connected_.load(std::memory_order_relaxed); }
  std::uint64_t failed_requests() const { return failed_requests_.load(std::memory_order_relaxed); }
  std::uint64_t connect_attempts() const { return connect_attempts_.load(std::memory_order_relaxed); }  // after open()
  std::uint64_t reconnects() const { return reconnects_.load(std::memory_order_relaxed); }

  const ModbusIoConfig& config() const { return config_; }

 private:
  ModbusIoConfig config_;
  _modbus* ctx_ = nullptr;
  std::array<std::uint16_t, 2> words_{};  // request buffer, reused: no allocation in the cycle
  int cycles_disconnected_ = 0;
  int reconnect_wait_ = 1;  // calls until the next connect attempt: 1, 2, 4, ... up to the interval
  bool flush_before_next_request_ = false;  // after a late or mismatched answer
  std::atomic<bool> connected_{false};
  std::atomic<std::uint64_t> failed_requests_{0}, connect_attempts_{0}, reconnects_{0};

  void flush_if_needed() noexcept;
  int read_point_words(const AnalogPoint& point) noexcept;  // libmodbus rc; errno set on -1
  IoStatus fail_request(int saved_errno) noexcept;          // counts, flushes or disconnects, classifies
  std::string where() const;                                // "127.0.0.1:1502 (unit 1)"
};

}  // namespace epa::hal
