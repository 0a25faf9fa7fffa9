#pragma once
// cpp-httplib serves a connection on one worker from start to end, so a fixed pool of N workers
// is taken by N clients that send their request head a byte at a time (the page then answered
// nothing for 25 s behind 200 of them). This queue starts a worker for each connection that finds
// none idle, up to `max_threads`, and lets a worker that has been idle for `idle_exit` end: slow
// clients cost a thread each (512 KiB of stack, not locked, a few pages touched), never the
// service of the others, and an idle appliance keeps only `min_threads`.
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
