// The random policy: deterministic by the rng's seed, never on a blocked or unreachable cell.
#include <catch2/catch.hpp>
#include <cmath>

#include "policy_fixture.h"

using namespace crunch;
using namespace crunch::exploration;
using crunch::exploration::testing::PolicyWorld;

TEST_CASE("random policy: same seed same poses, never blocked, never unreachable",
          "[exploration]") {
  PolicyWorld w({4, 2});
  for (double y = 0.025; y < 2.0; y += 0.05) w.known.markContact({2.0, y});  // closed wall
  auto a = makeRandomPolicy(PolicyOptions{});
  auto b = makeRandomPolicy(PolicyOptions{});
  Rng ra(7), rb(7);
  const Pose2 robot{1.0, 1.0, 0};
  double min_x = 1e9, max_x = -1e9;
  for (int i = 0; i < 200; ++i) {
    const auto da = a->next(w.state(robot), ra);
    const auto db = b->next(w.state(robot), rb);
    REQUIRE(da.goal);
    REQUIRE(db.goal);
    CHECK(da.goal->x == db.goal->x);
    CHECK(da.goal->y == db.goal->y);
    CHECK(da.goal->theta == db.goal->theta);
    CHECK_FALSE(w.costmap->blocked(da.goal->position()));
    CHECK(std::isfinite(w.field->to(da.goal->position())));
    CHECK(da.goal->x < 2.0);  // the other room is behind a closed wall
    min_x = std::min(min_x, da.goal->x);
    max_x = std::max(max_x, da.goal->x);
  }
  CHECK(max_x - min_x > 1.0);  // it does spread over the room
}

TEST_CASE("random policy: a boxed-in robot gets no goal and a reason", "[exploration]") {
  PolicyWorld w({0.3, 0.3});  // narrower than the robot's inflated disc: nowhere to stand
  auto p = makeRandomPolicy(PolicyOptions{});
  Rng rng(1);
  const auto d = p->next(w.state({0.5, 0.5, 0}), rng);
  CHECK_FALSE(d.goal);
  CHECK(d.why.find("boxed in") != std::string::npos);
}
