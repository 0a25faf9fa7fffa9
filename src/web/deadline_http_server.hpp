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
#include <map>
#include <mutex>
#include <thread>

namespace epa::web {

struct RequestLimits {
  std::chrono::milliseconds request_deadline{2000};    // first byte of a request -> its last byte
  std::chrono::milliseconds read_timeout{2000};        // for a read outside a request (is_readable)
  std::chrono::milliseconds write_timeout{5000};       // per write of the answer
  std::chrono::milliseconds keep_alive_timeout{2000};  // a kept-alive connection waits this long for the next request
  std::size_t keep_alive_max_requests = 100;
  std::size_t max_request_bytes = 64 * 1024;           // head and body; a larger request is cut, not read
};

// A connection with nothing to read (just accepted, or kept alive between requests) does not hold a
// worker: it is parked on one epoll thread until its next byte arrives, then handed to a worker
// again, or closed when its wait (read_timeout, keep_alive_timeout) ends. So 600 silent
// connections cost 600 descriptors, not 600 workers, and a poll behind them is served at once.
class DeadlineHttpServer final : public httplib::Server {
 public:
  explicit DeadlineHttpServer(const RequestLimits& limits);
  ~DeadlineHttpServer() override;

  // The queue httplib creates for its workers (from new_task_queue): where woken connections go.
  void set_task_queue(httplib::TaskQueue* queue);
  // Ends the parking: every parked connection is closed, and later ones are closed at once. Call
  // before stop(), while the task queue still exists.
  void stop_parking();

 private:
  // httplib calls this (a private virtual of httplib::Server) on a worker for each accepted socket.
  bool process_and_close_socket(socket_t sock) override;
  // Serves requests on `sock` while they come without a wait; parks it when it falls silent.
  void serve(socket_t sock, std::size_t requests_left, bool first);
  void park(socket_t sock, std::size_t requests_left, std::chrono::milliseconds wait);
  void park_loop();

  struct Parked {
    std::chrono::steady_clock::time_point until;
    std::size_t requests_left = 0;
  };
  RequestLimits limits_;
  int epoll_fd_ = -1, wake_fd_ = -1;
  bool epoll_ok_ = false;  // the parker runs; else a silent connection waits on its worker
  std::mutex mutex_;
  std::map<socket_t, Parked> parked_;
  httplib::TaskQueue* queue_ = nullptr;
  bool parking_ = true;
  std::thread parker_;
};

}  // namespace epa::web
