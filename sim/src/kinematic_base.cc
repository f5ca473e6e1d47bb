#include "crunch_sim/kinematic_base.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace crunch::sim {

Status KinematicBase::drive(double v, double omega) {
  return wheels_.command(v, omega, "simulated base (KinematicBase)");
}

void KinematicBase::step(double dt) {
  if (!(dt > 0) || !std::isfinite(dt)) return;
  time_ += dt;
  wheels_.advance(dt);
  const double v = wheels_.v(), omega = wheels_.omega();
  if (v == 0.0 && omega == 0.0) return;
  // The exact arc of constant wheel speeds.
  const double dtheta = omega * dt;
  const double d = v * dt;
  // Chord length along the mid heading: d * sinc(dtheta / 2).
  const double half = 0.5 * dtheta;
  const double chord = std::abs(half) < 1e-9 ? d : d * std::sin(half) / half;
  Pose2 next = pose_;
  next.x += chord * std::cos(pose_.theta + half);
  next.y += chord * std::sin(pose_.theta + half);
  next.theta = wrapPi(pose_.theta + dtheta);
  if (world_ != nullptr && world_->bodyCollides(next)) {
    const std::optional<Vec2> hit = world_->nearestSurfacePoint(next.position());
    const Vec2 to = hit ? *hit - next.position() : Vec2(std::cos(next.theta), std::sin(next.theta));
    bumper_ = bumperAt(std::atan2(to.y(), to.x()) - next.theta);
    ++refused_;
    return;
  }
  pose_ = next;
  bumper_ = Bumper::kReleased;
}

}  // namespace crunch::sim
