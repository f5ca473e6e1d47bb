// Counts heap allocations, for the tests that prove a hot loop allocates nothing after warm-up
// (ARCHITECTURE.md §3: the sampler's sweep, the frame decoder, the signal pipeline).
// It REPLACES the global operator new/delete: include it in exactly one source file of a test
// executable of its own, and read g_allocations before and after the code under test.
// g_allocations counts every thread's allocations (atomically); t_allocations the calling
// thread's own, for code under test that runs on several threads at once (the global
// inference's chains) while other threads allocate.
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

inline std::atomic<long long> g_allocations{0};
inline thread_local long long t_allocations = 0;

inline void countAllocation() {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  ++t_allocations;
}

void* operator new(std::size_t n) {
  countAllocation();
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  countAllocation();
  return std::malloc(n ? n : 1);
}
void* operator new[](std::size_t n, const std::nothrow_t& t) noexcept { return operator new(n, t); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
