// The loop's channels under real concurrency: readers never see a torn snapshot, commands arrive
// whole and in order, a full queue refuses instead of blocking.
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <thread>

#include "runtime/command_queue.hpp"
#include "runtime/seqlock.hpp"

namespace epa::runtime {
namespace {

// 64 words that the writer always sets to the same number: a torn copy mixes two numbers. Big
// enough that an unprotected copy tears often (checked by breaking the retry: this test fails).
struct Block {
  std::array<std::uint64_t, 64> words{};
};

TEST(SeqlockCell, ReadersNeverSeeATornValue) {
  SeqlockCell<Block> cell;
  std::atomic<bool> reader_done{false};
  std::atomic<std::uint64_t> published{0};
  std::atomic<std::uint64_t> reads_finished{0};
  // The writer publishes flat out (what tears an unprotected copy) until the reader has not
  // finished a read for 64 publishes, then waits for one: without that pause it starved the
  // reader's retries under ThreadSanitizer (199 reads finished in 10 s).
  std::thread writer([&] {
    Block b;
    std::uint64_t reads_seen = 0, publishes_since_a_read = 0;
    for (std::uint64_t i = 1; !reader_done.load(std::memory_order_relaxed); ++i) {
      b.words.fill(i);
      cell.publish(b);
      published.store(i, std::memory_order_relaxed);
      const auto reads_now = reads_finished.load(std::memory_order_relaxed);
      publishes_since_a_read = reads_now == reads_seen ? publishes_since_a_read + 1 : 0;
      reads_seen = reads_now;
      while (publishes_since_a_read >= 64 && reads_finished.load(std::memory_order_relaxed) == reads_seen &&
             !reader_done.load(std::memory_order_relaxed)) {
      }
    }
  });
  while (published.load() == 0) {
  }
  // Read flat out (a yield here hides tearing: a reader that never retries then passes) until 200
  // different values have been seen, bounded to 10 s for a loaded 2-core machine.
  std::uint64_t last = 0, changes = 0, reads = 0;
  bool torn = false, went_back = false;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!torn && !went_back && changes < 200 && std::chrono::steady_clock::now() < give_up) {
    const Block b = cell.read();
    reads_finished.store(++reads, std::memory_order_relaxed);
    for (std::uint64_t w : b.words) torn = torn || w != b.words[0];
    went_back = b.words[0] < last;
    changes += b.words[0] != last;
    last = b.words[0];
  }
  reader_done = true;
  writer.join();
  EXPECT_FALSE(torn) << "torn read after " << reads << " reads";
  EXPECT_FALSE(went_back) << "a read went back in time after " << reads << " reads";
  EXPECT_GE(changes, 200u);  // the reads really did run against a moving writer
}

TEST(CommandQueue, DeliversInOrderAndRefusesWhenFull) {
  CommandQueue<int, 4> q;
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(q.try_push(i));
  EXPECT_FALSE(q.try_push(99));
  int v = -1;
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(q.try_pop(v));
    EXPECT_EQ(v, i);
  }
  EXPECT_FALSE(q.try_pop(v));
}

TEST(CommandQueue, AGroupIsPushedWholeOrNotAtAll) {
  CommandQueue<int, 8> q;
  const int group[] = {1, 2, 3, 4, 5};
  EXPECT_TRUE(q.try_push_all(group, 5));
  EXPECT_FALSE(q.try_push_all(group, 5));  // 3 free slots: nothing of the group goes in
  int v = 0, count = 0;
  while (q.try_pop(v)) ++count;
  EXPECT_EQ(count, 5);
}

TEST(CommandQueue, AConcurrentConsumerNeverSeesHalfAGroup) {
  CommandQueue<int, 64> q;
  std::atomic<bool> done{false};
  std::thread producer([&] {
    const int group[] = {1, 2, 3};
    for (int i = 0; i < 20000;) i += q.try_push_all(group, 3) ? 1 : 0;
    done = true;
  });
  int v = 0, expected = 1, received = 0;
  for (;;) {
    const bool finished = done.load();  // read before draining: after it, one drain gets the rest
    // Drain what is visible now, as the scan cycle does: a group must never end mid-way.
    while (q.try_pop(v)) {
      ASSERT_EQ(v, expected);
      expected = expected % 3 + 1;
      ++received;
    }
    ASSERT_EQ(expected, 1) << "a drain ended inside a group";
    if (finished) break;
  }
  producer.join();
  EXPECT_EQ(received, 60000);
}

TEST(CommandQueue, ManyProducersOneConsumerLoseNothing) {
  CommandQueue<std::uint64_t, 64> q;
  constexpr int kProducers = 4, kEach = 20000;
  std::vector<std::thread> producers;
  for (int p = 0; p < kProducers; ++p)
    producers.emplace_back([&, p] {
      for (int i = 0; i < kEach;)
        if (q.try_push(static_cast<std::uint64_t>(p) * 1'000'000 + static_cast<std::uint64_t>(i))) ++i;
    });
  std::vector<int> next(kProducers, 0);
  int received = 0;
  std::uint64_t v = 0;
  while (received < kProducers * kEach) {
    if (!q.try_pop(v)) continue;
    const auto p = static_cast<int>(v / 1'000'000);
    ASSERT_EQ(static_cast<int>(v % 1'000'000), next[static_cast<std::size_t>(p)]++);  // per-producer order kept
    ++received;
  }
  for (auto& t : producers) t.join();
}

}  // namespace
}  // namespace epa::runtime
