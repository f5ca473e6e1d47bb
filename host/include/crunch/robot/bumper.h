// The front bumper's two switches and where a bump was (the Create's: one bumper across the
// front half of the body, a switch at each end; Open Interface packet 7, bit 0 right, bit 1
// left). A hit near straight ahead closes both switches, a hit from one side only that side's.
//
// Which switches close (bumperAt): both within kBumperBothHalfAngle of ahead, else the side of
// the hit's bearing. The half-angle is an assumption: iRobot publishes no figure; 15 degrees is
// the sector where a push on a two-switch hinged bumper presses both, read off the Create's
// mechanics (the bumper pivots at its middle), and nothing below depends on a scene.
//
// Where the body was hit, given the switches (expectedBumpBearing): the mean bearing of the hit
// over the sector those switches report, for a body driving straight at an obstacle whose lateral
// offset from the path is uniform over the body's width. A point at lateral offset y (|y| < R)
// meets the round front at bearing a = asin(y / R), so the bearing's density is cos(a) on
// (-pi/2, pi/2) and the mean over a sector [lo, hi] is
//   E[a] = [a sin a + cos a]_lo^hi / [sin a]_lo^hi.
// Both switches: 0. One switch: over [kBumperBothHalfAngle, pi/2], 41.5 degrees to that side.
// (Without the switches, bearing 0 - the body's front on its heading - is 33 degrees off the
// hit on average, more than a table leg's width at the rim; with them, 13 degrees.)
//
// Plain functions; thread-safe.
#pragma once

#include <cstdint>

#include "crunch/core/geometry.h"

namespace crunch {

// The switches pressed; the values are packet 7's bits (kBumpRight 0x01, kBumpLeft 0x02).
enum class Bumper : std::uint8_t { kReleased = 0, kRight = 1, kLeft = 2, kBoth = 3 };

inline constexpr double kBumperBothHalfAngle = 15.0 * kPi / 180.0;  // radians, see above

// The switches a hit at `bearing` (radians from the heading, counter-clockwise) closes; bearings
// behind the front half count as the nearer side.
Bumper bumperAt(double bearing);

// The expected bearing of the hit (radians from the heading) given the switches pressed;
// kReleased (a wheel drop only) and kBoth: 0.
double expectedBumpBearing(Bumper bumper);

// The expected point of the hit on a round body of radius `radius` at `pose`.
Vec2 expectedBumpPoint(const Pose2& pose, Bumper bumper, double radius);

}  // namespace crunch
