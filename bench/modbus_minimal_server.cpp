// The ceiling for a libmodbus-based Modbus TCP server, written for bench/modbus_vs_peers.sh: the
// multi-client pattern of libmodbus' own tests/bandwidth-server-many-up.c with poll() instead of
// select() (no FD_SETSIZE limit) and nothing else: a register image from modbus_mapping_new (100
// holding registers, all zero), modbus_tcp_listen on 127.0.0.1, accept, and per readable client
// modbus_receive + modbus_reply. No framing of its own, no validation, no logging per request.
// Runs until SIGTERM/SIGINT or for --seconds; prints "listening on 127.0.0.1:PORT" once bound.
#include <modbus.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <vector>

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Minimal libmodbus TCP server (the benchmark's ceiling)"};
  int port = 1502;
  double seconds = 0.0;
  app.add_option("--port", port, "TCP port on 127.0.0.1")->capture_default_str()->check(CLI::Range(1, 65535));
  app.add_option("--seconds", seconds, "Stop after this many seconds (0: run until SIGTERM/SIGINT)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  // No SA_RESTART: poll() returns EINTR on the signal and the loop sees the flag.
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);
  std::signal(SIGPIPE, SIG_IGN);  // a client gone mid-reply is an error return, not the end of the server

  modbus_t* ctx = modbus_new_tcp("127.0.0.1", port);
  if (!ctx) return std::fprintf(stderr, "modbus_new_tcp: %s\n", modbus_strerror(errno)), 1;
  modbus_mapping_t* mapping = modbus_mapping_new(0, 0, 100, 0);
  if (!mapping) return std::fprintf(stderr, "modbus_mapping_new: %s\n", modbus_strerror(errno)), modbus_free(ctx), 1;
  const int listener = modbus_tcp_listen(ctx, 64);
  if (listener < 0) {
    std::fprintf(stderr, "modbus_tcp_listen on 127.0.0.1:%d: %s\n", port, modbus_strerror(errno));
    modbus_mapping_free(mapping);
    modbus_free(ctx);
    return 1;
  }
  std::printf("listening on 127.0.0.1:%d\n", port);
  std::fflush(stdout);

  std::vector<pollfd> fds{{listener, POLLIN, 0}};  // [0] the listener, then one per client
  std::uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  unsigned long long requests = 0;
  while (!g_stop && (seconds <= 0 || std::chrono::steady_clock::now() < deadline)) {
    if (poll(fds.data(), fds.size(), 100) < 0) {
      if (errno == EINTR) continue;
      std::perror("poll");
      break;
    }
    // Clients in reverse, so closing one (swap with the last) does not skip another.
    for (std::size_t i = fds.size(); i-- > 1;) {
      if (!fds[i].revents) continue;
      modbus_set_socket(ctx, fds[i].fd);
      const int rc = modbus_receive(ctx, query);
      if (rc > 0) {
        if (modbus_reply(ctx, query, rc, mapping) >= 0) ++requests;
      } else if (rc == -1) {  // closed by the client, or an error: the connection ends
        ::close(fds[i].fd);
        fds[i] = fds.back();
        fds.pop_back();
      }  // rc == 0: a request for another unit id, ignored (libmodbus' convention)
    }
    if (fds[0].revents & POLLIN) {
      const int fd = accept(listener, nullptr, nullptr);
      if (fd >= 0) fds.push_back({fd, POLLIN, 0});
    }
  }
  for (std::size_t i = 1; i < fds.size(); ++i) ::close(fds[i].fd);
  ::close(listener);
  modbus_set_socket(ctx, -1);
  modbus_mapping_free(mapping);
  modbus_free(ctx);
  std::printf("stopped after %llu requests\n", requests);
  return 0;
}
