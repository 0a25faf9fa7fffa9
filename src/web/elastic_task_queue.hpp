#pragma once
// The web server's workers (DeadlineHttpServer hands them whole requests, one per job): a worker
// starts for each job that finds none idle, up to `max_threads`, and a worker idle for `idle_exit`
// ends, so an idle appliance keeps only `min_threads`. Workers never wait for clients (the front
// end reads requests and writes answers), so `max_threads` is a few per core: more would only
// share the CPU (web_server.hpp).
#include <httplib.h>

#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <list>
#include <mutex>
#include <thread>

namespace epa::web {

class ElasticTaskQueue final : public httplib::TaskQueue {
 public:
  ElasticTaskQueue(std::size_t min_threads, std::size_t max_threads, std::chrono::milliseconds idle_exit);
  ~ElasticTaskQueue() override;

  void enqueue(std::function<void()> fn) override;
  void shutdown() override;

  std::size_t threads() const;  // running now

 private:
  void work(std::list<std::thread>::iterator self);
  void reap();  // joins the workers that ended (under mutex_)

  const std::size_t min_threads_, max_threads_;
  const std::chrono::milliseconds idle_exit_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> jobs_;
  std::list<std::thread> workers_;
  std::vector<std::list<std::thread>::iterator> ended_;
  std::size_t idle_ = 0;
  bool stop_ = false;
};

}  // namespace epa::web
