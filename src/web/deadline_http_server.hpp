#pragma once
// cpp-httplib's server with a deadline for each whole request: httplib times out each read (5 s
// from the last byte), so a client that sends its head a byte every few seconds holds a worker
// for ever. This server serves each connection itself (keep-alive loop and socket reads; httplib
// still parses, routes and answers through its protected process_request), and a request whose
// head and body have not arrived within `request_deadline` of its first byte, or that exceeds
// `max_request_bytes` before it is answered, ends its connection unanswered.
#include <httplib.h>

#include <chrono>
#include <cstddef>

namespace epa::web {

struct RequestLimits {
  std::chrono::milliseconds request_deadline{2000};    // first byte of a request -> its last byte
  std::chrono::milliseconds read_timeout{2000};        // for a read outside a request (is_readable)
  std::chrono::milliseconds write_timeout{5000};       // per write of the answer
  std::chrono::milliseconds keep_alive_timeout{2000};  // a kept-alive connection waits this long for the next request
  std::size_t keep_alive_max_requests = 100;
  std::size_t max_request_bytes = 64 * 1024;           // head and body; a larger request is cut, not read
};

class DeadlineHttpServer final : public httplib::Server {
 public:
  explicit DeadlineHttpServer(const RequestLimits& limits) : limits_(limits) {}

 private:
  // httplib calls this (a private virtual of httplib::Server) on a worker for each accepted socket.
  bool process_and_close_socket(socket_t sock) override;

  RequestLimits limits_;
};

}  // namespace epa::web
