// The motion interface of a differential-drive base: what the behaviours (body whisk, §2.3)
// command, implemented by the Create's Open Interface driver on the robot (io/) and by the
// simulator's base (sim/). One interface, so `--sim` and `--robot` run the same behaviour code.
//
// Units: metres, seconds, radians, counter-clockwise positive. Commands hold until the next one.
// Time is the implementation's: the robot's clock runs by itself, the simulator's advances when
// it is stepped; behaviours read it through now() and never sleep.
// Thread-safety: none; one control loop owns a base.
#pragma once

#include "crunch/core/geometry.h"
#include "crunch/core/result.h"
#include "crunch/robot/bumper.h"

namespace crunch {

class MobileBase {
 public:
  virtual ~MobileBase() = default;

  // Forward speed v (m/s) and turn rate omega (rad/s) about the base's centre. An
  // implementation clamps to its limits (the Create: |wheel speed| <= 0.5 m/s) and says so in
  // its header. An Error names the device that did not take the command.
  virtual Status drive(double v, double omega) = 0;
  Status stop() { return drive(0.0, 0.0); }

  // The base's odometry pose (its own integration of wheel motion since start).
  virtual Pose2 odometry() const = 0;
  // A bumper or wheel drop is active: behaviours stop and back off.
  virtual bool bumped() const = 0;
  // Which of the front bumper's switches are pressed (robot/bumper.h); a wheel drop alone is
  // kReleased. A base that cannot tell the sides reports kBoth while bumped().
  virtual Bumper bumper() const { return bumped() ? Bumper::kBoth : Bumper::kReleased; }
  // Seconds since the base started (monotonic).
  virtual double now() const = 0;
};

}  // namespace crunch
