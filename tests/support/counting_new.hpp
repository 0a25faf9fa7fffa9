#pragma once
// Replaces the global operator new/delete of the test executable that includes this header (in
// exactly one of its .cpp files) with versions that count allocations and forward to malloc, so
// a test can prove that a code path allocates nothing: allocation_count() before and after.
#include <atomic>
#include <cstdlib>
#include <new>

namespace epa::testing {
inline std::atomic<long> g_allocation_count{0};
inline long allocation_count() { return g_allocation_count.load(std::memory_order_relaxed); }
}  // namespace epa::testing

// Not inlined, neither new nor delete: g++ otherwise sees malloc() in one and free() in the other
// and warns of a mismatch that is not one (-Wmismatched-new-delete, at -O2, and at -O1 with the
// sanitizers).
[[gnu::noinline]] void* operator new(std::size_t size) {
  epa::testing::g_allocation_count.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
[[gnu::noinline]] void* operator new[](std::size_t size) { return operator new(size); }
[[gnu::noinline]] void operator delete(void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
