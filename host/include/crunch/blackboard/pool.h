// A pool of records addressed by stable integer ids, with a free list: acquiring and releasing
// does not allocate once the pool has reached its high-water mark (STYLE.md item 5).
// Ids stay valid until released; a released id is reused by a later acquire. Not thread-safe.
#pragma once

#include <cassert>
#include <cstdint>
#include <vector>

namespace crunch {

template <typename T>
class Pool {
 public:
  explicit Pool(size_t reserve = 0) { reserve_(reserve); }

  // Returns the id of a value-initialised record.
  int32_t acquire() {
    if (!free_.empty()) {
      const int32_t id = free_.back();
      free_.pop_back();
      items_[static_cast<size_t>(id)] = T{};
      return id;
    }
    items_.emplace_back();
    return static_cast<int32_t>(items_.size() - 1);
  }

  void release(int32_t id) {
    assert(id >= 0 && static_cast<size_t>(id) < items_.size());
    free_.push_back(id);
  }

  // Releases every record; keeps the capacity.
  void reset() {
    items_.clear();
    free_.clear();
  }

  T& operator[](int32_t id) { return items_[static_cast<size_t>(id)]; }
  const T& operator[](int32_t id) const { return items_[static_cast<size_t>(id)]; }
  // Ids in [0, extent()) have been acquired at some point; check the record for liveness.
  int32_t extent() const { return static_cast<int32_t>(items_.size()); }
  size_t capacity() const { return items_.capacity(); }

 private:
  void reserve_(size_t n) {
    items_.reserve(n);
    free_.reserve(n);
  }
  std::vector<T> items_;
  std::vector<int32_t> free_;
};

}  // namespace crunch
