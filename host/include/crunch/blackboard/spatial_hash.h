// A uniform-grid spatial hash for parent, rival and overlap look-ups (paper §2.7, eq. 30).
// Items are integer ids at points; a query visits every id whose cell touches the query square,
// each at most once, and may visit ids farther than the radius (the caller filters by exact
// geometry). A fixed number of buckets, each holding its first kInline ids in place (one cache
// line: a look-up costs no pointer chase) and the rest in an overflow vector, so insert and
// remove do not allocate after construction unless a bucket outgrows its reserve (then it grows
// once and keeps the capacity). Not thread-safe.
#pragma once

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <vector>

#include "crunch/core/geometry.h"

namespace crunch {

class SpatialHash {
 public:
  // `cell`: cell side in metres; 2^log2_buckets buckets, each reserving `reserve` ids.
  // `cell`: cell side in metres; 2^log2_buckets buckets, each reserving `reserve` ids beyond
  // the ones it holds in place.
  SpatialHash(double cell, int log2_buckets = 12, int reserve = 0)
      : cell_(cell), mask_((1u << log2_buckets) - 1), buckets_(size_t{1} << log2_buckets) {
    if (reserve > 0)
      for (auto& b : buckets_) b.overflow.reserve(static_cast<size_t>(reserve));
  }

  void insert(int32_t id, const Vec2& p) {
    Bucket& b = buckets_[bucketOf(cellOf(p.x()), cellOf(p.y()))];
    if (b.n < kInline) b.ids[b.n] = id;
    else b.overflow.push_back(id);
    ++b.n;
  }

  // Removes `id`, which must have been inserted at `p`: the bucket's last id takes its place.
  void remove(int32_t id, const Vec2& p) {
    Bucket& b = buckets_[bucketOf(cellOf(p.x()), cellOf(p.y()))];
    int32_t* slot = nullptr;
    for (int i = 0; i < std::min(b.n, kInline); ++i)
      if (b.ids[i] == id) slot = &b.ids[i];
    for (size_t i = 0; !slot && i < b.overflow.size(); ++i)
      if (b.overflow[i] == id) slot = &b.overflow[i];
    assert(slot && "SpatialHash::remove: id not at that point");
    if (!slot) return;
    int32_t& last = b.n > kInline ? b.overflow.back() : b.ids[b.n - 1];
    *slot = last;
    if (b.n > kInline) b.overflow.pop_back();
    --b.n;
  }

  void clear() {
    for (auto& b : buckets_) {
      b.n = 0;
      b.overflow.clear();
    }
  }

  // Calls f(id) for every id in the cells touching the square of half-side `radius` around c.
  template <typename F>
  void query(const Vec2& c, double radius, F&& f) const {
    const int64_t x0 = cellOf(c.x() - radius), x1 = cellOf(c.x() + radius);
    const int64_t y0 = cellOf(c.y() - radius), y1 = cellOf(c.y() + radius);
    // Distinct cells can share a bucket; visit each bucket once. A 256-bit filter of the
    // buckets visited so far answers "not seen" without the list scan in the common case (a
    // query over a few dozen cells was spending most of its time in that scan).
    constexpr int kMaxVisited = 64;
    uint32_t visited[kMaxVisited];
    int n_visited = 0;
    uint64_t filter[4] = {0, 0, 0, 0};
    for (int64_t cx = x0; cx <= x1; ++cx) {
      for (int64_t cy = y0; cy <= y1; ++cy) {
        const uint32_t b = bucketOf(cx, cy);
        uint64_t& word = filter[(b >> 6) & 3];
        const uint64_t bit = uint64_t{1} << (b & 63);
        if (word & bit) {
          bool seen = false;
          for (int i = 0; i < n_visited; ++i) seen |= (visited[i] == b);
          if (seen) continue;
        }
        if (n_visited < kMaxVisited) {
          visited[n_visited++] = b;
          word |= bit;
        }
        const Bucket& bucket = buckets_[b];
        for (int i = 0; i < std::min(bucket.n, kInline); ++i) f(bucket.ids[i]);
        for (int32_t id : bucket.overflow) f(id);
      }
    }
  }

  double cell() const { return cell_; }

 private:
  int64_t cellOf(double v) const { return static_cast<int64_t>(std::floor(v / cell_)); }
  uint32_t bucketOf(int64_t cx, int64_t cy) const {
    const uint64_t h = static_cast<uint64_t>(cx) * 0x9E3779B97F4A7C15ull ^
                       static_cast<uint64_t>(cy) * 0xC2B2AE3D27D4EB4Full;
    return static_cast<uint32_t>(h ^ (h >> 29)) & mask_;
  }

  static constexpr int kInline = 6;
  struct Bucket {
    int n = 0;  // ids held: the first kInline in place, the rest in overflow
    int32_t ids[kInline];
    std::vector<int32_t> overflow;
  };

  double cell_;
  uint32_t mask_;
  std::vector<Bucket> buckets_;
};

}  // namespace crunch
