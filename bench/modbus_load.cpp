// Load generator for bench/modbus_vs_peers.sh: N client threads (libmodbus), each with its own
// connection to 127.0.0.1:PORT, reading `--count` holding registers (FC3) in a closed loop. All
// threads start together; requests begun in the first second (warm-up: connect, caches, the
// server's first accept) are not counted, those begun in the next --seconds are. Each latency
// goes into the thread's own histogram (1 us bins up to 100 ms, then one overflow bin; the exact
// maximum is kept aside), merged at the end. Prints one JSON line:
//   {"clients":N,"seconds":T,"requests":R,"throughput_rps":...,"p50_us":...,"p99_us":...,"max_us":...,"errors":E}
// Percentiles are the upper edge of their 1 us bin (as the scan cycle's own statistics report).
//
// Two helper modes for the script, both bounded:
//   --wait-ready S          retry connect + one FC3 read until it succeeds, at most S seconds
//                           (exit 2 if it never does); with --seconds 0 that is all it does.
//   --read-float-input A    (repeatable) read input registers A, A+1 as one float32, word order
//                           ABCD (high word first), and print {"input_A":value,...}; no load.
#include <modbus.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <bit>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "latency_tally.hpp"

namespace {

using Clock = std::chrono::steady_clock;

struct Target {
  std::string host = "127.0.0.1";
  int port = 1502;
  int unit = 1;
  int address = 0;
  int count = 10;
};

// One libmodbus client connection with a 1 s response timeout; nullptr when it cannot connect.
modbus_t* connect_client(const Target& t) {
  modbus_t* ctx = modbus_new_tcp(t.host.c_str(), t.port);
  if (!ctx) return nullptr;
  modbus_set_slave(ctx, t.unit);
  modbus_set_response_timeout(ctx, 1, 0);
  if (modbus_connect(ctx) < 0) {
    modbus_free(ctx);
    return nullptr;
  }
  return ctx;
}

// errno after a failed call: an exception answer from the server (EMBXILFUN .. EMBXGTAR)?
bool is_modbus_exception(int err) { return err >= EMBXILFUN && err <= EMBXGTAR; }

void disconnect(modbus_t*& ctx) {
  if (!ctx) return;
  modbus_close(ctx);
  modbus_free(ctx);
  ctx = nullptr;
}

// float32 in word order ABCD: the first register is the high word. Decoded here on purpose
// rather than with libmodbus' modbus_get_float_abcd (3.1.6's ABCD helpers are not trustworthy).
float decode_float_abcd(const std::uint16_t* regs) {
  const std::uint32_t bits = (static_cast<std::uint32_t>(regs[0]) << 16) | regs[1];
  return std::bit_cast<float>(bits);
}

bool wait_ready(const Target& t, double timeout_s) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  std::vector<std::uint16_t> regs(static_cast<std::size_t>(t.count));
  do {
    modbus_t* ctx = connect_client(t);
    if (ctx) {
      const int rc = modbus_read_registers(ctx, t.address, t.count, regs.data());
      disconnect(ctx);
      if (rc == t.count) return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  } while (Clock::now() < deadline);
  return false;
}

int read_floats(const Target& t, const std::vector<int>& addresses) {
  modbus_t* ctx = connect_client(t);
  if (!ctx) return std::fprintf(stderr, "modbus_load: cannot connect to %s:%d: %s\n", t.host.c_str(), t.port, modbus_strerror(errno)), 1;
  std::string json = "{";
  for (const int a : addresses) {
    std::uint16_t regs[2] = {};
    if (modbus_read_input_registers(ctx, a, 2, regs) != 2) {
      std::fprintf(stderr, "modbus_load: reading input registers %d-%d: %s\n", a, a + 1, modbus_strerror(errno));
      disconnect(ctx);
      return 1;
    }
    char item[96];
    std::snprintf(item, sizeof item, "%s\"input_%d\":%.9g", json.size() > 1 ? "," : "", a, static_cast<double>(decode_float_abcd(regs)));
    json += item;
  }
  disconnect(ctx);
  std::printf("%s}\n", json.c_str());
  return 0;
}

using LatencyTally = epa::bench::LatencyTally;

void client_thread(const Target& t, Clock::time_point measure_from, Clock::time_point measure_until, LatencyTally& r) {
  std::vector<std::uint16_t> regs(static_cast<std::size_t>(t.count));
  modbus_t* ctx = connect_client(t);
  r.connected = ctx != nullptr;
  for (Clock::time_point start = Clock::now(); start < measure_until; start = Clock::now()) {
    if (!ctx) {  // lost (or never had) the connection: count it, retry a little later
      if (start >= measure_from) ++r.errors;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      ctx = connect_client(t);
      continue;
    }
    const int rc = modbus_read_registers(ctx, t.address, t.count, regs.data());
    const auto end = Clock::now();
    if (rc != t.count) {
      // A Modbus exception answer keeps the connection; anything else (timeout, reset, an answer
      // that does not match the request) leaves the stream out of step, so it reconnects.
      if (!is_modbus_exception(errno)) disconnect(ctx);
      if (start >= measure_from) ++r.errors;
      continue;
    }
    if (start < measure_from) continue;
    r.record(start, end);
  }
  disconnect(ctx);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Modbus TCP load generator: N clients reading holding registers in a closed loop"};
  Target target;
  int clients = 1;
  double seconds = 10.0, warmup_s = 1.0, ready_timeout_s = 0.0;
  std::vector<int> float_inputs;
  app.add_option("--host", target.host, "Server address")->capture_default_str();
  app.add_option("--port", target.port, "Server TCP port")->capture_default_str()->check(CLI::Range(1, 65535));
  app.add_option("--unit", target.unit, "Unit id")->capture_default_str()->check(CLI::Range(0, 255));
  app.add_option("--address", target.address, "First holding register (0-based)")->capture_default_str()->check(CLI::Range(0, 65535));
  app.add_option("--count", target.count, "Holding registers per request")->capture_default_str()->check(CLI::Range(1, MODBUS_MAX_READ_REGISTERS));
  app.add_option("--clients", clients, "Client threads, one connection each")->capture_default_str()->check(CLI::Range(1, 256));
  app.add_option("--seconds", seconds, "Measured time after the warm-up (0: no load)")->capture_default_str()->check(CLI::Range(0.0, 3600.0));
  app.add_option("--warmup", warmup_s, "Warm-up before measuring, s")->capture_default_str()->check(CLI::Range(0.0, 60.0));
  app.add_option("--wait-ready", ready_timeout_s, "First wait until one read succeeds, at most this many seconds")->check(CLI::Range(0.0, 600.0));
  app.add_option("--read-float-input", float_inputs, "Read a float32 ABCD from input registers A, A+1 and print it (repeatable); no load");
  CLI11_PARSE(app, argc, argv);

  if (ready_timeout_s > 0 && !wait_ready(target, ready_timeout_s)) {
    std::fprintf(stderr, "modbus_load: %s:%d did not answer a read within %g s\n", target.host.c_str(), target.port, ready_timeout_s);
    return 2;
  }
  if (!float_inputs.empty()) return read_floats(target, float_inputs);
  if (seconds <= 0) return 0;

  const auto t0 = Clock::now();
  const auto measure_from = t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(warmup_s));
  const auto measure_until = measure_from + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
  std::vector<LatencyTally> results(static_cast<std::size_t>(clients));
  {
    std::vector<std::jthread> threads;
    for (auto& r : results) threads.emplace_back(client_thread, std::cref(target), measure_from, measure_until, std::ref(r));
  }

  const epa::bench::LatencySummary all(results);
  if (all.connected < clients) std::fprintf(stderr, "modbus_load: only %d of %d clients connected at first\n", all.connected, clients);
  std::printf("{\"clients\":%d,\"seconds\":%g,\"requests\":%llu,\"throughput_rps\":%s,\"p50_us\":%s,\"p99_us\":%s,\"max_us\":%s,\"errors\":%llu}\n",
              clients, seconds, static_cast<unsigned long long>(all.requests),
              epa::bench::json_number(static_cast<double>(all.requests) / seconds).c_str(),
              epa::bench::json_number(all.percentile_us(0.50), "%.0f").c_str(),
              epa::bench::json_number(all.percentile_us(0.99), "%.0f").c_str(), epa::bench::json_number(all.max_us()).c_str(),
              static_cast<unsigned long long>(all.errors));
  return all.requests > 0 ? 0 : 1;
}
