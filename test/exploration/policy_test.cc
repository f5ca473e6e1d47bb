// PolicyOptions::validate names the bad field; choosable() is every policy's test of a candidate.
#include "crunch/exploration/policy.h"

#include <catch2/catch.hpp>
#include <vector>

#include "policy_fixture.h"

using namespace crunch;
using namespace crunch::exploration;

TEST_CASE("PolicyOptions: out-of-range fields are named", "[exploration]") {
  PolicyOptions o;
  CHECK(o.validate());
  o.candidate_spacing = 0;
  REQUIRE_FALSE(o.validate());
  CHECK(o.validate().error().message.find("candidate_spacing") != std::string::npos);
  o = PolicyOptions{};
  o.candidate_headings = 65;
  CHECK_FALSE(o.validate());
  o = PolicyOptions{};
  o.samples = 0;
  CHECK_FALSE(o.validate());
}

TEST_CASE("choosable: not blocked, reachable, and not within given_up_radius of a goal given up",
          "[exploration]") {
  testing::PolicyWorld w({4, 2});
  for (double y = 0.025; y < 2.0; y += 0.05) w.known.markContact({2.0, y});  // closed wall
  const Pose2 robot{1.0, 1.0, 0};
  ExploreState s = w.state(robot);
  CHECK(choosable(s, {1.5, 1.0}));
  CHECK_FALSE(choosable(s, {2.0, 1.0}));  // on the wall: blocked
  CHECK_FALSE(choosable(s, {3.0, 1.0}));  // behind it: no path
  const std::vector<Vec2> given_up{{1.5, 1.0}};
  s.given_up = given_up;
  s.given_up_radius = 0.3;
  CHECK_FALSE(choosable(s, {1.5, 1.0}));
  CHECK_FALSE(choosable(s, {1.5, 1.29}));
  CHECK(choosable(s, {1.5, 1.31}));
  CHECK(choosable(s, {1.0, 1.0}));
  // Every policy's candidates pass through it: the random policy never picks a given-up place.
  auto random = makeRandomPolicy(PolicyOptions{});
  Rng rng(3);
  s.given_up_radius = 0.6;
  for (int i = 0; i < 200; ++i) {
    const Decision d = random->next(s, rng);
    REQUIRE(d.goal);
    CHECK((d.goal->position() - Vec2(1.5, 1.0)).norm() >= 0.6);
  }
}
