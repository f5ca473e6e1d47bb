// Can an in-place whisk touch anything (whisk_clearance.h)? Against whiskers placed a known
// distance from a wall, and against a brute-force sweep over the default arena's poses.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <span>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/core/rng.h"
#include "crunch/robot/whiskers.h"
#include "crunch/scene/scene.h"
#include "crunch_sim/whisk_clearance.h"
#include "crunch_sim/world.h"
#include "support/sanitizers.h"

using crunch::defaultWhiskerArray;
using crunch::kPi;
using crunch::kRobotRadius;
using crunch::Pose2;
using crunch::Scene;
using crunch::TableSpec;
using crunch::Vec2;
using crunch::WhiskerMount;
using crunch::sim::inPlaceWhiskClear;
using crunch::sim::straightPathClear;
using crunch::sim::World;

namespace {

constexpr double kA = kPi / 12;  // the body whisk's amplitude
constexpr double kTipReach = kRobotRadius + 0.14;  // the default whiskers are radial

Scene arena(double width, double depth) {
  Scene s;
  s.width = width;
  s.depth = depth;
  return s;
}

// The smallest distance from any straight whisker to any box over `samples` headings in
// pose.theta + [from, to]: the brute-force answer the test checks against.
double sweptDistance(const World& world, const std::vector<WhiskerMount>& mounts,
                     const Pose2& pose, double from, double to, int samples) {
  double best = std::numeric_limits<double>::infinity();
  std::vector<crunch::OrientedRect> near;  // boxes within 0.5 m of the whiskers' reach
  for (const crunch::OrientedRect& box : world.footprints()) {
    if ((box.pose.position() - pose.position()).norm() - box.circumradius() < kTipReach + 0.5) {
      near.push_back(box);
    }
  }
  for (int k = 0; k <= samples; ++k) {
    const Pose2 at{pose.x, pose.y, pose.theta + from + (to - from) * k / samples};
    for (const WhiskerMount& m : mounts) {
      const Vec2 base = at.toWorld(m.base);
      const double a = at.theta + m.bearing;
      const Vec2 tip = base + m.length * Vec2(std::cos(a), std::sin(a));
      for (const crunch::OrientedRect& box : near) {
        best = std::min(best, crunch::distanceRectSegment(box, base, tip));
      }
    }
  }
  return best;
}

}  // namespace

TEST_CASE("WhiskClearance: a whisk far from everything is clear", "[sim][skip]") {
  const auto world = World::build(arena(4.0, 4.0));
  const auto mounts = defaultWhiskerArray();
  CHECK(inPlaceWhiskClear(*world, mounts, {2.0, 2.0, 0.3}, -kA, kA, 0.01));
  CHECK(inPlaceWhiskClear(*world, mounts, {2.0, 2.0, -2.0}, -kPi, kPi, 0.01));
}

TEST_CASE("WhiskClearance: clear exactly when the tips stay farther than the margin from a wall",
          "[sim][skip]") {
  // Facing the +x wall (the arena boundary x = 3): the tip of a whisker sweeps through straight
  // ahead within +-A, so the closest approach is d = 3 - x - kTipReach.
  const auto world = World::build(arena(3.0, 3.0));
  const auto mounts = defaultWhiskerArray();
  const double margin = 0.01;
  for (const double d : {0.002, 0.009, 0.0099, 0.0126, 0.013, 0.05}) {
    const Pose2 pose{3.0 - kTipReach - d, 1.5, 0.0};
    REQUIRE(sweptDistance(*world, mounts, pose, -kA, kA, 4000) == Approx(d).margin(1e-6));
    const bool clear = inPlaceWhiskClear(*world, mounts, pose, -kA, kA, margin);
    INFO("closest approach " << d << " m, margin " << margin << " m");
    if (d <= margin) CHECK_FALSE(clear);        // never clear within the margin
    if (d > 1.25 * margin) CHECK(clear);        // the conservative band is margin / 4 wide
  }
}

TEST_CASE("WhiskClearance: only the headings asked about count", "[sim][skip]") {
  // A leg to the robot's left, beyond the whisk's +-A but within reach of a wider turn.
  Scene s = arena(4.0, 4.0);
  TableSpec t;
  t.pose = {2.0, 3.0, 0.0};
  s.tables.push_back(t);
  const auto world = World::build(s);
  const auto mounts = defaultWhiskerArray();
  // Facing +x below the table's -x-y leg (1.625, 2.775), which stands 0.25 m away at a bearing of
  // 75 degrees: past the outer whisker's 33.75 + 15 degrees, within reach of a quarter turn.
  const Pose2 pose{1.625 - 0.25 * std::cos(75.0 * kPi / 180), 2.775 - 0.25 * std::sin(75.0 * kPi / 180),
                   0.0};
  REQUIRE_FALSE(world->bodyCollides(pose));
  REQUIRE(sweptDistance(*world, mounts, pose, -kA, kA, 2000) > 0.02);
  REQUIRE(sweptDistance(*world, mounts, pose, -kPi / 2, kPi / 2, 4000) < 0.001);
  CHECK(inPlaceWhiskClear(*world, mounts, pose, -kA, kA, 0.01));
  CHECK_FALSE(inPlaceWhiskClear(*world, mounts, pose, -kPi / 2, kPi / 2, 0.01));
  CHECK_FALSE(inPlaceWhiskClear(*world, mounts, pose, 0.0, kPi / 2, 0.01));
}

TEST_CASE("WhiskClearance: agrees with a brute-force sweep on the default arena's poses",
          "[sim][skip]") {
  const Scene scene = crunch::defaultArena();
  const auto world = World::build(scene);
  const auto mounts = defaultWhiskerArray();
  const std::vector<Pose2> poses = world->reachablePoses(scene.poses, nullptr);
  const double margin = 0.01;
  // Under AddressSanitizer the brute force runs ~500 times slower (614 s for every pose): there
  // every 8th pose is checked, the same way; the Release build checks them all.
  constexpr std::size_t kStride = crunch::testing::kUnderAsan ? 8 : 1;
  int clear = 0, near = 0, checked = 0;
  for (std::size_t k = 0; k < poses.size(); k += kStride) {
    const Pose2& pose = poses[k];
    ++checked;
    const double d = sweptDistance(*world, mounts, pose, -kA, kA, 400);
    const bool c = inPlaceWhiskClear(*world, mounts, pose, -kA, kA, margin);
    clear += c;
    INFO("pose " << pose.x << " " << pose.y << " " << pose.theta << ": brute force " << d);
    // 400 headings over 2A leave at most kTipReach * A / 400 = 0.2 mm unseen between two.
    if (c) CHECK(d > margin - 2e-4);
    if (d > 1.25 * margin + 2e-4) CHECK(c);
    near += d <= 1.25 * margin + 2e-4 && d > margin;
  }
  // Most of the grid is open floor; the rest whisks at a leg or a wall.
  CHECK(clear > checked / 2);
  CHECK(clear < checked);
  INFO(near << " poses in the conservative band");
}

TEST_CASE("WhiskClearance: bad arguments are never clear", "[sim][skip]") {
  const auto world = World::build(arena(4.0, 4.0));
  const auto mounts = defaultWhiskerArray();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Pose2 pose{2.0, 2.0, 0.0};
  CHECK_FALSE(inPlaceWhiskClear(*world, mounts, {nan, 2.0, 0.0}, -kA, kA, 0.01));
  CHECK_FALSE(inPlaceWhiskClear(*world, mounts, pose, -kA, nan, 0.01));
  CHECK_FALSE(inPlaceWhiskClear(*world, mounts, pose, kA, -kA, 0.01));
  CHECK_FALSE(inPlaceWhiskClear(*world, mounts, pose, -kA, kA, 0.0));
  CHECK_FALSE(inPlaceWhiskClear(*world, mounts, pose, -kA, kA, nan));
  std::vector<WhiskerMount> bad = mounts;
  bad[1].bearing = nan;
  CHECK_FALSE(inPlaceWhiskClear(*world, bad, pose, -kA, kA, 0.01));
  // No whiskers: nothing can touch.
  CHECK(inPlaceWhiskClear(*world, std::vector<WhiskerMount>{}, pose, -kA, kA, 0.01));
}

TEST_CASE("WhiskClearance: a straight approach is clear exactly when the tips stay farther than "
          "the margin",
          "[sim][skip]") {
  // Driving toward the +x wall (x = 3) from x0 for `distance`: the foremost tip (the inner
  // whiskers', at +-11.25 degrees) ends 3 - x0 - distance - ahead from it, and nothing comes
  // closer on the way.
  const auto world = World::build(arena(3.0, 3.0));
  const auto mounts = defaultWhiskerArray();
  const auto tip_x = [](const WhiskerMount& m) {
    return (m.base + m.length * Vec2(std::cos(m.bearing), std::sin(m.bearing))).x();
  };
  double ahead = 0.0;
  for (const WhiskerMount& m : mounts) ahead = std::max(ahead, tip_x(m));
  const double margin = 0.01;
  const double x0 = 1.5;
  for (const double d : {-0.003, 0.002, 0.0099, 0.0126, 0.013, 0.05}) {
    const double distance = 3.0 - x0 - ahead - d;
    INFO("closest approach " << d << " m after " << distance << " m");
    REQUIRE(sweptDistance(*world, mounts, {x0 + distance, 1.5, 0.0}, 0.0, 0.0, 1) ==
            Approx(std::max(d, 0.0)).margin(1e-6));
    const bool clear = straightPathClear(*world, mounts, {x0, 1.5, 0.0}, distance, margin);
    if (d <= margin) CHECK_FALSE(clear);
    if (d > 1.25 * margin) CHECK(clear);
    // Each whisker alone: the outer ones (bearing +-33.75 deg) end farther from the wall.
    for (const WhiskerMount& m : mounts) {
      const double gap = 3.0 - (x0 + distance + tip_x(m));
      const bool one = straightPathClear(*world, std::span(&m, 1), {x0, 1.5, 0.0}, distance, margin);
      if (gap <= margin) CHECK_FALSE(one);
      if (gap > 1.25 * margin) CHECK(one);
    }
  }
  // Driving away from the wall is clear; a zero-length path is the pose itself.
  CHECK(straightPathClear(*world, mounts, {1.5, 1.5, kPi}, 1.0, margin));
  CHECK_FALSE(straightPathClear(*world, mounts, {3.0 - ahead, 1.5, 0.0}, 0.0, margin));
  // Bad arguments are never clear.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CHECK_FALSE(straightPathClear(*world, mounts, {1.5, 1.5, 0.0}, -0.1, margin));
  CHECK_FALSE(straightPathClear(*world, mounts, {1.5, 1.5, 0.0}, nan, margin));
  CHECK_FALSE(straightPathClear(*world, mounts, {1.5, 1.5, 0.0}, 0.1, 0.0));
}
