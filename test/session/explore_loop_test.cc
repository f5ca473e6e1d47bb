// The explore loop (crunch/session/explore_loop.h) driving the simulator's KinematicBase in
// simulated time: it reaches the policy's goal and whisks there; a bump against a leg it did not
// know replans around it; the whisk budget ends the run and says so.
#include "crunch/session/explore_loop.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "crunch_sim/kinematic_base.h"
#include "crunch_sim/world.h"

using namespace crunch;
using namespace crunch::session;
using crunch::exploration::KnownSpace;

namespace {

constexpr double kDt = 0.02;  // s of simulated time per control step

// A policy with a fixed list of goals, then "done".
class ListPolicy final : public exploration::ExplorePolicy {
 public:
  explicit ListPolicy(std::vector<Pose2> goals) : goals_(std::move(goals)) {}
  exploration::ExplorePolicyKind kind() const override { return exploration::ExplorePolicyKind::kGrid; }
  exploration::Decision next(const exploration::ExploreState&, Rng&) override {
    if (i_ >= goals_.size()) return {std::nullopt, "list done", 0.0};
    return {goals_[i_++], "", 0.0};
  }

 private:
  std::vector<Pose2> goals_;
  std::size_t i_ = 0;
};

// The list policy wanting `wanted` posterior draws, recording how many it was given.
class SamplingListPolicy final : public exploration::ExplorePolicy {
 public:
  SamplingListPolicy(std::vector<Pose2> goals, int wanted) : list_(std::move(goals)), wanted_(wanted) {}
  exploration::ExplorePolicyKind kind() const override { return exploration::ExplorePolicyKind::kGrid; }
  int samplesWanted() const override { return wanted_; }
  exploration::Decision next(const exploration::ExploreState& state, Rng& rng) override {
    given.push_back(state.samples.size());
    return list_.next(state, rng);
  }
  std::vector<std::size_t> given;

 private:
  ListPolicy list_;
  int wanted_;
};

// The list policy, recording the goals given up that each decision was told of.
class GivenUpListPolicy final : public exploration::ExplorePolicy {
 public:
  explicit GivenUpListPolicy(std::vector<Pose2> goals) : list_(std::move(goals)) {}
  exploration::ExplorePolicyKind kind() const override { return exploration::ExplorePolicyKind::kGrid; }
  exploration::Decision next(const exploration::ExploreState& state, Rng& rng) override {
    given_up.emplace_back(state.given_up.begin(), state.given_up.end());
    radius.push_back(state.given_up_radius);
    return list_.next(state, rng);
  }
  std::vector<std::vector<Vec2>> given_up;
  std::vector<double> radius;

 private:
  ListPolicy list_;
};

// 120 contacts on a circle of radius r about c: a closed ring of occupied cells.
void markRing(KnownSpace& known, const Vec2& c, double r) {
  for (int i = 0; i < 120; ++i) {
    const double a = 2 * kPi * i / 120;
    known.markContact(c + r * Vec2(std::cos(a), std::sin(a)));
  }
}

Scene room(std::vector<TableSpec> tables = {}) {
  Scene s;
  s.width = 4.0;
  s.depth = 3.0;
  s.tables = std::move(tables);
  return s;
}

// A table whose leg at (2.0, ~1.69) has its face 15 mm inside the path of a body driving along
// y = 1.5 (the start (0.5, 1.5) to the goal (3.5, 1.5)): a leg grazed at the body's left side.
Scene grazedLegRoom() {
  TableSpec t;
  const Vec2 leg{2.0, 1.5 + kRobotRadius + 0.5 * t.leg - 0.015};
  t.pose = {leg.x() + 0.5 * (t.width - t.leg), leg.y() + 0.5 * (t.depth - t.leg), 0.0};
  return room({t});
}

// Steps the loop and base until the loop finishes or `limit` simulated seconds pass.
void run(ExploreLoop& loop, sim::KinematicBase& base, double limit) {
  while (!loop.finished() && base.now() < limit) {
    REQUIRE(loop.update(0));
    base.step(kDt);
  }
}

}  // namespace

TEST_CASE("ExploreLoop: drives to the goal, turns to its heading and whisks there", "[session]") {
  const Scene scene = room();
  const auto world = sim::World::build(scene);
  sim::KinematicBase base(*world, {.start = {0.6, 0.6, 0.0}});
  KnownSpace known({0, 0}, {scene.width, scene.depth}, 0.05);
  ListPolicy policy({{3.0, 2.2, kPi / 2}});
  std::vector<Pose2> whisked;
  ExploreLoop loop(base, known, policy, defaultWhiskerArray(), ModelParams{}, {},
                   ExploreLoop::Options{}, {.whisked = [&](const Pose2& p) { whisked.push_back(p); }, .samples = {}, .bump_point = {}});
  run(loop, base, 200.0);
  REQUIRE(loop.finished());
  CHECK(loop.report().stop_reason == "list done");
  REQUIRE(whisked.size() == 1);
  CHECK((whisked[0].position() - Vec2(3.0, 2.2)).norm() < 0.05);       // waypoint tolerance
  CHECK(std::abs(wrapPi(whisked[0].theta - kPi / 2)) < 0.05);          // heading tolerance
  const double straight = std::hypot(3.0 - 0.6, 2.2 - 0.6);
  CHECK(loop.report().travel_m >= straight - 0.05);
  CHECK(loop.report().travel_m < straight + 0.2);  // open floor: near the straight line
  CHECK(loop.report().bumps == 0);
  CHECK(loop.report().whisks == 1);
  // The whisk took its time: toward, away, back at pi/24 rad/s = 8 s, plus the drive.
  CHECK(loop.report().sim_time_s > straight / 0.2 + 8.0 - 0.5);
  CHECK(loop.report().path.size() > 20);  // recorded every 5 cm
}

TEST_CASE("ExploreLoop: a bump on an unknown leg is recorded and the path replanned around it",
          "[session]") {
  // A table whose leg sits on the straight line from start to goal.
  TableSpec t;
  t.pose = {2.0 + 0.5 * (t.width - t.leg), 1.5 + 0.5 * (t.depth - t.leg), 0.0};  // +x+y leg at (2, 1.5)
  const Scene scene = room({t});
  const auto world = sim::World::build(scene);
  REQUIRE(world->bodyCollides({2.0, 1.5, 0}));
  sim::KinematicBase base(*world, {.start = {0.5, 1.5, 0.0}});
  KnownSpace known({0, 0}, {scene.width, scene.depth}, 0.05);
  ListPolicy policy({{3.5, 1.5, 0.0}});
  std::vector<Pose2> whisked;
  ExploreLoop loop(base, known, policy, defaultWhiskerArray(), ModelParams{}, {},
                   ExploreLoop::Options{}, {.whisked = [&](const Pose2& p) { whisked.push_back(p); }, .samples = {}, .bump_point = {}});
  run(loop, base, 400.0);
  REQUIRE(loop.finished());
  CHECK(loop.report().bumps >= 1);
  REQUIRE_FALSE(loop.report().bump_points.empty());
  const Vec2 hit = loop.report().bump_points[0];
  CHECK((hit - Vec2(2.0, 1.5)).norm() < 0.06);  // on the leg's face
  CHECK(known.at(hit) == KnownSpace::Cell::kOccupied);
  // Backed off straight (the hit was ahead), then whisked there, facing it; a bump at another
  // place (5 cm or more from the first) gets its own whisk; then the goal's whisk.
  INFO("bumps " << loop.report().bumps);
  REQUIRE(whisked.size() >= 2);
  CHECK(static_cast<int>(whisked.size()) <= 1 + loop.report().bumps);
  CHECK(loop.report().whisks == static_cast<int>(whisked.size()));
  CHECK((whisked.back().position() - Vec2(3.5, 1.5)).norm() < 0.05);
  CHECK(std::abs(wrapPi(whisked[0].theta)) < 0.05);
  CHECK((whisked[0].position() - hit).norm() > kRobotRadius + 0.04);
  CHECK((whisked[0].position() - hit).norm() < kRobotRadius + 0.08);
  CHECK((base.odometry().position() - Vec2(3.5, 1.5)).norm() < 0.05);  // got there anyway
  CHECK(loop.report().stop_reason == "list done");
}

TEST_CASE("ExploreLoop: the whisk budget ends the run and says so", "[session]") {
  const Scene scene = room();
  const auto world = sim::World::build(scene);
  sim::KinematicBase base(*world, {.start = {0.6, 0.6, 0.0}});
  KnownSpace known({0, 0}, {scene.width, scene.depth}, 0.05);
  ListPolicy policy({{1.0, 0.6, 0.0}, {1.5, 0.6, 0.0}, {2.0, 0.6, 0.0}});
  ExploreLoop::Options o;
  o.explore.whisk_budget = 2;
  ExploreLoop loop(base, known, policy, defaultWhiskerArray(), ModelParams{}, {}, o, {});
  run(loop, base, 400.0);
  REQUIRE(loop.finished());
  CHECK(loop.report().whisks == 2);
  CHECK(loop.report().stop_reason == "whisk budget reached");
}

TEST_CASE("ExploreLoop: a goal given up is passed to every later decision", "[session]") {
  const Scene scene = room();
  const auto world = sim::World::build(scene);
  sim::KinematicBase base(*world, {.start = {0.6, 0.6, 0.0}});
  KnownSpace known({0, 0}, {scene.width, scene.depth}, 0.05);
  // Goal 1 stands inside a ring of contacts: no path reaches it, so it is given up at once.
  markRing(known, {3.0, 2.0}, 0.3);
  GivenUpListPolicy policy({{3.0, 2.0, 0.0}, {1.2, 0.6, 0.0}});
  ExploreLoop::Options o;
  o.give_up_radius = 0.4;
  ExploreLoop loop(base, known, policy, defaultWhiskerArray(), ModelParams{}, {}, o, {});
  run(loop, base, 200.0);
  REQUIRE(loop.finished());
  CHECK(loop.report().stop_reason == "list done");
  CHECK(loop.report().whisks == 1);
  REQUIRE(policy.given_up.size() == 3);
  CHECK(policy.given_up[0].empty());
  for (std::size_t i = 1; i < 3; ++i) {
    REQUIRE(policy.given_up[i].size() == 1);
    CHECK((policy.given_up[i][0] - Vec2(3.0, 2.0)).norm() < 1e-12);
    CHECK(policy.radius[i] == 0.4);
  }
  o.give_up_radius = -1.0;
  CHECK_FALSE(o.validate());
  CHECK(o.validate().error().message.find("give_up_radius") != std::string::npos);
}

TEST_CASE("ExploreLoop: a robot boxed in ends the run cleanly and says why", "[session]") {
  const Scene scene = room();
  const auto world = sim::World::build(scene);
  sim::KinematicBase base(*world, {.start = {2.0, 1.5, 0.0}});
  KnownSpace known({0, 0}, {scene.width, scene.depth}, 0.05);
  // A ring of contacts 0.15 m around the robot: no cell it can reach is one it may stand on.
  markRing(known, {2.0, 1.5}, 0.15);
  auto policy = exploration::makeRandomPolicy(exploration::PolicyOptions{});
  ExploreLoop loop(base, known, *policy, defaultWhiskerArray(), ModelParams{}, {},
                   ExploreLoop::Options{}, {});
  run(loop, base, 10.0);
  REQUIRE(loop.finished());
  CHECK(loop.report().stop_reason.find("boxed in") != std::string::npos);
  CHECK(loop.report().whisks == 0);
  CHECK(loop.report().travel_m == 0.0);
}

TEST_CASE("ExploreLoop: a leg grazed at the side: the robot turns to face the bump, backs away "
          "from it and whisks it, once",
          "[session]") {
  const Scene scene = grazedLegRoom();
  const auto world = sim::World::build(scene);
  sim::KinematicBase base(*world, {.start = {0.5, 1.5, 0.0}});
  KnownSpace known({0, 0}, {scene.width, scene.depth}, 0.05);
  ListPolicy policy({{3.5, 1.5, 0.0}});
  std::vector<Pose2> whisked;
  ExploreLoop loop(
      base, known, policy, defaultWhiskerArray(), ModelParams{}, {}, ExploreLoop::Options{},
      {.whisked = [&](const Pose2& p) { whisked.push_back(p); },
       .samples = {},
       // As --sim's bumper: the nearest point of any leg to the body.
       .bump_point = [&](const Pose2& p) { return world->nearestSurfacePoint(p.position()); }});
  run(loop, base, 400.0);
  REQUIRE(loop.finished());
  CHECK(loop.report().stop_reason == "list done");
  REQUIRE(loop.report().bumps >= 1);
  const Vec2 hit = loop.report().bump_points[0];
  INFO("hit " << hit.x() << ", " << hit.y());
  const Vec2 rel = hit - Vec2(2.0, 1.5);
  CHECK(std::abs(rel.x()) < 0.1);  // beside the body, not ahead of it
  // The whisk after the bump faces the hit point from a body's radius plus the back-off.
  REQUIRE(whisked.size() >= 2);
  const Vec2 to_hit = hit - whisked[0].position();
  CHECK(std::abs(wrapPi(std::atan2(to_hit.y(), to_hit.x()) - whisked[0].theta)) < 0.1);
  CHECK(to_hit.norm() > kRobotRadius + 0.04);
  // A side graze no longer repeats: at most one bump per place (the old back-off along the
  // heading grazed the same leg again and again).
  CHECK(loop.report().bumps <= 2);
  CHECK((base.odometry().position() - Vec2(3.5, 1.5)).norm() < 0.05);
}

TEST_CASE("ExploreLoop: without a bump_point hook, the bumper's switches place the bump at the "
          "side that was hit",
          "[session]") {
  // The grazed leg of the test above, with only the base's bumper to go by (as on the Create):
  // the left switch puts the hit 41.5 degrees to the left on the rim (robot/bumper.h), about
  // 7 cm from the leg's corner, where the body's front on its heading would be 18 cm off.
  const Scene scene = grazedLegRoom();
  const auto world = sim::World::build(scene);
  sim::KinematicBase base(*world, {.start = {0.5, 1.5, 0.0}});
  KnownSpace known({0, 0}, {scene.width, scene.depth}, 0.05);
  ListPolicy policy({{3.5, 1.5, 0.0}});
  ExploreLoop loop(base, known, policy, defaultWhiskerArray(), ModelParams{}, {},
                   ExploreLoop::Options{}, {});
  run(loop, base, 400.0);
  REQUIRE(loop.finished());
  CHECK(loop.report().stop_reason == "list done");
  REQUIRE(loop.report().bumps >= 1);
  const Vec2 hit = loop.report().bump_points[0];
  INFO("hit " << hit.x() << ", " << hit.y());
  CHECK(hit.y() > 1.5 + 0.08);  // on the left, where the leg is
  const auto surface = world->nearestSurfacePoint(hit);
  REQUIRE(surface);
  CHECK((*surface - hit).norm() < 0.08);
  CHECK(loop.report().bumps <= 2);
  CHECK((base.odometry().position() - Vec2(3.5, 1.5)).norm() < 0.05);
}

TEST_CASE("ExploreLoop: a samples hook that draws over several updates: the robot stands still "
          "until the draws are in",
          "[session]") {
  // The robot's hook draws a slice per control step (controller.cc) and returns false until
  // the decision's draws are all made: the loop must not decide on part of them, nor move.
  const Scene scene = room();
  const auto world = sim::World::build(scene);
  sim::KinematicBase base(*world, {.start = {0.6, 0.6, 0.0}});
  KnownSpace known({0, 0}, {scene.width, scene.depth}, 0.05);
  SamplingListPolicy policy({{1.2, 0.6, 0.0}, {1.8, 0.6, 0.0}}, 3);
  int calls = 0;
  std::vector<std::size_t> sizes_seen;
  ExploreLoop loop(base, known, policy, defaultWhiskerArray(), ModelParams{}, {},
                   ExploreLoop::Options{},
                   {.whisked = {},
                    .samples = [&](int n, std::vector<MapSample>& out) {
                      ++calls;
                      sizes_seen.push_back(out.size());
                      if (calls % 5 != 0) return false;  // four updates of work, then the draws
                      for (int i = 0; i < n; ++i) out.push_back(MapSample{});
                      return true;
                    },
                    .bump_point = {}});
  const Pose2 start = base.odometry();
  for (int step = 0; step < 4; ++step) {
    REQUIRE(loop.update(0));
    base.step(kDt);
    CHECK(loop.phase() == ExploreLoop::Phase::kDecide);
    CHECK_FALSE(loop.goal().has_value());
  }
  CHECK(base.odometry().position() == start.position());
  CHECK(policy.given.empty());
  run(loop, base, 200.0);
  REQUIRE(loop.finished());
  CHECK(loop.report().stop_reason == "list done");
  // Three decisions (two goals, then "list done"), each given all 3 draws and none left over.
  REQUIRE(policy.given.size() == 3);
  for (const std::size_t g : policy.given) CHECK(g == 3);
  CHECK(calls == 15);
  // Within a decision the hook sees the same vector, empty at its first call.
  for (int c = 0; c < calls; ++c) CHECK(sizes_seen[static_cast<std::size_t>(c)] == 0);
  CHECK(loop.report().whisks == 2);
}
