// Tests of the lock-free SPSC ring (crunch/io/spsc_ring.h): FIFO order, capacity, drop-newest
// overflow with its counters, highWater(), drain(), and one producer and one consumer thread
// racing through a small ring. The no-allocation checks are in io_ring_alloc_test.cc (their own
// executable: count_allocations.h replaces operator new).
#include <catch2/catch.hpp>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>
#include <vector>

#include "crunch/io/spsc_ring.h"

using crunch::io::SpscRing;

TEST_CASE("SpscRing: elements come out in the order they went in", "[io][ring]") {
  SpscRing<int> ring(8);
  CHECK(ring.capacity() == 8);
  CHECK(ring.size() == 0);
  int out = -1;
  CHECK_FALSE(ring.tryPop(out));  // empty
  CHECK(out == -1);               // untouched when empty
  // Many times round the ring, with the queue length varying, so the indices wrap.
  int next_in = 0, next_out = 0;
  for (int round = 0; round < 50; ++round) {
    const int push = 1 + round % 8;
    for (int i = 0; i < push; ++i) REQUIRE(ring.tryPush(next_in++));
    CHECK(ring.size() == static_cast<std::size_t>(push));
    for (int i = 0; i < push; ++i) {
      REQUIRE(ring.tryPop(out));
      CHECK(out == next_out++);
    }
    CHECK_FALSE(ring.tryPop(out));
  }
  CHECK(ring.pushed() == static_cast<std::uint64_t>(next_in));
  CHECK(ring.dropped() == 0);
}

TEST_CASE("SpscRing: holds exactly its power-of-two capacity", "[io][ring]") {
  for (const std::size_t cap : {std::size_t{2}, std::size_t{4}, std::size_t{64}, std::size_t{1024}}) {
    SpscRing<std::uint32_t> ring(cap);
    CHECK(ring.capacity() == cap);
    for (std::size_t i = 0; i < cap; ++i) REQUIRE(ring.tryPush(static_cast<std::uint32_t>(i)));
    CHECK(ring.size() == cap);
    CHECK_FALSE(ring.tryPush(999));
    CHECK(ring.dropped() == 1);
    CHECK(ring.pushed() == cap);
  }
}

TEST_CASE("SpscRing: a full ring refuses the newest and keeps what is queued", "[io][ring]") {
  SpscRing<int> ring(4);
  for (int i = 0; i < 4; ++i) REQUIRE(ring.tryPush(i));
  // Three refused: counted, the queue unchanged.
  CHECK_FALSE(ring.tryPush(100));
  CHECK_FALSE(ring.tryPush(101));
  CHECK_FALSE(ring.tryPush(102));
  CHECK(ring.dropped() == 3);
  CHECK(ring.pushed() == 4);
  CHECK(ring.size() == 4);
  int out = -1;
  REQUIRE(ring.tryPop(out));
  CHECK(out == 0);
  // One slot free again: the next push is taken, and goes after the queued ones.
  CHECK(ring.tryPush(200));
  CHECK_FALSE(ring.tryPush(201));
  CHECK(ring.dropped() == 4);
  CHECK(ring.pushed() == 5);
  std::vector<int> rest;
  while (ring.tryPop(out)) rest.push_back(out);
  CHECK(rest == std::vector<int>{1, 2, 3, 200});
}

TEST_CASE("SpscRing: highWater is the most ever queued at once", "[io][ring]") {
  SpscRing<int> ring(16);
  CHECK(ring.highWater() == 0);
  int out = 0;
  for (int i = 0; i < 5; ++i) ring.tryPush(i);
  CHECK(ring.highWater() == 5);
  for (int i = 0; i < 5; ++i) ring.tryPop(out);
  CHECK(ring.highWater() == 5);  // not lowered by popping
  for (int i = 0; i < 3; ++i) ring.tryPush(i);
  CHECK(ring.highWater() == 5);  // 3 < 5
  for (int i = 0; i < 13; ++i) ring.tryPush(i);
  CHECK(ring.size() == 16);
  CHECK(ring.highWater() == 16);
  CHECK_FALSE(ring.tryPush(0));
  CHECK(ring.highWater() == 16);  // a refused push is not queued
}

TEST_CASE("SpscRing: drain visits the queued elements oldest first and frees their slots",
          "[io][ring]") {
  SpscRing<int> ring(8);
  // Start part-way round so the drained range wraps.
  int out = 0;
  for (int i = 0; i < 6; ++i) ring.tryPush(-1);
  for (int i = 0; i < 6; ++i) ring.tryPop(out);
  for (int i = 0; i < 7; ++i) REQUIRE(ring.tryPush(10 + i));
  std::vector<int> seen;
  const std::size_t n = ring.drain([&](const int& v) { seen.push_back(v); });
  CHECK(n == 7);
  CHECK(seen == std::vector<int>{10, 11, 12, 13, 14, 15, 16});
  CHECK(ring.size() == 0);
  CHECK_FALSE(ring.tryPop(out));
  // Every slot is free again.
  for (int i = 0; i < 8; ++i) CHECK(ring.tryPush(i));
  CHECK_FALSE(ring.tryPush(8));
  CHECK(ring.drain([](const int&) {}) == 8);
  CHECK(ring.drain([](const int&) {}) == 0);  // empty: f is not called
}

TEST_CASE("SpscRing: each slot is freed as soon as drain's callback returns", "[io][ring]") {
  // The consumer owns tail_: while f runs for element k, the slots of elements before k are
  // already free, so size() (exact from the consumer's own thread) counts down.
  SpscRing<int> ring(4);
  for (int i = 0; i < 4; ++i) ring.tryPush(i);
  std::vector<std::size_t> sizes;
  ring.drain([&](const int&) { sizes.push_back(ring.size()); });
  CHECK(sizes == std::vector<std::size_t>{4, 3, 2, 1});
}

namespace {
// A payload that is torn if its halves do not match: the number, its complement and a checksum.
struct Item {
  std::uint64_t seq = 0;
  std::uint64_t inverse = ~std::uint64_t{0};
  std::uint64_t mixed = 0;
  std::uint64_t pad[5] = {};  // 64 bytes: a copy takes several stores

  static std::uint64_t mix(std::uint64_t s) { return (s * 0x9E3779B97F4A7C15ull) ^ (s >> 7); }
  static Item of(std::uint64_t s) {
    Item it;
    it.seq = s;
    it.inverse = ~s;
    it.mixed = mix(s);
    for (auto& p : it.pad) p = s + 1;
    return it;
  }
  bool whole() const {
    if (inverse != ~seq || mixed != mix(seq)) return false;
    for (const auto p : pad)
      if (p != seq + 1) return false;
    return true;
  }
};
}  // namespace

TEST_CASE("SpscRing: two threads, 2 million items through 64 slots, none torn, none duplicated",
          "[io][ring][threads]") {
  constexpr std::uint64_t kItems = 2'000'000;
  SpscRing<Item> ring(64);
  std::atomic<bool> consumer_ready{false}, producer_done{false}, timed_out{false};
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  std::uint64_t produced = 0, refused = 0;
  // Which sequence numbers the ring accepted (producer's record) and which arrived (consumer's).
  std::vector<std::uint8_t> accepted(kItems, 0), arrived(kItems, 0);

  // Each item is offered once. Seven in eight wait (bounded) for a free slot first, so most
  // items really cross between the threads; every eighth is offered at once and is refused if
  // the ring is full at that moment: the drop-newest path, racing the consumer.
  std::thread producer([&] {
    while (!consumer_ready.load(std::memory_order_acquire)) std::this_thread::yield();
    for (std::uint64_t s = 0; s < kItems; ++s) {
      if (s % 8 != 0) {
        while (ring.size() >= ring.capacity()) {
          if (std::chrono::steady_clock::now() > deadline) {
            timed_out.store(true);
            break;
          }
          std::this_thread::yield();
        }
      }
      ++produced;
      if (ring.tryPush(Item::of(s))) {
        accepted[s] = 1;
      } else {
        ++refused;
      }
    }
    producer_done.store(true, std::memory_order_release);
  });

  // The consumer: this thread. Alternates tryPop and drain so both paths race the producer.
  std::uint64_t received = 0, torn = 0, out_of_order = 0;
  std::int64_t last = -1;
  auto take = [&](const Item& it) {
    if (!it.whole()) ++torn;
    if (static_cast<std::int64_t>(it.seq) <= last) ++out_of_order;  // duplicate or reordered
    last = static_cast<std::int64_t>(it.seq);
    if (it.seq < kItems) ++arrived[it.seq];
    ++received;
  };
  consumer_ready.store(true, std::memory_order_release);
  Item it;
  for (std::uint64_t round = 0;; ++round) {
    const bool done = producer_done.load(std::memory_order_acquire);
    if (round % 2 == 0) {
      while (ring.tryPop(it)) take(it);
    } else {
      ring.drain(take);
    }
    // After the producer finished, one more full pass empties the ring.
    if (done) {
      while (ring.tryPop(it)) take(it);
      break;
    }
    if (std::chrono::steady_clock::now() > deadline) break;
  }
  const bool finished = producer_done.load();
  producer.join();
  REQUIRE(finished);  // else the deadline passed: the consumer was starved or stuck
  REQUIRE_FALSE(timed_out.load());

  INFO("dropped " << ring.dropped() << " of " << kItems << ", high water " << ring.highWater());
  CHECK(torn == 0);
  CHECK(out_of_order == 0);
  CHECK(produced == kItems);
  CHECK(ring.pushed() + ring.dropped() == produced);
  CHECK(ring.dropped() == refused);
  CHECK(received == ring.pushed());  // every accepted item arrived, exactly once
  CHECK(accepted == arrived);  // exactly the accepted ones, each once; the refused ones never
  CHECK(ring.size() == 0);
  CHECK(ring.pushed() >= kItems / 8 * 7);  // the waiting seven in eight all crossed
  CHECK(ring.highWater() <= 64);
  CHECK(ring.highWater() >= 1);
  WARN("two-thread ring: " << ring.pushed() << " crossed, " << ring.dropped()
                           << " dropped, high water " << ring.highWater());
}
