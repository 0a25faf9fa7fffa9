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

void* operator new(std::size_t size) {
  epa::testing::g_allocation_count.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
// Not inlined: g++ (at -O1 with sanitizers) otherwise sees free() applied to what operator new
// returned and warns of a mismatch that is not one (both sides are malloc/free).
[[gnu::noinline]] void operator delete(void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
