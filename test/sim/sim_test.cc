#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/core/rng.h"
#include "crunch/mapping/sensor_model.h"
#include "crunch/robot/shapelet.h"
#include "crunch/scene/scene.h"
#include "crunch_sim/ray_sensor.h"
#include "crunch_sim/world.h"

using crunch::ContactReport;
using crunch::kPi;
using crunch::kRobotRadius;
using crunch::NoiseRegime;
using crunch::OrientedRect;
using crunch::Pose2;
using crunch::Rng;
using crunch::Scene;
using crunch::Shapelet;
using crunch::TableSpec;
using crunch::Vec2;
using crunch::WhiskerMount;
using crunch::sim::RaySensorModel;
using crunch::sim::World;

namespace {

// ODE's ray-box test works in double precision; hits agree with the analytic geometry far
// below a micrometre.
constexpr double kGeomTol = 1e-9;
// The brief's tolerance for a noiseless r.
constexpr double kRTol = 1e-6;
constexpr double kWhiskerZ = 0.1;

// A walled 4 x 4 m arena with the given tables and interior walls.
Scene makeScene(std::vector<TableSpec> tables = {}, std::vector<crunch::WallSpec> walls = {}) {
  Scene s;
  s.width = 4.0;
  s.depth = 4.0;
  s.tables = std::move(tables);
  s.walls = std::move(walls);
  return s;
}

TableSpec makeTable(double x, double y, double theta) {
  TableSpec t;
  t.pose = {x, y, theta};
  return t;
}

// Difference of two orientations modulo pi, in [0, pi/2].
double orientationError(double a, double b) { return std::abs(crunch::wrapPeriod(a - b, kPi)); }

// Distance from p to the scene's ground truth: the nearest leg surface or wall segment. (An
// interior wall's faces lie half its thickness from its segment.)
double distanceToScene(const Scene& scene, const Vec2& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const TableSpec& t : scene.tables) {
    for (const OrientedRect& leg : t.legs()) {
      best = std::min(best, crunch::closestOnPerimeter(leg, p).distance);
    }
  }
  for (const crunch::WallSpec& w : scene.allWalls()) {
    best = std::min(best, crunch::distanceToSegment(p, w.a, w.b));
  }
  return best;
}

RaySensorModel makeSensor(const World& world, std::vector<WhiskerMount> mounts, NoiseRegime noise) {
  return RaySensorModel(world, std::move(mounts), std::move(noise), RaySensorModel::Options{});
}

// A robot whose default whisker #2 (bearing +11.25 deg) points straight at the centre of the
// -x face of leg 1 of a table at (2, 2, table_theta), with the whisker base `gap` metres from
// the face.
struct FacingLeg {
  Scene scene;
  Pose2 robot;
  WhiskerMount mount;
  Vec2 face_centre;
  double face_orientation;  // arena frame, modulo pi
};
FacingLeg makeFacingLeg(double table_theta, double gap) {
  FacingLeg f;
  f.scene = makeScene({makeTable(2.0, 2.0, table_theta)});
  const OrientedRect leg = f.scene.tables[0].legs()[1];
  f.face_centre = leg.pose.toWorld({-0.5 * leg.size_x, 0.0});
  const Vec2 outward(-std::cos(leg.pose.theta), -std::sin(leg.pose.theta));
  const Vec2 centre = f.face_centre + (kRobotRadius + gap) * outward;
  f.mount = crunch::defaultWhiskerArray()[2];
  f.robot = {centre.x(), centre.y(), leg.pose.theta - f.mount.bearing};
  f.face_orientation = leg.pose.theta + 0.5 * kPi;
  return f;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Whisker array and shapelets

TEST_CASE("Shapelet: default whisker array has four radial whiskers on the body rim", "[sim]") {
  const auto mounts = crunch::defaultWhiskerArray();
  REQUIRE(mounts.size() == 4);
  const double expected_deg[] = {-33.75, -11.25, 11.25, 33.75};
  for (size_t i = 0; i < mounts.size(); ++i) {
    CHECK(mounts[i].bearing == Approx(expected_deg[i] * kPi / 180.0));
    CHECK(mounts[i].base.norm() == Approx(kRobotRadius));
    CHECK(std::atan2(mounts[i].base.y(), mounts[i].base.x()) == Approx(mounts[i].bearing));
    CHECK(mounts[i].length == Approx(0.14));
  }
}

TEST_CASE("Shapelet: over a pose's four compass headings the 16 whiskers are 22.5 deg apart",
          "[sim]") {
  const auto mounts = crunch::defaultWhiskerArray();
  REQUIRE(mounts.size() == 4);
  std::vector<double> directions;
  for (int k = 0; k < 4; ++k) {
    for (const WhiskerMount& m : mounts) {
      double d = std::fmod(m.bearing + 0.5 * kPi * k, 2.0 * kPi);
      if (d < 0.0) d += 2.0 * kPi;
      directions.push_back(d);
    }
  }
  std::sort(directions.begin(), directions.end());
  REQUIRE(directions.size() == 16);
  const double step = 22.5 * kPi / 180.0;
  for (size_t i = 0; i < directions.size(); ++i) {
    // The last gap wraps around through 2 pi back to the first direction.
    const double gap = i + 1 < directions.size()
                           ? directions[i + 1] - directions[i]
                           : directions.front() + 2.0 * kPi - directions.back();
    INFO("gap after direction " << i << " (" << directions[i] * 180.0 / kPi << " deg)");
    CHECK(gap == Approx(step).margin(1e-12));
  }
}

TEST_CASE("Shapelet: toShapelet rejects non-finite and out-of-range reports", "[sim]") {
  const auto mounts = crunch::defaultWhiskerArray();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  ContactReport good;
  good.whisker = 1;
  good.r = 0.05;
  good.phi = 0.4;
  good.robot = {1.0, 1.0, 0.2};

  Shapelet untouched;
  untouched.x = 123.0;
  auto rejected = [&](ContactReport rep) {
    Shapelet out = untouched;
    const bool ok = crunch::toShapelet(rep, mounts, 7, out);
    return !ok && out.x == 123.0;
  };
  ContactReport rep = good;
  rep.r = nan;
  CHECK(rejected(rep));
  rep = good;
  rep.phi = nan;
  CHECK(rejected(rep));
  rep = good;
  rep.robot.x = inf;
  CHECK(rejected(rep));
  rep = good;
  rep.robot.theta = nan;
  CHECK(rejected(rep));
  // A face's length must be a length: finite and not negative; it is carried to the shapelet.
  for (const double span : {nan, inf, -0.01}) {
    rep = good;
    rep.face_span = span;
    CHECK(rejected(rep));
  }
  rep = good;
  rep.face_span = 0.2;
  Shapelet carried;
  REQUIRE(crunch::toShapelet(rep, mounts, 7, carried));
  CHECK(carried.face_span == 0.2);
  // r is a measurement only within [-length, 2 length].
  const double length = mounts[1].length;
  REQUIRE(length == Approx(0.14));
  rep = good;
  rep.r = 2.5 * length;
  CHECK(rejected(rep));
  rep = good;
  rep.r = -1.5 * length;
  CHECK(rejected(rep));
  rep = good;
  rep.r = 2.0 * length + 1e-3;
  CHECK(rejected(rep));
  rep = good;
  rep.r = -length - 1e-3;
  CHECK(rejected(rep));
  rep = good;
  rep.whisker = 4;
  CHECK(rejected(rep));
  rep = good;
  rep.whisker = -1;
  CHECK(rejected(rep));

  Shapelet out;
  rep = good;
  rep.r = 0.0;
  CHECK(crunch::toShapelet(rep, mounts, 7, out));
  rep.r = 0.14;
  CHECK(crunch::toShapelet(rep, mounts, 7, out));
}

TEST_CASE("Shapelet: toShapelet clamps a noisy r just past either end onto the whisker",
          "[sim]") {
  const auto mounts = crunch::defaultWhiskerArray();
  const WhiskerMount& m = mounts[1];
  ContactReport rep;
  rep.whisker = 1;
  rep.phi = 0.4;
  rep.robot = {1.0, 1.0, 0.2};
  // The whisker's base and tip in the arena, computed independently of toShapelet.
  const Vec2 base = rep.robot.toWorld(m.base);
  const double heading = rep.robot.theta + m.bearing;
  const Vec2 tip = base + m.length * Vec2(std::cos(heading), std::sin(heading));

  auto place = [&](double r) {
    ContactReport rr = rep;
    rr.r = r;
    Shapelet s;
    s.x = s.y = 123.0;
    const bool ok = crunch::toShapelet(rr, mounts, 3, s);
    return std::make_pair(ok, s);
  };

  SECTION("a little past the tip: at the tip") {
    const auto [ok, s] = place(m.length + 0.01);
    REQUIRE(ok);
    CHECK(Vec2(s.x, s.y).isApprox(tip, kGeomTol));
    CHECK(Vec2(s.ox, s.oy).isApprox(base, kGeomTol));
    CHECK(s.pose_index == 3);
    CHECK(s.whisker == 1);
  }
  SECTION("a little before the base: at the base") {
    const auto [ok, s] = place(-0.01);
    REQUIRE(ok);
    CHECK(Vec2(s.x, s.y).isApprox(base, kGeomTol));
    CHECK(Vec2(s.ox, s.oy).isApprox(base, kGeomTol));
  }
  SECTION("at the limits of plausibility: still clamped, not rejected") {
    const auto [ok_far, far] = place(2.0 * m.length);
    REQUIRE(ok_far);
    CHECK(Vec2(far.x, far.y).isApprox(tip, kGeomTol));
    const auto [ok_back, back] = place(-m.length);
    REQUIRE(ok_back);
    CHECK(Vec2(back.x, back.y).isApprox(base, kGeomTol));
  }
  SECTION("inside the whisker: not clamped") {
    const auto [ok, s] = place(0.5 * m.length);
    REQUIRE(ok);
    CHECK(Vec2(s.x, s.y).isApprox(0.5 * (base + tip), kGeomTol));
  }
}

TEST_CASE("Shapelet: a report from a rotated robot lands at the right arena point", "[sim]") {
  const auto mounts = crunch::defaultWhiskerArray();
  ContactReport rep;
  rep.whisker = 0;  // bearing -33.75 deg
  rep.r = 0.05;
  rep.phi = 2.0;
  rep.robot = {1.0, 2.0, 0.5 * kPi};
  const WhiskerMount& m = mounts[0];
  REQUIRE(m.bearing == Approx(-33.75 * kPi / 180.0));

  Shapelet s;
  REQUIRE(crunch::toShapelet(rep, mounts, 11, s));
  // In the robot frame the base is m.base and the contact m.base + r (cos b, sin b); turning
  // by +90 degrees sends (u, v) to (-v, u).
  const Vec2 contact = m.base + rep.r * Vec2(std::cos(m.bearing), std::sin(m.bearing));
  CHECK(s.x == Approx(1.0 - contact.y()).margin(kGeomTol));
  CHECK(s.y == Approx(2.0 + contact.x()).margin(kGeomTol));
  CHECK(s.ox == Approx(1.0 - m.base.y()).margin(kGeomTol));
  CHECK(s.oy == Approx(2.0 + m.base.x()).margin(kGeomTol));
  // The whisker is radial, so the contact is R + r from the robot centre, at bearing
  // b + 90 deg: (R + r)(-sin b, cos b) = (R + r)(0.5556, 0.8315).
  const double d = kRobotRadius + rep.r;
  CHECK(s.x == Approx(1.0 + d * std::sin(33.75 * kPi / 180.0)).margin(kGeomTol));
  CHECK(s.y == Approx(2.0 + d * std::cos(33.75 * kPi / 180.0)).margin(kGeomTol));
  // 2.0 + pi/2 = 3.5708 wraps to 3.5708 - pi = 0.4292, in [0, pi).
  CHECK(s.phi == Approx(2.0 + 0.5 * kPi - kPi).margin(kGeomTol));
  CHECK(s.phi >= 0.0);
  CHECK(s.phi < kPi);
  CHECK(s.tau == 1.0);
  CHECK(s.pose_index == 11);
  CHECK(s.whisker == 0);
}

// ---------------------------------------------------------------------------------------------
// World

TEST_CASE("World: ray hits a wall at the right distance and normal", "[sim]") {
  const auto world = World::build(makeScene({}, {{{1.0, 1.0}, {1.0, 3.0}}}));

  SECTION("boundary wall: its inner face is the arena boundary") {
    const auto east = world->castRay({2.0, 2.5}, 0.0, 3.0, kWhiskerZ);
    REQUIRE(east);
    CHECK(east->distance == Approx(2.0).margin(kGeomTol));
    CHECK(east->point.isApprox(Vec2(4.0, 2.5), kGeomTol));
    CHECK(east->normal.isApprox(Vec2(-1.0, 0.0), kGeomTol));

    const auto north = world->castRay({2.0, 2.5}, 0.5 * kPi, 3.0, kWhiskerZ);
    REQUIRE(north);
    CHECK(north->distance == Approx(1.5).margin(kGeomTol));
    CHECK(north->normal.isApprox(Vec2(0.0, -1.0), kGeomTol));
  }
  SECTION("interior wall: straddles its segment") {
    const auto west = world->castRay({2.0, 2.0}, kPi, 3.0, kWhiskerZ);
    REQUIRE(west);
    CHECK(west->distance == Approx(1.0 - 0.5 * crunch::sim::kWallThickness).margin(kGeomTol));
    CHECK(west->normal.isApprox(Vec2(1.0, 0.0), kGeomTol));
  }
  SECTION("oblique ray: distance along the ray, normal still the face's") {
    const double heading = kPi / 6.0;  // 30 deg toward the east wall
    const auto hit = world->castRay({3.0, 1.0}, heading, 3.0, kWhiskerZ);
    REQUIRE(hit);
    CHECK(hit->distance == Approx(1.0 / std::cos(heading)).margin(kGeomTol));
    CHECK(hit->normal.isApprox(Vec2(-1.0, 0.0), kGeomTol));
  }
}

TEST_CASE("World: ray misses when nothing is in range", "[sim]") {
  const auto world = World::build(makeScene({makeTable(2.0, 2.0, 0.0)}));
  CHECK_FALSE(world->castRay({2.0, 2.0}, 0.3, 0.14, kWhiskerZ));  // under the table: no top
  CHECK_FALSE(world->castRay({3.0, 3.0}, 0.0, 0.5, kWhiskerZ));   // wall 1 m away
  CHECK_FALSE(world->castRay({3.0, 3.0}, 0.0, 2.0, 0.6));         // above the 0.5 m walls
  CHECK_FALSE(world->castRay({3.0, 3.0}, 0.0, 0.0, kWhiskerZ));   // zero length
  CHECK(world->castRay({3.0, 3.0}, 0.0, 2.0, kWhiskerZ));         // the same ray, long enough
}

TEST_CASE("World: the nearest of two legs wins", "[sim]") {
  // Legs 0 (+x+y) and 1 (-x+y) of a table at (2, 2) span x in [2.35, 2.40] and [1.60, 1.65],
  // y in [2.20, 2.25]; a ray along y = 2.225 passes through both.
  const auto world = World::build(makeScene({makeTable(2.0, 2.0, 0.0)}));
  const auto from_west = world->castRay({1.0, 2.225}, 0.0, 2.0, kWhiskerZ);
  REQUIRE(from_west);
  CHECK(from_west->distance == Approx(0.60).margin(kGeomTol));
  CHECK(from_west->normal.isApprox(Vec2(-1.0, 0.0), kGeomTol));
  const auto from_east = world->castRay({3.0, 2.225}, kPi, 2.0, kWhiskerZ);
  REQUIRE(from_east);
  CHECK(from_east->distance == Approx(0.60).margin(kGeomTol));
  CHECK(from_east->normal.isApprox(Vec2(1.0, 0.0), kGeomTol));
  // Between the legs, looking east: the inner face of leg 0.
  const auto between = world->castRay({2.0, 2.225}, 0.0, 2.0, kWhiskerZ);
  REQUIRE(between);
  CHECK(between->distance == Approx(0.35).margin(kGeomTol));
}

TEST_CASE("World: the nearest surface point is on the nearest leg's outline", "[sim]") {
  // Leg 0 (+x+y) of a table at (2, 2) spans x in [2.35, 2.40], y in [2.20, 2.25].
  const auto world = World::build(makeScene({makeTable(2.0, 2.0, 0.0)}));
  const auto east = world->nearestSurfacePoint({2.5, 2.225});
  REQUIRE(east);
  CHECK(east->isApprox(Vec2(2.40, 2.225), kGeomTol));
  const auto corner = world->nearestSurfacePoint({2.45, 2.30});
  REQUIRE(corner);
  CHECK(corner->isApprox(Vec2(2.40, 2.25), kGeomTol));
}

TEST_CASE("World: builds only walls and legs", "[sim]") {
  const auto world = World::build(
      makeScene({makeTable(1.0, 1.0, 0.0), makeTable(3.0, 3.0, 0.5)}, {{{1.0, 2.0}, {2.0, 2.0}}}));
  CHECK(world->footprints().size() == 4 + 1 + 2 * 4);
}

TEST_CASE("World: body collides with a leg and a wall, not in free space", "[sim]") {
  const auto world = World::build(makeScene({makeTable(2.0, 2.0, 0.0)}));
  CHECK(world->bodyCollides({1.5, 2.225, 0.0}));      // 0.10 m from leg 1's face
  CHECK(world->bodyCollides({0.1, 1.0, 0.0}));        // overlaps the west wall
  CHECK(world->bodyCollides({3.9, 3.9, 1.0}));        // in the north-east corner
  CHECK_FALSE(world->bodyCollides({2.0, 2.0, 0.0}));  // under the top, between the legs
  CHECK_FALSE(world->bodyCollides({3.2, 1.0, 0.7}));
  CHECK_FALSE(world->bodyCollides({0.2, 1.0, 0.0}));  // 0.035 m clear of the wall
  CHECK(world->bodyCollides({std::numeric_limits<double>::quiet_NaN(), 1.0, 0.0}));
}

TEST_CASE("World: body collision matches the exact circle-footprint overlap, deep overlaps too",
          "[sim]") {
  // Guards against ODE 0.16's cylinder-box test, which misses boxes that pass right through
  // the cylinder (see World::bodyCollides).
  const Scene scene = makeScene({makeTable(2.0, 2.0, 0.4)}, {{{0.5, 3.0}, {1.5, 3.5}}});
  const auto world = World::build(scene);
  constexpr double kBorderline = 1e-6;  // skip positions this close to grazing contact
  int mismatches = 0, overlapping = 0;
  for (const OrientedRect& box : world->footprints()) {
    if (box.size_x > 1.5) continue;  // boundary walls: covered by the interior wall's case
    for (double dx = -0.3; dx <= 0.3; dx += 0.01) {
      for (double dy = -0.3; dy <= 0.3; dy += 0.01) {
        const Vec2 p = box.pose.toWorld({dx, dy});
        const Vec2 local = box.pose.toLocal(p);
        const bool inside =
            std::abs(local.x()) <= 0.5 * box.size_x && std::abs(local.y()) <= 0.5 * box.size_y;
        double d = inside ? 0.0 : std::numeric_limits<double>::infinity();
        for (const OrientedRect& other : world->footprints()) {
          d = std::min(d, crunch::closestOnPerimeter(other, p).distance);
        }
        if (!inside && std::abs(d - kRobotRadius) < kBorderline) continue;
        const bool exact = inside || d < kRobotRadius;
        overlapping += exact;
        mismatches += exact != world->bodyCollides({p.x(), p.y(), 0.0});
      }
    }
  }
  CHECK(overlapping > 1000);
  CHECK(mismatches == 0);
}

// The nearest entry of the ray origin + t dir, 0 <= t <= length, into the box's footprint (slab
// method in the box frame); infinity if it misses.
double rayEntry(const OrientedRect& box, const Vec2& origin, const Vec2& dir, double length) {
  const Vec2 o = box.pose.toLocal(origin);
  const Vec2 d = Pose2{0.0, 0.0, box.pose.theta}.toLocal(Vec2(dir));
  const double half[2] = {0.5 * box.size_x, 0.5 * box.size_y};
  double enter = 0.0, leave = length;
  for (int a = 0; a < 2; ++a) {
    if (std::abs(d[a]) < 1e-15) {
      if (std::abs(o[a]) > half[a]) return std::numeric_limits<double>::infinity();
      continue;
    }
    double t0 = (-half[a] - o[a]) / d[a], t1 = (half[a] - o[a]) / d[a];
    if (t0 > t1) std::swap(t0, t1);
    enter = std::max(enter, t0);
    leave = std::min(leave, t1);
  }
  return enter <= leave ? enter : std::numeric_limits<double>::infinity();
}

TEST_CASE("World: rays and body probes on a crowded floor match the exact footprint geometry",
          "[sim]") {
  // The broad phase (World's grid) must neither drop a box nor change a hit: 40 tables at random
  // poses and three slanted interior walls on a 12 x 8 m floor, rays from 0.05 to 15 m (the
  // longest meet more boxes than the grid's candidate list holds, and ask the whole space).
  Scene scene = makeScene();
  scene.width = 12.0;
  scene.depth = 8.0;
  Rng rng(7);
  for (int i = 0; i < 40; ++i)
    scene.tables.push_back(makeTable(rng.uniform(0.5, 11.5), rng.uniform(0.5, 7.5),
                                     rng.uniform(-kPi, kPi)));
  scene.walls = {{{2.0, 1.0}, {5.0, 3.5}}, {{9.0, 7.0}, {11.0, 4.0}}, {{6.0, 6.0}, {6.0, 2.0}}};
  const auto world = World::build(scene);
  const auto inside_any = [&](const Vec2& p) {
    for (const OrientedRect& box : world->footprints()) {
      const Vec2 l = box.pose.toLocal(p);
      if (std::abs(l.x()) <= 0.5 * box.size_x && std::abs(l.y()) <= 0.5 * box.size_y) return true;
    }
    return false;
  };
  int hits = 0, misses = 0, long_hits = 0, mismatches = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec2 origin{rng.uniform(0.01, 11.99), rng.uniform(0.01, 7.99)};
    if (inside_any(origin)) continue;
    const double heading = rng.uniform(-kPi, kPi);
    const double length = i % 10 == 0 ? rng.uniform(3.0, 15.0) : rng.uniform(0.05, 1.0);
    const Vec2 dir{std::cos(heading), std::sin(heading)};
    double best = std::numeric_limits<double>::infinity();
    for (const OrientedRect& box : world->footprints())
      best = std::min(best, rayEntry(box, origin, dir, length));
    const auto hit = world->castRay(origin, heading, length, kWhiskerZ);
    if (std::isfinite(best)) {
      ++hits;
      long_hits += length > 3.0;
      mismatches += !hit || std::abs(hit->distance - best) > kGeomTol;
    } else {
      ++misses;
      mismatches += hit.has_value();
    }
  }
  CHECK(hits > 3000);
  CHECK(misses > 3000);
  CHECK(long_hits > 1000);
  CHECK(mismatches == 0);

  constexpr double kBorderline = 1e-6;
  int overlapping = 0, body_mismatches = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec2 p{rng.uniform(0.0, 12.0), rng.uniform(0.0, 8.0)};
    double d = inside_any(p) ? 0.0 : std::numeric_limits<double>::infinity();
    for (const OrientedRect& box : world->footprints())
      d = std::min(d, crunch::closestOnPerimeter(box, p).distance);
    if (d > 0.0 && std::abs(d - kRobotRadius) < kBorderline) continue;
    const bool exact = d < kRobotRadius;
    overlapping += exact;
    body_mismatches += exact != world->bodyCollides({p.x(), p.y(), 0.0});
  }
  CHECK(overlapping > 3000);
  CHECK(body_mismatches == 0);
}

TEST_CASE("World: reachablePoses keeps free poses in order and counts the skipped", "[sim]") {
  const auto world = World::build(makeScene({makeTable(2.0, 2.0, 0.0)}));
  const std::vector<Pose2> candidates = {
      {1.0, 1.0, 0.0}, {1.5, 2.225, 0.0}, {3.0, 3.0, 1.0}, {0.05, 2.0, 0.0}, {2.0, 2.0, 2.0}};
  int skipped = -1;
  const auto kept = world->reachablePoses(candidates, &skipped);
  CHECK(skipped == 2);
  REQUIRE(kept.size() == 3);
  CHECK(kept[0].x == 1.0);
  CHECK(kept[1].x == 3.0);
  CHECK(kept[2].theta == 2.0);
  CHECK(world->reachablePoses(candidates, nullptr).size() == 3);
}

TEST_CASE("World: several worlds coexist and outlive each other", "[sim]") {
  auto a = World::build(makeScene());
  {
    auto b = World::build(makeScene({makeTable(2.0, 2.0, 0.0)}));
    CHECK(b->castRay({1.0, 2.225}, 0.0, 2.0, kWhiskerZ));
  }
  CHECK(a->castRay({2.0, 2.0}, 0.0, 3.0, kWhiskerZ));
  a.reset();
  auto c = World::build(makeScene());  // ODE re-initialised after the last world closed it
  CHECK(c->bodyCollides({0.1, 1.0, 0.0}));
}

// ---------------------------------------------------------------------------------------------
// Ray sensor

TEST_CASE("RaySensor: whisk sweeps +-pi/12 in steps of at most the sweep step", "[sim]") {
  CHECK(RaySensorModel::Options{}.whisk_amplitude == Approx(kPi / 12));
  const auto world = World::build(makeScene());
  const auto sensor = makeSensor(*world, crunch::defaultWhiskerArray(), NoiseRegime::ideal());
  const auto& offsets = sensor.sweepOffsets();
  REQUIRE(offsets.size() == 61);  // 15 deg / 0.5 deg = 30 steps each way, plus theta0
  CHECK(offsets.front() == 0.0);
  CHECK(*std::max_element(offsets.begin(), offsets.end()) == Approx(kPi / 12));
  CHECK(*std::min_element(offsets.begin(), offsets.end()) == Approx(-kPi / 12));
  // Sorted, the sampled headings are evenly spaced no wider than the sweep step.
  std::vector<double> sorted = offsets;
  std::sort(sorted.begin(), sorted.end());
  const double step = RaySensorModel::Options{}.sweep_step;
  for (size_t i = 1; i < sorted.size(); ++i) {
    CHECK(sorted[i] - sorted[i - 1] == Approx(step).margin(1e-12));
  }
  CHECK(RaySensorModel::Options{}.validate().ok());
  RaySensorModel::Options bad;
  bad.sweep_step = 0.0;
  CHECK_FALSE(bad.validate().ok());
}

TEST_CASE("RaySensor: a whisker facing a leg face reports its distance and orientation", "[sim]") {
  const double table_theta = GENERATE(0.0, 0.3, -1.1);
  const double gap = 0.08;
  const FacingLeg f = makeFacingLeg(table_theta, gap);
  const auto world = World::build(f.scene);
  REQUIRE_FALSE(world->bodyCollides(f.robot));
  auto sensor = makeSensor(*world, {f.mount}, NoiseRegime::ideal());

  Rng rng(1);
  std::vector<ContactReport> reps;
  sensor.sense(f.robot, rng, reps);
  REQUIRE(reps.size() == 1);
  // A radial whisker is closest to a flat face when it is perpendicular to it, at theta0.
  CHECK(reps[0].r == Approx(gap).margin(kRTol));
  CHECK(reps[0].robot.x == f.robot.x);
  CHECK(reps[0].robot.y == f.robot.y);
  CHECK(reps[0].robot.theta == f.robot.theta);
  CHECK(orientationError(reps[0].phi + reps[0].robot.theta, f.face_orientation) < kGeomTol);
  CHECK(reps[0].phi >= 0.0);
  CHECK(reps[0].phi < kPi);

  Shapelet s;
  REQUIRE(crunch::toShapelet(reps[0], sensor.mounts(), 0, s));
  CHECK(Vec2(s.x, s.y).isApprox(f.face_centre, kRTol));
  CHECK(orientationError(s.phi, f.face_orientation) < kGeomTol);
}

TEST_CASE("RaySensor: realistic noise has the regime's standard deviations (eqs. 4-5)", "[sim]") {
  const double gap = 0.08;
  const FacingLeg f = makeFacingLeg(0.3, gap);
  const auto world = World::build(f.scene);
  const NoiseRegime noise = NoiseRegime::realistic();
  auto sensor = makeSensor(*world, {f.mount}, noise);
  const double true_phi = f.face_orientation - f.robot.theta;

  Rng rng(2024);
  std::vector<ContactReport> reps;
  constexpr int kTrials = 4000;
  reps.reserve(kTrials);
  for (int i = 0; i < kTrials; ++i) sensor.sense(f.robot, rng, reps);
  REQUIRE(reps.size() == static_cast<size_t>(kTrials));

  double sum_r = 0.0, sum_r2 = 0.0, sum_p = 0.0, sum_p2 = 0.0;
  for (const auto& rep : reps) {
    const double er = rep.r - gap;
    const double ep = crunch::wrapPeriod(rep.phi - true_phi, kPi);
    sum_r += er;
    sum_r2 += er * er;
    sum_p += ep;
    sum_p2 += ep * ep;
  }
  const double n = kTrials;
  const double std_r = std::sqrt((sum_r2 - sum_r * sum_r / n) / (n - 1));
  const double std_p = std::sqrt((sum_p2 - sum_p * sum_p / n) / (n - 1));
  // 20% is about 18 standard errors of a 4000-sample standard deviation: never flaky, but
  // catches a wrong sigma or a missing noise term.
  CHECK(std_r == Approx(noise.sigma_r).epsilon(0.2));
  CHECK(std_p == Approx(noise.sigma_phi).epsilon(0.2));
  CHECK(std::abs(sum_r / n) < 0.1 * noise.sigma_r);
  CHECK(std::abs(sum_p / n) < 0.1 * noise.sigma_phi);
}

TEST_CASE("RaySensor: a whisk over a leg corner still reports", "[sim]") {
  // Leg 1 of a table at (2, 2) spans x in [1.60, 1.65], y in [2.20, 2.25]. A whisker along +x
  // at y = 2.19 passes 1 cm below its corner at theta0; turning toward +A sweeps it over.
  const Scene scene = makeScene({makeTable(2.0, 2.0, 0.0)});
  const auto world = World::build(scene);
  const WhiskerMount straight{{kRobotRadius, 0.0}, 0.0, 0.14};
  const Pose2 robot{1.5 - kRobotRadius, 2.19, 0.0};
  REQUIRE_FALSE(world->bodyCollides(robot));
  REQUIRE_FALSE(world->castRay(robot.toWorld(straight.base), 0.0, 0.14, kWhiskerZ));

  auto sensor = makeSensor(*world, {straight}, NoiseRegime::ideal());
  Rng rng(3);
  std::vector<ContactReport> reps;
  sensor.sense(robot, rng, reps);
  REQUIRE(reps.size() == 1);
  CHECK(reps[0].robot.theta > 0.0);  // found while turned toward the leg
  Shapelet s;
  REQUIRE(crunch::toShapelet(reps[0], sensor.mounts(), 0, s));
  CHECK(distanceToScene(scene, {s.x, s.y}) < kRTol);
}

TEST_CASE("RaySensor: a whisker touching nothing gives no report", "[sim]") {
  const auto world = World::build(makeScene({makeTable(2.0, 2.0, 0.0)}));
  auto sensor = makeSensor(*world, crunch::defaultWhiskerArray(), NoiseRegime::realistic());
  Rng rng(4);
  std::vector<ContactReport> reps;
  sensor.sense({3.0, 1.0, 0.0}, rng, reps);
  CHECK(reps.empty());
}

TEST_CASE("RaySensor: the same seed gives identical reports", "[sim]") {
  const Scene scene = makeScene({makeTable(2.0, 2.0, 0.3), makeTable(1.0, 3.0, -0.2)});
  const auto world = World::build(scene);
  auto sensor = makeSensor(*world, crunch::defaultWhiskerArray(), NoiseRegime::realistic());
  const auto poses = world->reachablePoses(crunch::poseGrid(4.0, 4.0, 10, 10, 4), nullptr);

  auto run = [&](uint64_t seed) {
    Rng rng(seed);
    std::vector<ContactReport> reps;
    for (const Pose2& p : poses) sensor.sense(p, rng, reps);
    return reps;
  };
  const auto a = run(99), b = run(99), c = run(100);
  REQUIRE(!a.empty());
  REQUIRE(a.size() == b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    CHECK(a[i].whisker == b[i].whisker);
    CHECK(a[i].r == b[i].r);
    CHECK(a[i].phi == b[i].phi);
    CHECK(a[i].robot.x == b[i].robot.x);
    CHECK(a[i].robot.y == b[i].robot.y);
    CHECK(a[i].robot.theta == b[i].robot.theta);
  }
  REQUIRE(c.size() == a.size());  // contacts are geometry; only the noise depends on the seed
  CHECK(c[0].r != a[0].r);
}

TEST_CASE("RaySensor: the default arena run yields hundreds of shapelets on real surfaces",
          "[sim]") {
  const Scene scene = crunch::defaultArena();
  REQUIRE(scene.poses.size() == 400);
  const auto world = World::build(scene);
  int skipped = 0;
  const auto poses = world->reachablePoses(scene.poses, &skipped);
  CHECK(poses.size() + static_cast<size_t>(skipped) == scene.poses.size());

  auto sensor = makeSensor(*world, crunch::defaultWhiskerArray(), NoiseRegime::ideal());
  Rng rng(5);
  std::vector<ContactReport> reps;
  std::vector<Shapelet> shapelets;
  for (size_t i = 0; i < poses.size(); ++i) {
    reps.clear();
    sensor.sense(poses[i], rng, reps);
    for (const auto& rep : reps) {
      Shapelet s;
      REQUIRE(crunch::toShapelet(rep, sensor.mounts(), static_cast<int>(i), s));
      shapelets.push_back(s);
    }
  }
  CHECK(shapelets.size() >= 100);
  double worst = 0.0;
  for (const Shapelet& s : shapelets) {
    worst = std::max(worst, distanceToScene(scene, {s.x, s.y}));
  }
  INFO("shapelets: " << shapelets.size() << ", farthest from a surface: " << worst << " m");
  CHECK(worst <= 0.5 * crunch::sim::kWallThickness + kGeomTol);
}
