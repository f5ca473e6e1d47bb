// A differential-drive base with pure kinematics: the Create's geometry and limits (OI spec:
// wheel base 0.258 m, |wheel| <= 0.5 m/s) and bumpers against the scene's walls and legs
// (World::bodyCollides). What the Create emulator (create_emulator.h) drives in tests and in
// fast simulations; the ODE WhiskeredRobot is the other MobileBase the emulator can drive.
//
// drive(v, omega) is the simulated Create's one command handling (DiffDrive, diff_drive.h, shared
// with WhiskeredRobot): wheel speeds right/left = v +- omega b/2, both scaled down by one factor
// when a wheel would exceed the limit (the path's curvature is kept), ramped at
// Options::max_wheel_acceleration if set (0, the default: at once); non-finite input stops the
// base and returns an Error (until issue 11 it stopped and returned ok). step(dt) advances the
// clock by dt, ramps the wheels over dt, and moves the body along the exact arc of the wheel
// speeds then in effect; if the new pose collides, the move is refused (the body stays put) and
// bumped() turns true, with bumper() the switches a hit at the bearing of the nearest wall or leg
// point would close (robot/bumper.h); it turns false again at the next step that moves the
// body. odometry() is the true pose (this base has no wheel slip). The options must be valid
// (DiffDrive::Options::validate; asserted).
// Thread-safety: none. Allocation: none after construction.
#pragma once

#include "crunch/robot/mobile_base.h"
#include "crunch_sim/diff_drive.h"
#include "crunch_sim/world.h"

namespace crunch::sim {

class KinematicBase final : public MobileBase {
 public:
  struct Options {
    double wheel_base = 0.258;      // metres
    double max_wheel_speed = 0.5;   // m/s per wheel
    Pose2 start{};
    double max_wheel_acceleration = 0.0;  // m/s^2 per wheel; 0: the wheels take a command at once
  };

  // No obstacles: an open floor.
  explicit KinematicBase(const Options& options) : KinematicBase(nullptr, options) {}
  KinematicBase() : KinematicBase(Options{}) {}
  // Bumps against `world`, which must outlive the base.
  KinematicBase(const World& world, const Options& options) : KinematicBase(&world, options) {}

  Status drive(double v, double omega) override;
  Pose2 odometry() const override { return pose_; }
  bool bumped() const override { return bumper_ != Bumper::kReleased; }
  Bumper bumper() const override { return bumper_; }
  double now() const override { return time_; }

  // Advances time by dt seconds (dt <= 0 or non-finite: nothing happens).
  void step(double dt);
  // Teleports to `pose` (not checked for collision), clears the bump.
  void place(const Pose2& pose) {
    pose_ = pose;
    bumper_ = Bumper::kReleased;
  }

  double commandedV() const { return wheels_.v(); }          // in effect, after clamping, m/s
  double commandedOmega() const { return wheels_.omega(); }  // in effect, rad/s
  double rightWheel() const { return wheels_.right(); }      // m/s
  double leftWheel() const { return wheels_.left(); }
  std::uint64_t refusedMoves() const { return refused_; }

 private:
  KinematicBase(const World* world, const Options& options)
      : world_(world),
        options_(options),
        wheels_(DiffDrive::Options{options.wheel_base, options.max_wheel_speed,
                                   options.max_wheel_acceleration}),
        pose_(options.start) {}

  const World* world_;
  Options options_;
  DiffDrive wheels_;
  Pose2 pose_;
  double time_ = 0.0;
  Bumper bumper_ = Bumper::kReleased;
  std::uint64_t refused_ = 0;
};

}  // namespace crunch::sim
