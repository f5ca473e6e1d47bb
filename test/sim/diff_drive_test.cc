// DiffDrive (crunch_sim/diff_drive.h): the one command handling of both simulated bases, and
// that KinematicBase and WhiskeredRobot answer the same commands the same way.
#include "crunch_sim/diff_drive.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <memory>

#include "crunch/robot/whiskers.h"
#include "crunch/scene/scene.h"
#include "crunch_sim/kinematic_base.h"
#include "crunch_sim/whisker_physics.h"
#include "crunch_sim/world.h"

namespace {

using namespace crunch;
using sim::DiffDrive;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

Scene openFloor() {
  Scene s;
  s.width = 4.0;
  s.depth = 4.0;
  s.poses.clear();
  return s;
}

}  // namespace

TEST_CASE("DiffDrive: a command within the limits is taken as it is", "[sim][drive]") {
  DiffDrive d;
  REQUIRE(d.command(0.2, 0.5, "test base"));
  CHECK(d.right() == Approx(0.2 + 0.5 * 0.129));
  CHECK(d.left() == Approx(0.2 - 0.5 * 0.129));
  CHECK(d.v() == Approx(0.2));
  CHECK(d.omega() == Approx(0.5));
  CHECK_FALSE(d.clamped());
}

TEST_CASE("DiffDrive: a wheel over the limit scales both, keeping the curvature",
          "[sim][drive]") {
  DiffDrive d;
  REQUIRE(d.command(0.4, 2.0, "test base"));  // right 0.658 m/s: over 0.5
  CHECK(d.clamped());
  CHECK(d.right() == Approx(0.5));
  CHECK(d.omega() / d.v() == Approx(2.0 / 0.4));
  REQUIRE(d.command(-1.0, 0.0, "test base"));
  CHECK(d.left() == Approx(-0.5));
  CHECK(d.right() == Approx(-0.5));
  REQUIRE(d.command(0.0, -10.0, "test base"));  // turning in place stays in place
  CHECK(d.v() == Approx(0.0).margin(1e-15));
  CHECK(d.right() == Approx(-0.5));
}

TEST_CASE("DiffDrive: non-finite input stops the base and is an Error naming it",
          "[sim][drive]") {
  DiffDrive d;
  REQUIRE(d.command(0.3, 0.0, "test base"));
  const Status s = d.command(kNan, 0.0, "test base");
  REQUIRE_FALSE(s);
  CHECK_THAT(s.error().message, Catch::StartsWith("test base:"));
  CHECK(d.v() == 0.0);
  CHECK(d.omega() == 0.0);
  REQUIRE(d.command(0.3, 0.0, "test base"));
  CHECK_FALSE(d.command(0.0, -kInf, "test base"));
  CHECK(d.targetLeft() == 0.0);
  CHECK(d.targetRight() == 0.0);
}

TEST_CASE("DiffDrive: the acceleration limit ramps each wheel toward its target",
          "[sim][drive]") {
  DiffDrive d(DiffDrive::Options{0.258, 0.5, 1.0});  // 1 m/s^2
  REQUIRE(d.command(0.2, 0.0, "test base"));
  CHECK(d.v() == 0.0);  // nothing yet: the wheels ramp when time passes
  d.advance(0.1);
  CHECK(d.v() == Approx(0.1));
  d.advance(0.1);
  d.advance(0.1);
  CHECK(d.v() == Approx(0.2));  // reached, not passed
  // A stop for a non-finite command ramps down too (the motors cannot stop at once)...
  CHECK_FALSE(d.command(kNan, kNan, "test base"));
  d.advance(0.05);
  CHECK(d.v() == Approx(0.15));
  // ... and halt() (a teleport) is at once.
  d.halt();
  CHECK(d.v() == 0.0);
}

TEST_CASE("DiffDrive: options name the bad field", "[sim][drive]") {
  CHECK(DiffDrive::Options{}.validate());
  CHECK_THAT((DiffDrive::Options{0.0, 0.5, 0.0}.validate().error().message),
             Catch::Contains("wheel_base"));
  CHECK_THAT((DiffDrive::Options{0.258, kNan, 0.0}.validate().error().message),
             Catch::Contains("max_wheel_speed"));
  CHECK_THAT((DiffDrive::Options{0.258, 0.5, -1.0}.validate().error().message),
             Catch::Contains("max_wheel_acceleration"));
}

TEST_CASE("DiffDrive: KinematicBase and WhiskeredRobot take the same commands alike",
          "[sim][drive]") {
  const auto world = sim::World::build(openFloor());
  sim::KinematicBase kin(*world, sim::KinematicBase::Options{0.258, 0.5, {2.0, 2.0, 0.0}, 0.5});
  sim::WhiskeredRobot::Options ro;
  ro.max_wheel_acceleration = 0.5;
  auto made = sim::WhiskeredRobot::create(*world, defaultWhiskerArray(), ro);
  REQUIRE(made);
  sim::WhiskeredRobot& ode = *made.value();
  ode.place({2.0, 2.0, 0.0});

  struct Command {
    double v, omega;
    bool ok;
  };
  const Command commands[] = {{0.3, 0.0, true},   {0.4, 2.0, true}, {kNan, 0.0, false},
                              {-0.2, 0.5, true}, {0.0, kInf, false}, {0.0, 9.0, true}};
  const double dt = ro.dt;
  for (const Command& c : commands) {
    const Status a = kin.drive(c.v, c.omega);
    const Status b = ode.drive(c.v, c.omega);
    CHECK(static_cast<bool>(a) == c.ok);
    CHECK(static_cast<bool>(b) == c.ok);
    for (int i = 0; i < 200; ++i) {  // 0.1 s: the wheels ramp alike
      kin.step(dt);
      ode.step();
      REQUIRE(kin.leftWheel() == Approx(ode.wheelSpeeds().first).margin(1e-12));
      REQUIRE(kin.rightWheel() == Approx(ode.wheelSpeeds().second).margin(1e-12));
    }
  }
  // The same arcs: the poses agree (the ODE base integrates per substep, the kinematic one per
  // step; both exact arcs of piecewise-constant wheel speeds).
  CHECK(kin.odometry().x == Approx(ode.odometry().x).margin(1e-4));
  CHECK(kin.odometry().y == Approx(ode.odometry().y).margin(1e-4));
  CHECK(wrapPi(kin.odometry().theta - ode.odometry().theta) == Approx(0.0).margin(1e-4));
}
