#pragma once
// Work waiting for a worker, taken one item per key in turn. A FIFO queue serves a crowd from many
// addresses before the one poll that came after it: 1,500 clients pipelining requests from 50
// addresses put the page's poll behind 1,500 answers, over a second. Taken by address in turn, the
// poll waits for at most one answer per other address. Thread-safe: pushed by the front end, taken
// by workers.
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>

namespace epa::web {

template <class Item>
class RoundRobinByKey {
 public:
  void push(const std::string& key, Item item) {
    std::lock_guard lock(mutex_);
    auto [it, added] = waiting_.try_emplace(key);
    it->second.push_back(std::move(item));
    if (added) turns_.push_back(key);
    ++size_;
  }

  // The oldest item of the key whose turn it is; that key goes to the back of the turns.
  std::optional<Item> pop() {
    std::lock_guard lock(mutex_);
    if (turns_.empty()) return std::nullopt;
    const std::string key = std::move(turns_.front());
    turns_.pop_front();
    auto it = waiting_.find(key);
    Item item = std::move(it->second.front());
    it->second.pop_front();
    if (it->second.empty()) waiting_.erase(it);
    else turns_.push_back(key);
    --size_;
    return item;
  }

  std::size_t size() const {
    std::lock_guard lock(mutex_);
    return size_;
  }

 private:
  mutable std::mutex mutex_;
  std::unordered_map<std::string, std::deque<Item>> waiting_;  // by key, oldest first; no empty deques
  std::deque<std::string> turns_;                             // each key with items, once
  std::size_t size_ = 0;
};

}  // namespace epa::web
