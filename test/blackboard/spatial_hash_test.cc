#include "crunch/blackboard/spatial_hash.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <set>
#include <utility>
#include <vector>

#include "crunch/blackboard/pool.h"
#include "crunch/core/rng.h"

using namespace crunch;

TEST_CASE("SpatialHash: radius queries agree with brute force on random points", "[blackboard]") {
  // Few buckets (2^6): many cells of a query share one, which the query must visit once. More
  // (2^10): buckets rarely repeat but their bits in the query's 256-bit filter of visited
  // buckets do, so the filter's "maybe seen" path runs and must not drop a bucket.
  const auto [log2_buckets, max_radius] = GENERATE(std::pair{6, 0.6}, std::pair{10, 0.35});
  INFO("2^" << log2_buckets << " buckets");
  Rng rng(7);
  SpatialHash hash(0.1, log2_buckets);
  std::vector<Vec2> pts;
  for (int i = 0; i < 3000; ++i) {
    pts.emplace_back(rng.uniform(-5, 25), rng.uniform(-5, 25));
    hash.insert(i, pts.back());
  }
  // Remove a third to exercise removal.
  std::vector<bool> live(pts.size(), true);
  for (int i = 0; i < 3000; i += 3) {
    hash.remove(i, pts[static_cast<size_t>(i)]);
    live[static_cast<size_t>(i)] = false;
  }
  for (int q = 0; q < 300; ++q) {
    const Vec2 c{rng.uniform(-5, 25), rng.uniform(-5, 25)};
    const double r = rng.uniform(0.01, max_radius);
    std::multiset<int> seen;
    std::set<int> got;
    hash.query(c, r, [&](int32_t id) {
      seen.insert(id);
      if ((pts[static_cast<size_t>(id)] - c).norm() <= r) got.insert(id);
    });
    std::set<int> want;
    for (size_t i = 0; i < pts.size(); ++i)
      if (live[i] && (pts[i] - c).norm() <= r) want.insert(static_cast<int>(i));
    REQUIRE(got == want);
    for (int id : seen) REQUIRE(seen.count(id) == 1);  // each id visited once
  }
}

TEST_CASE("Pool: released ids are reused without growing", "[blackboard]") {
  Pool<int> pool(4);
  const auto cap = pool.capacity();
  const int32_t a = pool.acquire(), b = pool.acquire(), c = pool.acquire();
  CHECK(a == 0);
  CHECK(b == 1);
  CHECK(c == 2);
  pool[b] = 42;
  pool.release(b);
  const int32_t d = pool.acquire();
  CHECK(d == b);
  CHECK(pool[d] == 0);  // value-initialised again
  CHECK(pool.extent() == 3);
  CHECK(pool.capacity() == cap);
}
