#include "crunch/core/geometry.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <random>

using namespace crunch;

namespace {
bool near(double a, double b, double tol = 1e-12) { return std::abs(a - b) <= tol; }
}  // namespace

TEST_CASE("Geometry: wrapPeriod folds angles into the half-open period", "[core]") {
  CHECK(wrapPi(3 * kPi) == Approx(-kPi));
  CHECK(wrapPeriod(kPi / 2, kPi) == Approx(-kPi / 2));
  CHECK(wrapPeriod(kPi, kPi) == Approx(0.0).margin(1e-12));
  CHECK(wrapPeriod(0.1 + kPi, kPi) == Approx(0.1));
  CHECK(wrapPeriod(-0.1 - kPi / 2, kPi / 2) == Approx(-0.1));
}

TEST_CASE("Geometry: closest perimeter point names the face it lies on", "[core]") {
  const OrientedRect r{{1.0, 1.0, kPi / 2}, 0.2, 0.1};  // x-faces now face +-y
  const auto p = closestOnPerimeter(r, {1.0, 1.5});
  CHECK(p.side == 0);
  CHECK(p.distance == Approx(0.4));
  CHECK(p.point.x() == Approx(1.0));
  CHECK(p.point.y() == Approx(1.1));
}

TEST_CASE("Geometry: rectangles overlap only when interiors intersect", "[core]") {
  const OrientedRect a{{0, 0, 0}, 1.0, 1.0};
  CHECK(overlaps(a, {{0.9, 0.0, 0.0}, 1.0, 1.0}));
  CHECK_FALSE(overlaps(a, {{1.0, 0.0, 0.0}, 1.0, 1.0}));  // touching faces
  CHECK(overlaps(a, {{1.1, 0.0, kPi / 4}, 1.0, 1.0}));    // rotated corner pokes in
  CHECK_FALSE(overlaps(a, {{1.3, 0.0, kPi / 4}, 1.0, 1.0}));
}

TEST_CASE("Geometry: distance from rectangle to segment", "[core]") {
  const OrientedRect a{{0, 0, 0}, 1.0, 1.0};
  CHECK(distanceRectSegment(a, {1.0, -1.0}, {1.0, 1.0}) == Approx(0.5));
  CHECK(distanceRectSegment(a, {-1.0, 0.0}, {1.0, 0.0}) == Approx(0.0));
  CHECK(distanceRectSegment(a, {0.1, 0.1}, {0.2, 0.2}) == Approx(0.0));
}

TEST_CASE("Geometry: wrapHalfTurn maps any angle to 0 <= a < pi", "[core]") {
  CHECK(wrapHalfTurn(0.0) == 0.0);
  CHECK(near(wrapHalfTurn(kPi), 0.0));
  CHECK(near(wrapHalfTurn(-0.1), kPi - 0.1));
  CHECK(near(wrapHalfTurn(2.0 * kPi + 0.2), 0.2, 1e-9));
  CHECK(near(wrapHalfTurn(kPi + 0.3), 0.3, 1e-12));
  CHECK(near(wrapHalfTurn(-3.0 * kPi + 1.0), 1.0, 1e-9));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-40.0, 40.0);
  for (int i = 0; i < 10000; ++i) {
    const double a = u(rng);
    const double h = wrapHalfTurn(a);
    REQUIRE(h >= 0.0);
    REQUIRE(h < kPi);
    // Same orientation modulo pi.
    const double k = std::round((a - h) / kPi);
    REQUIRE(near(a - h, k * kPi, 1e-9));
  }
}

TEST_CASE("Geometry: fitRigid recovers a rigid frame and is the least-squares one", "[core]") {
  const Vec2 local[4] = {{0.375, 0.225}, {-0.375, 0.225}, {-0.375, -0.225}, {0.375, -0.225}};
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Pose2 truth{u(rng), u(rng), wrapPeriod(u(rng), 2.0 * kPi)};
    Vec2 world[4];
    for (int i = 0; i < 4; ++i) world[i] = truth.toWorld(local[i]);
    for (int n = 2; n <= 4; ++n) {
      const Pose2 f = fitRigid(local, world, n, 0.0);
      REQUIRE(near(f.x, truth.x, 1e-9));
      REQUIRE(near(f.y, truth.y, 1e-9));
      REQUIRE(near(wrapPi(f.theta - truth.theta), 0.0, 1e-9));
    }
  }
  // Noisy points: no small turn or shift of the fit lowers the squared error.
  std::normal_distribution<double> g(0.0, 0.02);
  Vec2 world[4];
  const Pose2 truth{1.0, 2.0, 0.7};
  for (int i = 0; i < 4; ++i) world[i] = truth.toWorld(local[i]) + Vec2{g(rng), g(rng)};
  auto err = [&](const Pose2& f) {
    double e = 0.0;
    for (int i = 0; i < 4; ++i) e += (f.toWorld(local[i]) - world[i]).squaredNorm();
    return e;
  };
  const Pose2 f = fitRigid(local, world, 4, 0.0);
  for (const Pose2& d : {Pose2{1e-3, 0, 0}, Pose2{-1e-3, 0, 0}, Pose2{0, 1e-3, 0},
                         Pose2{0, -1e-3, 0}, Pose2{0, 0, 1e-3}, Pose2{0, 0, -1e-3}})
    CHECK(err(f) < err({f.x + d.x, f.y + d.y, f.theta + d.theta}));
  // One point: the given angle, the point carried onto the point.
  const Pose2 one = fitRigid(local, world, 1, 0.4);
  CHECK(near(one.theta, 0.4));
  CHECK(near((one.toWorld(local[0]) - world[0]).norm(), 0.0, 1e-12));
}
