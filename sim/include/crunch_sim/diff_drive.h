// The wheels of a simulated differential-drive base: how a drive(v, omega) command becomes the
// two wheel speeds, written once for both simulated MobileBases (KinematicBase and the ODE
// WhiskeredRobot), so that the Create emulator, the behaviours and the tests see one simulated
// Create whichever body is behind it.
//
//   command(v, omega)  wheel targets right/left = v +- omega b/2 (b the wheel base); if either
//                      exceeds max_wheel_speed, both are scaled down by one factor, so the
//                      path's curvature omega/v is kept and only the speed along it drops (as the
//                      Create driver's io::oi::twistToWheels does). Non-finite v or omega: the
//                      targets become zero (the base stops) and an Error says so.
//   advance(h)         the wheels move toward their targets at most max_wheel_acceleration * h
//                      each (0: they take the targets at once, in command()).
//   halt()             both wheels and targets at zero at once (a teleported base).
//
// Thread-safety: none. Allocation: none.
#pragma once

#include "crunch/core/result.h"

namespace crunch::sim {

class DiffDrive {
 public:
  struct Options {
    double wheel_base = 0.258;           // metres (Create, OI specification)
    double max_wheel_speed = 0.5;        // m/s per wheel (Create, OI specification)
    double max_wheel_acceleration = 0.0;  // m/s^2 per wheel; 0: no limit

    // Finite wheel_base and max_wheel_speed > 0, finite max_wheel_acceleration >= 0; an Error
    // naming the field otherwise.
    Status validate() const;
  };

  DiffDrive() : DiffDrive(Options{}) {}
  // Asserts valid options (the bases validate theirs first).
  explicit DiffDrive(const Options& options);

  // Sets the wheel targets (see the top of this file). Error (the base stops) for non-finite
  // input; `who` names the base in the message.
  Status command(double v, double omega, const char* who);
  // Ramps the wheels toward their targets over h seconds (h > 0).
  void advance(double h);
  // Stops at once: wheels and targets zero.
  void halt();

  double left() const { return left_; }    // wheel speeds in effect, m/s
  double right() const { return right_; }
  double v() const { return 0.5 * (left_ + right_); }                    // m/s
  double omega() const { return (right_ - left_) / options_.wheel_base; }  // rad/s
  double targetLeft() const { return target_left_; }
  double targetRight() const { return target_right_; }
  // The last command was scaled down to fit the wheel limit.
  bool clamped() const { return clamped_; }
  const Options& options() const { return options_; }

 private:
  Options options_;
  double left_ = 0.0, right_ = 0.0;
  double target_left_ = 0.0, target_right_ = 0.0;
  bool clamped_ = false;
};

}  // namespace crunch::sim
