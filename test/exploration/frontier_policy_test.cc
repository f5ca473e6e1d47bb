// The nearest-frontier policy: of two frontiers it goes to the nearer; with none, it stops.
#include <catch2/catch.hpp>

#include "policy_fixture.h"

using namespace crunch;
using namespace crunch::exploration;
using crunch::exploration::testing::PolicyWorld;

namespace {
// Everything free but two unknown patches (0.4 m squares) at `a` and `b`.
void freeAllBut(PolicyWorld& w, const Vec2& a, const Vec2& b) {
  for (double y = 0.025; y < w.known.hi().y(); y += 0.05) {
    w.known.markFreeRay({Vec2(0.0, y), Vec2(w.known.hi().x() - 1e-6, y)});
  }
  // Rebuild with the patches unknown: a fresh space, freed cell by cell outside them.
  KnownSpace k(w.known.lo(), w.known.hi(), w.known.cell());
  for (int iy = 0; iy < k.ny(); ++iy) {
    for (int ix = 0; ix < k.nx(); ++ix) {
      const Vec2 c = k.centre(ix, iy);
      const bool in_a = (c - a).cwiseAbs().maxCoeff() < 0.2;
      const bool in_b = (c - b).cwiseAbs().maxCoeff() < 0.2;
      if (!in_a && !in_b) k.markFreeRay({c, c});
    }
  }
  w.known = k;
}
}  // namespace

TEST_CASE("frontier policy: picks the nearer of two frontiers", "[exploration]") {
  PolicyWorld w({6, 3});
  freeAllBut(w, {1.5, 1.5}, {4.8, 1.5});
  auto p = makeFrontierPolicy(PolicyOptions{});
  Rng rng(1);
  const Pose2 robot{2.5, 1.5, 0};
  const auto d = p->next(w.state(robot), rng);
  REQUIRE(d.goal);
  CHECK((d.goal->position() - Vec2(1.5, 1.5)).norm() < 0.6);  // whisker reach of the near one
  // From the other side, the other one.
  auto q = makeFrontierPolicy(PolicyOptions{});
  const auto e = q->next(w.state({4.0, 1.5, 0}), rng);
  REQUIRE(e.goal);
  CHECK((e.goal->position() - Vec2(4.8, 1.5)).norm() < 0.6);
}

TEST_CASE("frontier policy: everything known, no frontier left", "[exploration]") {
  PolicyWorld w({3, 3});
  for (int iy = 0; iy < w.known.ny(); ++iy)
    for (int ix = 0; ix < w.known.nx(); ++ix) {
      const Vec2 c = w.known.centre(ix, iy);
      w.known.markFreeRay({c, c});
    }
  auto p = makeFrontierPolicy(PolicyOptions{});
  Rng rng(1);
  const auto d = p->next(w.state({1.5, 1.5, 0}), rng);
  CHECK_FALSE(d.goal);
  CHECK(d.why == "no frontier left");
}

TEST_CASE("frontier policy: a frontier is counted once, so it does not pull back for ever",
          "[exploration]") {
  PolicyWorld w({6, 3});
  freeAllBut(w, {1.5, 1.5}, {4.8, 1.5});
  auto p = makeFrontierPolicy(PolicyOptions{});
  Rng rng(1);
  // Nothing is sensed between decisions: the second goal must not be the first one again.
  const auto d1 = p->next(w.state({2.5, 1.5, 0}), rng);
  REQUIRE(d1.goal);
  int decisions = 1;
  for (; decisions < 200; ++decisions) {
    const auto d = p->next(w.state({2.5, 1.5, 0}), rng);
    if (!d.goal) break;
    CHECK_FALSE((d.goal->position() == d1.goal->position() && d.goal->theta == d1.goal->theta));
  }
  CHECK(decisions < 200);  // it runs out
}
