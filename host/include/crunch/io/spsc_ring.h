// The circular buffer between the USB event thread and the signal pipeline (paper §2.1: "a
// circular buffer makes the samples available to the processes that extract features"): a
// lock-free single-producer single-consumer ring of fixed-size slots.
//
// Concurrency: exactly one thread calls tryPush() (the producer: the USB event thread) and
// exactly one other thread calls tryPop()/drain() (the consumer: the control loop). Each index is
// written by one side only: the producer publishes a slot with a release store of head_ after
// filling it, the consumer acquires head_ before reading the slot and releases tail_ after it is
// done, so a slot is never read while written nor overwritten while read. The counters are
// atomics readable from any thread (relaxed: they are statistics, not synchronisation).
//
// Overflow policy: drop the NEWEST. When the ring is full, tryPush() refuses the element, counts
// it in dropped(), and returns false; what is already queued is kept. Dropping the oldest would
// need the producer to move tail_, which the consumer owns; a lock-free ring cannot do that
// without racing the consumer's read of that very slot. The loss is not silent downstream
// either: a dropped USB chunk shows as a sequence gap in the bridge decoder's per-board counters.
//
// Capacity: a power of two, fixed at construction, where the slots are allocated once.
// tryPush()/tryPop() never allocate, never block and never spin: they are wait-free.
// T must be copy-assignable (slots are assigned in place).
#pragma once

#include <atomic>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>

namespace crunch::io {

template <typename T>
class SpscRing {
 public:
  // `capacity` slots, a power of two >= 2 (asserted). Allocates them here, once.
  explicit SpscRing(std::size_t capacity)
      : slots_(std::make_unique<T[]>(capacity)), mask_(capacity - 1) {
    assert(capacity >= 2 && (capacity & (capacity - 1)) == 0);
  }
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  // Producer only. Copies `item` into the next slot; false (and counted in dropped()) if full.
  bool tryPush(const T& item) {
    const std::uint64_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) > mask_) {
      dropped_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    slots_[head & mask_] = item;
    head_.store(head + 1, std::memory_order_release);
    pushed_.fetch_add(1, std::memory_order_relaxed);
    const std::uint64_t used = head + 1 - tail_.load(std::memory_order_relaxed);
    if (used > high_water_.load(std::memory_order_relaxed)) {
      high_water_.store(used, std::memory_order_relaxed);
    }
    return true;
  }

  // Consumer only. Copies the oldest element into `out`; false if the ring is empty.
  bool tryPop(T& out) {
    const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return false;
    out = slots_[tail & mask_];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  // Consumer only. Calls f(const T&) on each element queued now, oldest first, reading it in
  // place (no copy) and freeing each slot after f returns. Returns how many.
  template <typename F>
  std::size_t drain(F&& f) {
    std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    const std::uint64_t head = head_.load(std::memory_order_acquire);
    std::size_t n = 0;
    for (; tail != head; ++tail, ++n) {
      f(static_cast<const T&>(slots_[tail & mask_]));
      tail_.store(tail + 1, std::memory_order_release);
    }
    return n;
  }

  std::size_t capacity() const { return mask_ + 1; }
  // Elements queued now (exact from either side's own thread, a snapshot from others).
  std::size_t size() const {
    return static_cast<std::size_t>(head_.load(std::memory_order_acquire) -
                                    tail_.load(std::memory_order_acquire));
  }
  std::uint64_t pushed() const { return pushed_.load(std::memory_order_relaxed); }
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }
  // The most elements ever queued at once (how close the consumer came to losing data).
  std::uint64_t highWater() const { return high_water_.load(std::memory_order_relaxed); }

 private:
  // The two indices on their own cache lines: the producer writes head_, the consumer tail_.
  static constexpr std::size_t kLine = 64;
  std::unique_ptr<T[]> slots_;
  const std::uint64_t mask_;
  alignas(kLine) std::atomic<std::uint64_t> head_{0};  // next slot to fill; producer writes
  alignas(kLine) std::atomic<std::uint64_t> tail_{0};  // next slot to read; consumer writes
  alignas(kLine) std::atomic<std::uint64_t> pushed_{0};
  std::atomic<std::uint64_t> dropped_{0};
  std::atomic<std::uint64_t> high_water_{0};
};

}  // namespace crunch::io
