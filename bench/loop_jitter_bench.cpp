// The scan cycle in real time: the real loop (MonotonicClock, absolute deadlines, SCHED_FIFO and
// mlockall when allowed) against the sim backend, closed loop with setpoint changes every 2 s, for
// a fixed time. Prints one JSON line of wake-up latency, period jitter, compute time and overruns.
// bench/jitter_vs_cyclictest.sh runs it next to cyclictest.
#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <thread>

#include "control/paper_controller.hpp"
#include "core/paper_reference.hpp"
#include "hal/sim_daq.hpp"
#include "runtime/clock.hpp"
#include "hal/realtime.hpp"
#include "runtime/scan_cycle.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Scan-cycle timing benchmark"};
  int period_us = 1000, priority = 80;
  double seconds = 60.0;
  app.add_option("--period-us", period_us, "Scan period, us")->capture_default_str();
  app.add_option("--seconds", seconds, "How long to run")->capture_default_str();
  app.add_option("--priority", priority, "SCHED_FIFO priority (0: normal)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  using namespace epa;
  auto model = core::paper::model();
  model.Ts = period_us * 1e-6;  // the paper does not print Ts; the plant runs at the loop's rate
  auto daq = *hal::SimDaq::make(model, {.noise_std_mm = 0.1});
  runtime::RuntimeConfig config;
  config.period_s = model.Ts;
  config.start_mode = runtime::Mode::kRun;
  config.start_setpoint_mm = 100.0;
  config.move_window_s = 1.0;
  config.following_error_time_s = 0.0;
  runtime::LoopChannels channels(static_cast<std::size_t>(config.record_buffer_s / config.period_s));
  runtime::MonotonicClock clock;
  runtime::ScanCycle loop(config, *runtime::make_tuning(control::paper_controller_config(control::ControllerKind::kPpFfidz)),
                          daq, clock, channels);
  std::atomic<bool> stop{false};
  std::thread loop_thread([&] {
    for (const auto& w : hal::request_realtime({.fifo_priority = priority, .lock_memory = true, .cpu_dma_latency_us = 0})) std::fprintf(stderr, "warning: %s\n", w.c_str());
    loop.run(stop);
  });
  const auto started = std::chrono::steady_clock::now();
  for (int k = 0; std::chrono::steady_clock::now() - started < std::chrono::duration<double>(seconds); ++k) {
    std::this_thread::sleep_for(std::chrono::seconds(2));
    channels.commands.try_push(runtime::setpoint_command(k % 2 ? 100.0 : 200.0));
  }
  stop = true;
  loop_thread.join();
  const auto s = loop.last_snapshot();
  // Percentiles are refreshed every 200 cycles; the loop's own stats object is final here.
  std::printf("{\"period_us\": %d, \"seconds\": %g, \"cycles\": %llu, \"wake_p50_us\": %g, \"wake_p99_us\": %g, "
              "\"wake_max_us\": %g, \"jitter_p50_us\": %g, \"jitter_p99_us\": %g, \"jitter_max_us\": %g, "
              "\"compute_p50_us\": %g, \"compute_p99_us\": %g, \"compute_max_us\": %g, \"overruns\": %llu, \"moves\": %llu}\n",
              period_us, seconds, static_cast<unsigned long long>(s.loop.cycles), s.loop.wake_p50_us, s.loop.wake_p99_us,
              s.loop.wake_max_us, s.loop.jitter_p50_us, s.loop.jitter_p99_us, s.loop.jitter_max_us, s.loop.compute_p50_us,
              s.loop.compute_p99_us, s.loop.compute_max_us, static_cast<unsigned long long>(s.loop.overruns),
              static_cast<unsigned long long>(s.moves));
  return 0;
}
