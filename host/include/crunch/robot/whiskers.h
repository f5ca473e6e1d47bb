// The robot's description: its body and the whiskers mounted on it (paper §2.2). Everything
// that turns a whisker's egocentric reading into a place in the world needs this, so it lies
// below sensing (signal/, io/, session/) and inference (blackboard/, mapping/) alike.
#pragma once

#include <cmath>
#include <vector>

#include "crunch/core/geometry.h"

namespace crunch {

// One whisker's mount on the robot, in the robot frame.
struct WhiskerMount {
  Vec2 base;         // follicle position, metres
  double bearing;    // direction the whisker points, radians from the robot's +x
  double length;     // external length, metres

  // Unit vector along the whisker, robot frame.
  Vec2 direction() const { return {std::cos(bearing), std::sin(bearing)}; }
  // The point r metres along the straight whisker from its base, arena frame, with the robot
  // at `robot` (eqs. 4-6: where a report at r puts its contact).
  Vec2 pointAt(const Pose2& robot, double r) const { return robot.toWorld(base + r * direction()); }
};

// The four horizontal front whiskers of the paper's mapping experiment (§2.2). Bases on the
// front rim of the 0.33 m Create-sized body at bearings -33.75, -11.25, +11.25, +33.75 degrees,
// pointing radially outward, 0.14 m external length. Over the four compass headings of a pose
// the 16 whisker directions are then evenly 22.5 degrees apart (docs/DESIGN.md).
std::vector<WhiskerMount> defaultWhiskerArray();

inline constexpr double kRobotRadius = 0.165;  // Create-sized cylinder, 0.33 m diameter

}  // namespace crunch
