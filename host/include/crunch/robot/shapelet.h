// Contact reports and shapelets (paper eqs. 4-6). A whisker reports an egocentric radial
// distance r along the whisker and a surface orientation phi; with the robot's (exact) pose the
// report becomes an allocentric shapelet S(x, y, phi, tau).
#pragma once

#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/robot/whiskers.h"

namespace crunch {

// An egocentric contact report from one whisker (eqs. 4-5).
struct ContactReport {
  int whisker = 0;    // index into the whisker array
  double r = 0.0;     // radial distance from the base along the whisker, metres
  double phi = 0.0;   // surface orientation in the robot frame, radians, modulo pi
  Pose2 robot;        // robot pose when the report was taken (exact: zero odometry noise)
  // phi was measured (a flat surface); false: an edge or a point, whose orientation is unknown
  // and whose shapelet has no angle term (blackboard/factors.h).
  bool oriented = true;
  // Length of one flat face the contact is known to lie on, metres: the distance between two
  // whiskers' located tips on it (session/whisk_evidence.h); 0 when unknown. A face longer than
  // a leg's diagonal is no leg's (factors.h).
  double face_span = 0.0;
};

// An allocentric shapelet (the observation node of the blackboard).
struct Shapelet {
  double x = 0.0, y = 0.0;
  double phi = 0.0;     // surface orientation, modulo pi
  double tau = 1.0;     // texture; all surfaces have tau = 1 in the present system
  bool oriented = true;  // phi measured (ContactReport::oriented)
  double face_span = 0.0;  // ContactReport::face_span, metres
  double ox = 0.0, oy = 0.0;  // where it was sensed from (the whisker base): the free side
  int pose_index = -1;
  int whisker = -1;
};

// A whisker sample that touched nothing: the whole whisker from base to tip was free (negative
// evidence, blackboard/free_space.h).
struct FreeRay {
  Vec2 a, b;
};

// Converts a report to a shapelet with the report's robot pose; r is clamped to [0, length]
// (noise can carry a tip contact past the tip). Returns false (and leaves `out` alone) for a
// non-finite report, a bad whisker index, or r outside [-length, 2 length]: such reports are
// counted and never enter the blackboard.
bool toShapelet(const ContactReport& rep, const std::vector<WhiskerMount>& mounts,
                int pose_index, Shapelet& out);

}  // namespace crunch
