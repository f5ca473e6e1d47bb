// A uniform-grid spatial hash for parent, rival and overlap look-ups (paper §2.7, eq. 30).
// Items are integer ids at points; a query visits every id whose cell touches the query square,
// each at most once, and may visit ids farther than the radius (the caller filters by exact
// geometry). A fixed number of buckets, each with reserved capacity, so insert and remove do not
// allocate after construction unless a bucket outgrows its reserve (then it grows once and keeps
// the capacity). Not thread-safe.
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
  SpatialHash(double cell, int log2_buckets = 12, int reserve = 16)
      : cell_(cell), mask_((1u << log2_buckets) - 1), buckets_(size_t{1} << log2_buckets) {
    for (auto& b : buckets_) b.reserve(reserve);
  }

  void insert(int32_t id, const Vec2& p) { buckets_[bucketOf(cellOf(p.x()), cellOf(p.y()))].push_back(id); }

  // Removes `id`, which must have been inserted at `p`.
  void remove(int32_t id, const Vec2& p) {
    auto& b = buckets_[bucketOf(cellOf(p.x()), cellOf(p.y()))];
    auto it = std::find(b.begin(), b.end(), id);
    assert(it != b.end() && "SpatialHash::remove: id not at that point");
    *it = b.back();
    b.pop_back();
  }

  void clear() {
    for (auto& b : buckets_) b.clear();
  }

  // Calls f(id) for every id in the cells touching the square of half-side `radius` around c.
  template <typename F>
  void query(const Vec2& c, double radius, F&& f) const {
    const int64_t x0 = cellOf(c.x() - radius), x1 = cellOf(c.x() + radius);
    const int64_t y0 = cellOf(c.y() - radius), y1 = cellOf(c.y() + radius);
    // Distinct cells can share a bucket; visit each bucket once.
    constexpr int kMaxVisited = 64;
    uint32_t visited[kMaxVisited];
    int n_visited = 0;
    for (int64_t cx = x0; cx <= x1; ++cx) {
      for (int64_t cy = y0; cy <= y1; ++cy) {
        const uint32_t b = bucketOf(cx, cy);
        bool seen = false;
        for (int i = 0; i < n_visited; ++i) seen |= (visited[i] == b);
        if (seen) continue;
        if (n_visited < kMaxVisited) visited[n_visited++] = b;
        for (int32_t id : buckets_[b]) f(id);
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

  double cell_;
  uint32_t mask_;
  std::vector<std::vector<int32_t>> buckets_;
};

}  // namespace crunch
