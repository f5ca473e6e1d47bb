// The bumper's switches and the expected hit point (robot/bumper.h), checked against a
// simulation of the situation the derivation assumes: a round body driving straight at point
// obstacles whose lateral offsets are uniform over its width.
#include "crunch/robot/bumper.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "crunch/core/rng.h"
#include "crunch/robot/whiskers.h"

using crunch::Bumper;
using crunch::kPi;

TEST_CASE("Bumper: which switches a hit closes") {
  CHECK(crunch::bumperAt(0.0) == Bumper::kBoth);
  CHECK(crunch::bumperAt(0.9 * crunch::kBumperBothHalfAngle) == Bumper::kBoth);
  CHECK(crunch::bumperAt(-0.9 * crunch::kBumperBothHalfAngle) == Bumper::kBoth);
  CHECK(crunch::bumperAt(0.6) == Bumper::kLeft);
  CHECK(crunch::bumperAt(-0.6) == Bumper::kRight);
  CHECK(crunch::bumperAt(2.0 * kPi + 0.6) == Bumper::kLeft);  // wrapped
  CHECK(crunch::bumperAt(2.5) == Bumper::kLeft);              // behind the front: nearer side
  // The values are the Open Interface's packet 7 bits.
  CHECK(static_cast<int>(Bumper::kRight) == 0x01);
  CHECK(static_cast<int>(Bumper::kLeft) == 0x02);
  CHECK(static_cast<int>(Bumper::kBoth) == 0x03);
}

TEST_CASE("Bumper: the expected bearing is the mean hit bearing of straight driving") {
  CHECK(crunch::expectedBumpBearing(Bumper::kBoth) == 0.0);
  CHECK(crunch::expectedBumpBearing(Bumper::kReleased) == 0.0);
  CHECK(crunch::expectedBumpBearing(Bumper::kLeft) == -crunch::expectedBumpBearing(Bumper::kRight));
  // Monte Carlo of the assumption: obstacle offsets uniform across the body's width.
  const double R = crunch::kRobotRadius;
  crunch::Rng rng(11);
  double sum[4] = {0, 0, 0, 0};
  int n[4] = {0, 0, 0, 0};
  double err_front = 0.0, err_switch = 0.0;
  const int draws = 200000;
  for (int i = 0; i < draws; ++i) {
    const double y = R * (2.0 * rng.uniform() - 1.0);
    const double a = std::asin(y / R);
    const Bumper b = crunch::bumperAt(a);
    sum[static_cast<int>(b)] += a;
    ++n[static_cast<int>(b)];
    err_front += std::abs(a);
    err_switch += std::abs(a - crunch::expectedBumpBearing(b));
  }
  REQUIRE(n[1] > 1000);
  REQUIRE(n[2] > 1000);
  REQUIRE(n[3] > 1000);
  CHECK(sum[2] / n[2] == Approx(crunch::expectedBumpBearing(Bumper::kLeft)).margin(0.005));
  CHECK(sum[1] / n[1] == Approx(crunch::expectedBumpBearing(Bumper::kRight)).margin(0.005));
  CHECK(sum[3] / n[3] == Approx(0.0).margin(0.005));
  CHECK(crunch::expectedBumpBearing(Bumper::kLeft) == Approx(41.5 * kPi / 180).margin(0.002));
  // Reading the switches cuts the mean bearing error of "the body's front" (33 degrees) to 13.
  CHECK(err_front / draws == Approx(kPi / 2 - 1).margin(0.005));
  CHECK(err_switch / draws < 0.25);
}

TEST_CASE("Bumper: the expected point lies on the rim at the expected bearing") {
  const crunch::Pose2 pose{1.0, 2.0, kPi / 2};
  const crunch::Vec2 p = crunch::expectedBumpPoint(pose, Bumper::kRight, 0.2);
  CHECK((p - pose.position()).norm() == Approx(0.2));
  const double a = crunch::kPi / 2 + crunch::expectedBumpBearing(Bumper::kRight);
  CHECK(p.x() == Approx(1.0 + 0.2 * std::cos(a)));
  CHECK(p.y() == Approx(2.0 + 0.2 * std::sin(a)));
  const crunch::Vec2 f = crunch::expectedBumpPoint(pose, Bumper::kBoth, 0.2);
  CHECK(f.x() == Approx(1.0).margin(1e-12));
  CHECK(f.y() == Approx(2.2));
}
