// The grid policy: the pose list in order, blocked or unreachable poses skipped when driving,
// every pose when teleporting, then "the pose list is done".
#include <catch2/catch.hpp>

#include "policy_fixture.h"

using namespace crunch;
using namespace crunch::exploration;
using crunch::exploration::testing::PolicyWorld;

TEST_CASE("grid policy: in order, skipping a pose next to a known obstacle", "[exploration]") {
  PolicyWorld w({3, 3});
  w.grid = {{0.5, 0.5, 0}, {1.5, 1.5, 1}, {2.5, 2.5, 2}};
  w.known.markContact({1.5, 1.6});  // 0.1 m from the second pose: its centre is blocked
  auto policy = makeGridPolicy(PolicyOptions{});
  Rng rng(1);
  auto d = policy->next(w.state({0.5, 0.5, 0}), rng);
  REQUIRE(d.goal);
  CHECK(d.goal->theta == 0);
  d = policy->next(w.state({0.5, 0.5, 0}), rng);
  REQUIRE(d.goal);
  CHECK(d.goal->theta == 2);  // the blocked one skipped
  d = policy->next(w.state({2.5, 2.5, 2}), rng);
  CHECK_FALSE(d.goal);
  CHECK(d.why == "the pose list is done");
}

TEST_CASE("grid policy: teleporting takes every pose of the list", "[exploration]") {
  PolicyWorld w({3, 3});
  w.grid = {{0.5, 0.5, 0}, {1.5, 1.5, 1}, {2.5, 2.5, 2}};
  w.known.markContact({1.5, 1.6});
  auto policy = makeGridPolicy(PolicyOptions{});
  Rng rng(1);
  for (double theta : {0.0, 1.0, 2.0}) {
    const auto d = policy->next(w.state({0.5, 0.5, 0}, /*teleport=*/true), rng);
    REQUIRE(d.goal);
    CHECK(d.goal->theta == theta);
  }
}
