#include "crunch_sim/kinematic_base.h"

#include <algorithm>
#include <cmath>

namespace crunch::sim {

Status KinematicBase::drive(double v, double omega) {
  if (!std::isfinite(v) || !std::isfinite(omega)) {
    v = 0.0;
    omega = 0.0;
  }
  const double b = options_.wheel_base;
  double right = v + 0.5 * omega * b;
  double left = v - 0.5 * omega * b;
  const double biggest = std::max(std::abs(right), std::abs(left));
  if (biggest > options_.max_wheel_speed) {
    const double s = options_.max_wheel_speed / biggest;
    right *= s;
    left *= s;
  }
  right_ = right;
  left_ = left;
  v_ = 0.5 * (right + left);
  omega_ = (right - left) / b;
  return okStatus();
}

void KinematicBase::step(double dt) {
  if (!(dt > 0) || !std::isfinite(dt)) return;
  time_ += dt;
  if (v_ == 0.0 && omega_ == 0.0) return;
  // The exact arc of constant wheel speeds.
  const double dtheta = omega_ * dt;
  const double d = v_ * dt;
  // Chord length along the mid heading: d * sinc(dtheta / 2).
  const double half = 0.5 * dtheta;
  const double chord = std::abs(half) < 1e-9 ? d : d * std::sin(half) / half;
  Pose2 next = pose_;
  next.x += chord * std::cos(pose_.theta + half);
  next.y += chord * std::sin(pose_.theta + half);
  next.theta = wrapPi(pose_.theta + dtheta);
  if (world_ != nullptr && world_->bodyCollides(next)) {
    bumped_ = true;
    ++refused_;
    return;
  }
  pose_ = next;
  bumped_ = false;
}

}  // namespace crunch::sim
