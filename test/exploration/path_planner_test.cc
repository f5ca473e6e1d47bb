// The A* planner and distance field (crunch/exploration/path_planner.h) on small grids.
#include "crunch/exploration/path_planner.h"

#include <catch2/catch.hpp>
#include <algorithm>
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

TEST_CASE("planPath: a start inside the inflation leaves it without coming nearer the obstacle",
          "[exploration]") {
  // A leg just north of the robot, the goal beyond it: the cheapest way through the leg's
  // inflated zone hugs the leg (cells next to it); the shortest way out backs away from it.
  KnownSpace k({0, 0}, {3, 3}, 0.05);
  k.markContact({1.51, 1.61});
  const Costmap cm(k, PlannerOptions{});
  const Vec2 start{1.51, 1.46};
  const double start_clearance = clearance(k, {1.525, 1.475});  // the start cell's centre
  REQUIRE(start_clearance < PlannerOptions{}.robot_radius);
  REQUIRE(cm.blocked(start));
  const auto plan = planPath(cm, start, {1.5, 2.5});
  REQUIRE(plan);
  CHECK(plan->waypoints.back().y() == Approx(2.5));
  // Waypoints inside the inflation are the raw cell path; outside it the robot keeps the full
  // radius plus margin by construction. Either way none is nearer the leg than the start.
  for (const Vec2& w : plan->waypoints) CHECK(clearance(k, w) >= start_clearance - 1e-9);
}

TEST_CASE("planPath: a robot squeezed between a leg and the room's edge leaves by the open side",
          "[exploration]") {
  // The l_room pocket (docs/EXPLORATION.md "Leaving the inflation"): a leg to the west, the
  // region's edge to the east, a wall touched at one point to the north. The goal is north of
  // the wall; the way is back south, out of the inflation, and round.
  KnownSpace k({0, 0}, {4, 4}, 0.05);
  k.markContact({3.61, 2.16});  // the leg
  k.markContact({3.79, 2.41});  // the wall's bumped point
  const Costmap cm(k, PlannerOptions{});
  const Vec2 start{3.81, 2.16};
  REQUIRE(cm.blocked(start));
  const auto plan = planPath(cm, start, {3.0, 3.0});
  REQUIRE(plan);
  // The first waypoint outside the inflation is south of the start: the robot backs out of the
  // pocket the way it came in, not through the halos of the leg or the bumped point.
  const auto out = std::find_if(plan->waypoints.begin(), plan->waypoints.end(),
                                [&](const Vec2& w) { return !cm.blocked(w); });
  REQUIRE(out != plan->waypoints.end());
  CHECK(out->y() < start.y());
  for (auto w = plan->waypoints.begin(); w != out; ++w) CHECK(w->y() <= start.y() + 1e-9);
}

TEST_CASE("planPath: a start where every step out first comes nearer an obstacle still leaves",
          "[exploration]") {
  // Contacts on a ring of 0.18 m round the robot, open to the south: every step toward the gap
  // comes nearer the ring's ends. A rule that forbade that inside the inflation (tried first)
  // trapped the robot there (default arena, seed 3: "no candidate worth its travel" at 15 m).
  KnownSpace k({0, 0}, {3, 3}, 0.05);
  const Vec2 c{1.51, 1.51};
  for (int deg = 0; deg < 360; deg += 5) {
    const double a = deg * kPi / 180.0;
    if (std::abs(wrapPi(a + kPi / 2)) < 75.0 * kPi / 180.0) continue;  // the gap
    k.markContact(c + 0.18 * Vec2{std::cos(a), std::sin(a)});
  }
  const Costmap cm(k, PlannerOptions{});
  REQUIRE(cm.blocked(c));
  const auto plan = planPath(cm, c, {1.5, 0.5});
  REQUIRE(plan);
  CHECK(plan->waypoints.back().y() == Approx(0.5));
}

TEST_CASE("Costmap: where the robot has been it fits, unless it bumped there", "[exploration]") {
  // A 0.45 m chair whose legs were found after the robot drove under it (chairs_at_table seed 2):
  // the inflation closes its 0.415 m gaps, and the robot under it stands on free cells a search
  // may not leave. The way it came in stays passable.
  KnownSpace k({0, 0}, {3, 3}, 0.05);
  const Vec2 chair{1.51, 1.51};
  // Contacts on the legs' inner faces, 0.36 m apart across each gap.
  for (const Vec2& corner : {Vec2{1, 1}, Vec2{1, -1}, Vec2{-1, 1}, Vec2{-1, -1}})
    k.markContact(chair + 0.18 * corner);
  const Vec2 outside{1.51, 0.6};
  {
    const Costmap cm(k, PlannerOptions{});
    REQUIRE_FALSE(cm.blocked(chair));
    REQUIRE(cm.blocked(Vec2{1.51, 1.51 - 0.18}));  // the gap between the two south legs
    CHECK_FALSE(planPath(cm, chair, outside));       // an island
  }
  k.markVisited(outside, chair);  // it drove in from the south
  {
    const Costmap cm(k, PlannerOptions{});
    CHECK_FALSE(cm.blocked(Vec2{1.51, 1.51 - 0.18}));
    const auto plan = planPath(cm, chair, outside);
    REQUIRE(plan);
    CHECK(plan->waypoints.back().y() == Approx(0.6));
    // The other gaps stay closed: only the trail opens.
    CHECK(cm.blocked(Vec2{1.51 + 0.18, 1.51}));
  }
  // A trail that crossed a cell corner diagonally (cells 8-connected): the two cells it joins
  // at the corner are a step the robot drove, though both side cells are blocked.
  {
    KnownSpace d({0, 0}, {3, 3}, 0.05);
    for (const Vec2& corner : {Vec2{1, 1}, Vec2{1, -1}, Vec2{-1, 1}, Vec2{-1, -1}})
      d.markContact(chair + 0.18 * corner);
    d.markVisited(chair, {1.51, 1.51 - 0.1});          // down the middle
    d.markVisited({1.51, 1.51 - 0.1}, {1.525, 1.375});  // ...into the cell centred (1.525, 1.375)
    d.markVisited({1.575, 1.325}, {1.575, 0.6});        // and on from the diagonal cell
    const Costmap cd(d, PlannerOptions{});
    int ax, ay, bx, by;
    REQUIRE(d.index({1.525, 1.375}, ax, ay));
    REQUIRE(d.index({1.575, 1.325}, bx, by));
    REQUIRE((bx == ax + 1 && by == ay - 1));
    REQUIRE(cd.blocked(ax + 1, ay));  // both side cells blocked: a corner cut
    REQUIRE(cd.blocked(ax, ay - 1));
    CHECK(planPath(cd, chair, {1.575, 0.6}));
  }
  // A bump beside the trail: the rim touched there, so the trail near it closes again.
  k.markBump({1.51 + 0.1, 1.51 - 0.18});
  const Costmap cm(k, PlannerOptions{});
  CHECK(cm.blocked(Vec2{1.51, 1.51 - 0.18}));
  CHECK_FALSE(planPath(cm, chair, outside));
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
