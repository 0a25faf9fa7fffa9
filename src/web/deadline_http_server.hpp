#pragma once
// cpp-httplib's server behind an event-driven front end. httplib serves a connection on one
// worker from its first byte to its last, so a crowd of clients that send their request a byte at a
// time held every worker and the page starved (84 % of polls within 1 s at 512 slow connections, 23 %
// at 1000). Here one thread accepts every connection and reads every request into memory; a worker
// (from new_task_queue) gets a connection only once a whole request has arrived, runs httplib's
// parsing, routing and answer on it (its protected process_request), and hands the connection back.
// So a slow or silent connection costs a descriptor and a buffer, never a worker. The same holds
// the other way: a worker writes its answer into memory and sends what the socket takes at once;
// the rest the front end writes as the client reads, within `write_timeout`, or it closes the
// connection. A client that never reads its answers (3,000 of them held every worker blocked in
// send and starved the page) costs a buffer, not a worker.
//
// Bounds: a request's head and body arrive within `request_deadline` of its first byte (else 408),
// a request past `max_request_bytes` is cut unread (431), a head of more than `max_header_fields`
// fields is refused (431), a connection waits `read_timeout` for its first request and
// `keep_alive_timeout` for each next one, an address holds at most `max_connections_per_address`
// connections (more are closed at once), and all connections together at most `max_connections`.
// Refused connections and a full descriptor table are logged once a minute with a count.
//
// With use_tls() the port speaks HTTPS only (front_end_tls.hpp): each connection's handshake is
// driven by the front end a step at a time and must be complete within `handshake_timeout`; a
// connection over the caps is closed without an answer (there is no session to answer in); a
// request's bytes are decrypted into its buffer and its answer encrypted as the client reads it.
// A handler finds the client's session, and so its certificate, in Request::ssl.
#include <httplib.h>

#include <chrono>
#include <cstddef>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace epa::web {

class FrontEndTls;

struct RequestLimits {
  std::chrono::milliseconds request_deadline{2000};    // first byte of a request -> its last byte
  std::chrono::milliseconds read_timeout{2000};        // a new connection waits this long for its first byte
  std::chrono::milliseconds handshake_timeout{2000};   // HTTPS: a new connection's TLS handshake is complete within this
  std::chrono::milliseconds write_timeout{2000};       // an answer must be taken by the client within this
  std::chrono::milliseconds keep_alive_timeout{2000};  // a kept-alive connection waits this long for the next request
  std::size_t keep_alive_max_requests = 100;
  std::size_t max_request_bytes = 64 * 1024;  // head and body; a larger request is cut, not read
  std::size_t max_header_fields = 64;         // a head with more fields is refused (431)
  std::size_t max_connections_per_address = 32;
  std::size_t max_connections = 4096;  // all addresses together (also bounded by the descriptor limit)
};

class DeadlineHttpServer final : public httplib::Server {
 public:
  using Log = std::function<void(const std::string&)>;
  // Headers added to the front end's own answers (408, 431, 503), as httplib's default headers are to its.
  explicit DeadlineHttpServer(const RequestLimits& limits, Log log = {}, httplib::Headers answer_headers = {});
  ~DeadlineHttpServer() override;

  // HTTPS only on the port, with `tls`; before serve_after_bind.
  void use_tls(std::unique_ptr<FrontEndTls> tls);
  // Serves the socket bound by bind_to_port/bind_to_any_port until stop_serving(); call on its own
  // thread (in place of httplib's listen_after_bind). False if it could not start.
  bool serve_after_bind();
  // Ends serve_after_bind: the listening socket and every connection are closed, workers joined.
  void stop_serving();
  bool serving() const;
  // True while the serving thread answers its own warm-up request (before any client's): a
  // handler that counts requests leaves it out.
  bool warming_up() const { return warming_up_; }
  std::size_t connections() const;  // open now (front end and workers)

  struct Connection;  // one client's socket, its unread bytes and its deadline (in the .cpp)

 private:
  void warm_up();  // one request on the serving thread before the workers start (in the .cpp)
  bool warming_up_ = false;  // written and read on the serving thread before the workers exist
  struct Front;
  // A worker: answers the whole request(s) buffered on `c`, then hands it back to the front end.
  void answer(std::shared_ptr<Connection> c);
  void hand_back(std::shared_ptr<Connection> c, bool close);
  // The front end's steps (its thread only).
  void accept_waiting(int listen_fd);
  void admit(int fd, const std::string& peer);
  void read_from(int fd);
  // These take the connection by value: each may erase the `waiting` entry it was called with,
  // and a reference to that entry's pointer would then dangle (a client that reset its connection
  // while its answer was being written crashed the appliance).
  bool shake_hands(std::shared_ptr<Connection> c);  // HTTPS: false when the connection was closed
  void write_to(std::shared_ptr<Connection> c);  // the rest of an answer, as the client reads it
  void wait_for_request(std::shared_ptr<Connection> c);  // back to reading: the next request
  void dispatch(std::shared_ptr<Connection> c);
  void take_back();
  void end_waits(int listen_fd);

  RequestLimits limits_;
  Log log_;
  httplib::Headers answer_headers_;
  std::unique_ptr<FrontEndTls> tls_;  // null: plain HTTP
  std::unique_ptr<Front> front_;
};

}  // namespace epa::web
