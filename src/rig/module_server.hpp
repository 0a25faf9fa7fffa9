#pragma once
// The simulated module's Modbus TCP server, on its own thread: select() over the listening socket
// and up to kMaxClients clients, waking at least every 50 ms so that a stop is noticed promptly;
// libmodbus' modbus_receive/modbus_reply do the protocol (modbus_reply also answers illegal
// addresses and functions with exceptions). Requests for the configured unit id or for 0xFF
// (Modbus TCP's "no unit id") are served; any other unit id gets exception 0x0B (gateway target
// device failed to respond) rather than silence, so that a misconfigured client gets a clear error
// at once instead of a timeout. A client that disconnects, sends garbage or stalls mid-frame for
// more than 100 ms is dropped; the server carries on. Answers follow the injected faults.
#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include <modbus.h>

#include "core/result.hpp"
#include "hal/remote_io_layout.hpp"
#include "rig/module_faults.hpp"
#include "rig/module_registers.hpp"

namespace epa::rig {

// When the master last talked to the module (CLOCK_MONOTONIC ns; 0: not yet), for the plant
// thread's schedule and the module's watchdog.
struct MasterActivity {
  std::atomic<std::int64_t> last_request_ns{0};
  std::atomic<std::int64_t> last_valve_write_ns{0};  // recorded only when the plant syncs to the writes
};

class ModuleServer {
 public:
  static constexpr int kMaxClients = 16;

  struct Setup {
    int unit_id = 1;
    hal::AnalogPoint valve;            // the point whose writes are recorded
    bool record_valve_writes = false;  // the plant steps in sync with them
  };

  // Binds and listens on address:port (errors name them and the system's reason).
  static core::Result<std::unique_ptr<ModuleServer>> listen(const std::string& address, int port, const Setup& setup,
                                                            ModuleRegisters& registers, const InjectedFaults& faults,
                                                            MasterActivity& activity);
  ~ModuleServer();
  ModuleServer(const ModuleServer&) = delete;
  ModuleServer& operator=(const ModuleServer&) = delete;

  int port() const { return bound_port_; }  // the bound port (the real one when asked for 0)
  std::uint64_t requests() const { return requests_.load(); }  // answered (including exceptions)
  int clients() const { return clients_.load(); }              // connected now

  // The server thread's loop, until `running` is false; then it closes every client.
  void serve(const std::atomic<bool>& running) noexcept;
  void close_listener();

 private:
  ModuleServer(const Setup& setup, ModuleRegisters& registers, const InjectedFaults& faults, MasterActivity& activity)
      : setup_(setup), registers_(registers), faults_(faults), activity_(activity) {}
  bool serve_request(int fd, std::uint8_t* query) noexcept;
  bool writes_valve(const std::uint8_t* query, int length) const noexcept;
  void accept_client() noexcept;

  const Setup setup_;
  ModuleRegisters& registers_;
  const InjectedFaults& faults_;
  MasterActivity& activity_;
  modbus_t* ctx_ = nullptr;  // the server thread's alone once started
  int listen_fd_ = -1;
  int bound_port_ = 0;
  std::vector<int> client_fds_;  // the server thread's; reserved in listen(), so it never allocates
  std::atomic<std::uint64_t> requests_{0};
  std::atomic<int> clients_{0};
};

}  // namespace epa::rig
