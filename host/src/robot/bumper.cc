#include "crunch/robot/bumper.h"

#include <cmath>

namespace crunch {
namespace {

// Mean of a under the density cos(a) on [lo, hi] (both within [-pi/2, pi/2]).
double meanBearing(double lo, double hi) {
  const auto primitive = [](double a) { return a * std::sin(a) + std::cos(a); };
  return (primitive(hi) - primitive(lo)) / (std::sin(hi) - std::sin(lo));
}

}  // namespace

Bumper bumperAt(double bearing) {
  const double a = wrapPi(bearing);
  if (std::abs(a) <= kBumperBothHalfAngle) return Bumper::kBoth;
  return a > 0.0 ? Bumper::kLeft : Bumper::kRight;
}

double expectedBumpBearing(Bumper bumper) {
  static const double side = meanBearing(kBumperBothHalfAngle, kPi / 2);
  switch (bumper) {
    case Bumper::kLeft:
      return side;
    case Bumper::kRight:
      return -side;
    case Bumper::kReleased:
    case Bumper::kBoth:
      break;
  }
  return 0.0;
}

Vec2 expectedBumpPoint(const Pose2& pose, Bumper bumper, double radius) {
  const double a = pose.theta + expectedBumpBearing(bumper);
  return pose.position() + radius * Vec2(std::cos(a), std::sin(a));
}

}  // namespace crunch
