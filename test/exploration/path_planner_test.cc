// The A* planner and distance field (crunch/exploration/path_planner.h) on small grids.
#include "crunch/exploration/path_planner.h"

#include <catch2/catch.hpp>
#include <cmath>

using namespace crunch;
using namespace crunch::exploration;

namespace {
// A 4 x 2 m room split at x = 2 by a wall with a 0.6 m doorway at y in [1.2, 1.8].
KnownSpace wallWithDoor() {
  KnownSpace k({0, 0}, {4, 2}, 0.05);
  for (double y = 0.025; y < 2.0; y += 0.05) {
    if (y > 1.2 && y < 1.8) continue;
    k.markContact({2.0, y});
  }
  return k;
}
// Smallest distance from p to any occupied cell's centre.
double clearance(const KnownSpace& k, const Vec2& p) {
  double best = 1e9;
  for (int iy = 0; iy < k.ny(); ++iy)
    for (int ix = 0; ix < k.nx(); ++ix)
      if (k.at(ix, iy) == KnownSpace::Cell::kOccupied) best = std::min(best, (k.centre(ix, iy) - p).norm());
  return best;
}
}  // namespace

TEST_CASE("planPath: goes through the doorway and keeps the robot's disc off the wall",
          "[exploration]") {
  const KnownSpace k = wallWithDoor();
  const PlannerOptions o;
  const Costmap cm(k, o);
  const auto plan = planPath(cm, {1.0, 0.5}, {3.0, 0.5});
  REQUIRE(plan);
  REQUIRE_FALSE(plan->waypoints.empty());
  CHECK((plan->waypoints.back() - Vec2(3.0, 0.5)).norm() < 1e-12);
  // Crossing x = 2 happens inside the doorway.
  Vec2 prev(1.0, 0.5);
  bool crossed = false;
  for (const Vec2& w : plan->waypoints) {
    // Every point along the path keeps radius + margin (less half a cell of discretisation)
    // from every occupied cell: the inflation.
    for (double t = 0; t <= 1.0; t += 0.02) {
      const Vec2 p = prev + t * (w - prev);
      CHECK(clearance(k, p) >= o.robot_radius + o.margin - 0.5 * k.cell() * std::sqrt(2.0));
      if (!crossed && p.x() >= 2.0) {
        crossed = true;
        CHECK(p.y() > 1.2);
        CHECK(p.y() < 1.8);
      }
    }
    prev = w;
  }
  CHECK(crossed);
  // Longer than the straight line, shorter than a generous detour bound.
  CHECK(plan->length > 2.0);
  CHECK(plan->length < 2.0 * std::hypot(1.0, 1.0) + 0.5);
  CHECK(plan->length <= plan->cost + 1e-9);
}

TEST_CASE("planPath: a closed wall makes the goal unreachable, a blocked goal too",
          "[exploration]") {
  KnownSpace k({0, 0}, {4, 2}, 0.05);
  for (double y = 0.025; y < 2.0; y += 0.05) k.markContact({2.0, y});
  const Costmap cm(k, PlannerOptions{});
  CHECK_FALSE(planPath(cm, {1.0, 0.5}, {3.0, 0.5}));
  CHECK_FALSE(planPath(cm, {1.0, 0.5}, {2.0, 0.5}));  // on the wall
  CHECK(planPath(cm, {1.0, 0.5}, {1.0, 1.5}));         // same side
}

TEST_CASE("DistanceField: equals planPath's search cost to every goal", "[exploration]") {
  KnownSpace k = wallWithDoor();
  k.markFreeRay({Vec2(0.3, 1.0), Vec2(3.7, 1.0)});  // some free cells: two cost rates
  const Costmap cm(k, PlannerOptions{});
  const Vec2 from(0.6, 0.4);
  const DistanceField field(cm, from);
  for (const Vec2& goal : {Vec2(3.0, 0.5), Vec2(1.5, 1.5), Vec2(3.5, 1.6), Vec2(0.6, 0.45)}) {
    const auto plan = planPath(cm, from, goal);
    REQUIRE(plan);
    CHECK(field.to(goal) == Approx(plan->cost).margin(1e-9));
  }
  CHECK(std::isinf(field.to(Vec2(2.0, 0.5))));  // on the wall
}

TEST_CASE("planPath: unknown cells cost more, so known free space is preferred", "[exploration]") {
  KnownSpace k({0, 0}, {3, 3}, 0.05);
  const Costmap cm(k, PlannerOptions{});
  const auto unknown = planPath(cm, {0.5, 0.5}, {2.5, 0.5});
  REQUIRE(unknown);
  CHECK(unknown->cost == Approx(2.0 * 1.5).margin(1e-9));
  k.markFreeRay({Vec2(0.5, 0.5), Vec2(2.5, 0.5)});
  const Costmap cm2(k, PlannerOptions{});
  const auto known = planPath(cm2, {0.5, 0.5}, {2.5, 0.5});
  REQUIRE(known);
  CHECK(known->cost < unknown->cost);
}

TEST_CASE("planPath: a start inside an inflated obstacle leaves it", "[exploration]") {
  KnownSpace k({0, 0}, {3, 3}, 0.05);
  k.markBump({1.5, 1.6});  // the robot at (1.5, 1.5) just bumped it
  const Costmap cm(k, PlannerOptions{});
  REQUIRE(cm.blocked(Vec2(1.5, 1.5)));
  const auto plan = planPath(cm, {1.5, 1.5}, {1.5, 0.5});
  REQUIRE(plan);
  CHECK(plan->waypoints.back().y() == Approx(0.5));
}

TEST_CASE("PlannerOptions: bad values are named", "[exploration]") {
  PlannerOptions o;
  CHECK(o.validate());
  o.margin = -0.1;
  REQUIRE_FALSE(o.validate());
  CHECK(o.validate().error().message.find("margin") != std::string::npos);
  o = PlannerOptions{};
  o.unknown_cost = 0.5;
  CHECK_FALSE(o.validate());
}
