// A differential-drive base with pure kinematics: the Create's geometry and limits (OI spec:
// wheel base 0.258 m, |wheel| <= 0.5 m/s) and bumpers against the scene's walls and legs
// (World::bodyCollides). What the Create emulator (create_emulator.h) drives in tests and in
// fast simulations; the ODE WhiskeredRobot is the other MobileBase the emulator can drive.
//
// drive(v, omega) sets the wheel speeds right/left = v +- omega b/2, both scaled down by one
// factor when a wheel would exceed the limit (the path's curvature is kept); non-finite input
// stops. step(dt) advances the clock by dt and moves the body along the exact arc of those
// wheel speeds; if the new pose collides, the move is refused (the body stays put) and bumped()
// turns true; it turns false again at the next step that moves the body. odometry() is the true
// pose (this base has no wheel slip).
// Thread-safety: none. Allocation: none after construction.
#pragma once

#include "crunch/robot/mobile_base.h"
#include "crunch_sim/world.h"

namespace crunch::sim {

class KinematicBase final : public MobileBase {
 public:
  struct Options {
    double wheel_base = 0.258;      // metres
    double max_wheel_speed = 0.5;   // m/s per wheel
    Pose2 start{};
  };

  // No obstacles: an open floor.
  explicit KinematicBase(const Options& options) : KinematicBase(nullptr, options) {}
  KinematicBase() : KinematicBase(Options{}) {}
  // Bumps against `world`, which must outlive the base.
  KinematicBase(const World& world, const Options& options) : KinematicBase(&world, options) {}

  Status drive(double v, double omega) override;
  Pose2 odometry() const override { return pose_; }
  bool bumped() const override { return bumped_; }
  double now() const override { return time_; }

  // Advances time by dt seconds (dt <= 0 or non-finite: nothing happens).
  void step(double dt);
  // Teleports to `pose` (not checked for collision), clears the bump.
  void place(const Pose2& pose) {
    pose_ = pose;
    bumped_ = false;
  }

  double commandedV() const { return v_; }        // after clamping, m/s
  double commandedOmega() const { return omega_; }  // after clamping, rad/s
  double rightWheel() const { return right_; }    // m/s
  double leftWheel() const { return left_; }
  std::uint64_t refusedMoves() const { return refused_; }

 private:
  KinematicBase(const World* world, const Options& options)
      : world_(world), options_(options), pose_(options.start) {}

  const World* world_;
  Options options_;
  Pose2 pose_;
  double time_ = 0.0;
  double right_ = 0.0, left_ = 0.0;
  double v_ = 0.0, omega_ = 0.0;
  bool bumped_ = false;
  std::uint64_t refused_ = 0;
};

}  // namespace crunch::sim
