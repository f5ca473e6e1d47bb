// Counts heap allocations, for the tests that prove a hot loop allocates nothing after warm-up
// (ARCHITECTURE.md §3: the sampler's sweep, the frame decoder, the signal pipeline).
// It REPLACES the global operator new/delete: include it in exactly one source file of a test
// executable of its own, and read g_allocations before and after the code under test.
#pragma once

#include <cstdlib>
#include <new>

inline long long g_allocations = 0;

void* operator new(std::size_t n) {
  ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  ++g_allocations;
  return std::malloc(n ? n : 1);
}
void* operator new[](std::size_t n, const std::nothrow_t& t) noexcept { return operator new(n, t); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
