// The --sim --explore run (crunch_sim/explore_run.h) on test/scenes/two_tables.json:
// `--explore grid --teleport` maps exactly what the run without --explore maps (the paper's run
// is one policy of the new loop), and a driven frontier run moves, whisks, and scores the map it
// would end with every curve_step_m metres.
#include "crunch_sim/explore_run.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "crunch_sim/sim_run.h"

using namespace crunch;
using namespace crunch::sim;

namespace {
const std::string kTwoTables = std::string(CRUNCH_SOURCE_DIR) + "/test/scenes/two_tables.json";

SimScene twoTables() { return SimScene::build(loadSimScene(kTwoTables).value()); }
}  // namespace

TEST_CASE("explore run: grid --teleport maps exactly what the run without --explore maps",
          "[sim]") {
  const SimScene scene = twoTables();
  SimRunOptions o;
  o.seed = 3;
  const auto plain = runSimulation(scene, o);
  REQUIRE(plain);
  o.explore = exploration::ExploreOptions{};
  o.explore->teleport = true;
  const auto tele = runSimulation(scene, o);
  REQUIRE(tele);
  REQUIRE(tele.value().exploration);
  const Map& a = plain.value().map;
  const Map& b = tele.value().map;
  REQUIRE(a.tables.size() == b.tables.size());
  for (std::size_t i = 0; i < a.tables.size(); ++i) {
    CHECK(a.tables[i].pose.x == b.tables[i].pose.x);
    CHECK(a.tables[i].pose.y == b.tables[i].pose.y);
    CHECK(a.tables[i].pose.theta == b.tables[i].pose.theta);
  }
  CHECK(a.shapelets.size() == b.shapelets.size());
  CHECK(a.per_pose.size() == b.per_pose.size());
  CHECK(a.stats.poses == b.stats.poses);
  const auto& x = *tele.value().exploration;
  CHECK(x.whisks == static_cast<int>(scene.poses.size()));
  CHECK(x.stop_reason == "the pose list is done");
  CHECK(x.bumps == 0);
  // The curve ends on the final map, after the last whisk.
  REQUIRE_FALSE(x.curve.empty());
  CHECK(x.curve.back().whisks == x.whisks);
  CHECK(x.curve.back().recall == tele.value().evaluation.recall);
  // Travel: the straight lines between consecutive poses of the list.
  double travel = 0.0;
  for (std::size_t i = 1; i < scene.poses.size(); ++i) {
    travel += (scene.poses[i].position() - scene.poses[i - 1].position()).norm();
  }
  CHECK(x.travel_m == Approx(travel).epsilon(1e-12));
  CHECK(plain.value().evaluation.recall == tele.value().evaluation.recall);
}

TEST_CASE("explore run: a driven frontier run moves, whisks, and scores its map every step",
          "[sim]") {
  const SimScene scene = twoTables();
  SimRunOptions o;
  o.seed = 1;
  o.explore = exploration::ExploreOptions{};
  o.explore->policy = exploration::ExplorePolicyKind::kFrontier;
  o.explore->travel_budget_m = 8.0;
  const auto run = runSimulation(scene, o);
  REQUIRE(run);
  REQUIRE(run.value().exploration);
  const auto& x = *run.value().exploration;
  CHECK(x.policy == "frontier");
  CHECK_FALSE(x.teleport);
  CHECK(x.travel_m > 0.5);
  CHECK(x.travel_m < 8.0 + 0.05);  // the budget, overshot by at most a control step or so
  CHECK(x.whisks > 3);
  // A point after the first whisk, then after the first whisk past each further curve_step_m
  // metres, then the final map at the whole travel.
  const double step = o.explore->curve_step_m;
  REQUIRE(x.curve.size() >= 3);
  CHECK(x.curve.front().whisks == 1);
  CHECK(x.curve.size() <= static_cast<std::size_t>(x.travel_m / step) + 2);
  for (std::size_t i = 0; i < x.curve.size(); ++i) {
    if (i > 0) {
      CHECK(x.curve[i].whisks > x.curve[i - 1].whisks);
      CHECK(x.curve[i].travel_m >= x.curve[i - 1].travel_m);
    }
    if (i > 0 && i + 1 < x.curve.size()) {
      CHECK(std::floor(x.curve[i].travel_m / step) > std::floor(x.curve[i - 1].travel_m / step));
    }
    CHECK(x.curve[i].recall >= 0.0);
    CHECK(x.curve[i].recall <= 1.0);
  }
  CHECK(x.curve.back().whisks == x.whisks);
  CHECK(x.curve.back().travel_m == x.travel_m);
  CHECK(x.curve.back().recall == run.value().evaluation.recall);
  CHECK(x.curve.back().f1 == run.value().evaluation.f1);
  CHECK(x.whisk_poses.size() == static_cast<std::size_t>(x.whisks));
  CHECK(x.path.size() > 10);
  CHECK(x.sim_time_s > x.travel_m / 0.2);  // it cannot outrun the Create's 0.2 m/s
  CHECK(x.stop_reason == "travel budget reached");
  // Every whisk pose is where the body fits: the robot drove there.
  for (const Pose2& p : x.whisk_poses) CHECK_FALSE(scene.world->bodyCollides(p));
  CHECK(run.value().map.stats.poses == x.whisks);
}

TEST_CASE("explore run: a start inside an obstacle or outside the arena is an Error naming --start",
          "[sim]") {
  const SimScene scene = twoTables();
  SimRunOptions o;
  o.explore = exploration::ExploreOptions{};
  o.explore->policy = exploration::ExplorePolicyKind::kRandom;
  o.explore->start = Pose2{1.5, 0.3, 0.0};  // on the interior wall
  auto r = runSimulation(scene, o);
  REQUIRE_FALSE(r);
  CHECK(r.error().message.rfind("--start 1.5,0.3,0: inside an obstacle", 0) == 0);
  o.explore->start = Pose2{-1.0, 1.0, 0.0};
  r = runSimulation(scene, o);
  REQUIRE_FALSE(r);
  CHECK(r.error().message.find("outside the arena") != std::string::npos);
}
