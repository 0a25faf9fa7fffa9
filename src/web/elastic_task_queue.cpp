#include "web/elastic_task_queue.hpp"

namespace epa::web {

ElasticTaskQueue::ElasticTaskQueue(std::size_t min_threads, std::size_t max_threads, std::chrono::milliseconds idle_exit)
    : min_threads_(min_threads), max_threads_(std::max(max_threads, min_threads)), idle_exit_(idle_exit) {}

ElasticTaskQueue::~ElasticTaskQueue() { shutdown(); }

std::size_t ElasticTaskQueue::threads() const {
  std::lock_guard lock(mutex_);
  return workers_.size() - ended_.size();
}

void ElasticTaskQueue::reap() {
  for (auto it : ended_) {
    it->join();
    workers_.erase(it);
  }
  ended_.clear();
}

void ElasticTaskQueue::enqueue(std::function<void()> fn) {
  std::lock_guard lock(mutex_);
  if (stop_) return;
  reap();
  jobs_.push_back(std::move(fn));
  if (idle_ >= jobs_.size() || workers_.size() >= max_threads_) {
    wake_.notify_one();  // an idle worker takes it, or it waits for the first one free
    return;
  }
  workers_.emplace_back();
  auto self = std::prev(workers_.end());
  *self = std::thread([this, self] { work(self); });
}

void ElasticTaskQueue::work(std::list<std::thread>::iterator self) {
  std::unique_lock lock(mutex_);
  for (;;) {
    ++idle_;
    const bool woke = wake_.wait_for(lock, idle_exit_, [this] { return stop_ || !jobs_.empty(); });
    --idle_;
    if (stop_ && jobs_.empty()) return;
    if (!woke) {
      if (workers_.size() - ended_.size() > min_threads_) {
        ended_.push_back(self);  // joined by the next enqueue or by shutdown
        return;
      }
      continue;
    }
    auto job = std::move(jobs_.front());
    jobs_.pop_front();
    lock.unlock();
    job();
    lock.lock();
  }
}

void ElasticTaskQueue::shutdown() {
  std::list<std::thread> workers;
  {
    std::lock_guard lock(mutex_);
    if (stop_ && workers_.empty()) return;
    stop_ = true;
    wake_.notify_all();
    reap();
    workers.swap(workers_);
  }
  for (auto& t : workers)
    if (t.joinable()) t.join();
}

}  // namespace epa::web
