// Small builders for blackboard tests: shapelets as a whisker would report them off a table.
#pragma once

#include <vector>

#include "crunch/blackboard/params.h"
#include "crunch/core/geometry.h"
#include "crunch/robot/shapelet.h"

namespace crunch::testing {

// A shapelet on face `face` (0:+x,1:+y,2:-x,3:-y of the leg frame) of a leg, `along` metres from
// the face centre, sensed from 0.1 m outside that face.
inline Shapelet MakeShapelet(const Pose2& leg, double side, int face, double along = 0.0) {
  const double h = 0.5 * side;
  const Vec2 n_local[4] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
  const Vec2 t_local[4] = {{0, 1}, {-1, 0}, {0, -1}, {1, 0}};
  const Vec2 p = leg.toWorld(h * n_local[face] + along * t_local[face]);
  const Vec2 o = leg.toWorld((h + 0.1) * n_local[face]);
  Shapelet s;
  s.x = p.x();
  s.y = p.y();
  s.phi = wrapPeriod(leg.theta + (face % 2 == 0 ? kPi / 2 : 0.0), kPi);
  s.ox = o.x();
  s.oy = o.y();
  return s;
}

// Leg centre poses of a table hypothesis with the model's geometry.
inline Pose2 LegOf(const Pose2& table, const ModelParams& p, int corner) {
  const Vec2 c = table.toWorld(p.cornerOffset(corner));
  return {c.x(), c.y(), table.theta};
}

// Shapelets off two outward faces of each listed corner's leg.
inline std::vector<Shapelet> TableShapelets(const Pose2& table, const ModelParams& p,
                                            std::vector<int> corners) {
  std::vector<Shapelet> out;
  for (int c : corners) {
    const Pose2 leg = LegOf(table, p, c);
    const int fx = (c == 0 || c == 3) ? 0 : 2;  // outward x face
    const int fy = (c < 2) ? 1 : 3;             // outward y face
    out.push_back(MakeShapelet(leg, p.leg_side, fx, 0.01));
    out.push_back(MakeShapelet(leg, p.leg_side, fy, -0.005));
  }
  return out;
}

}  // namespace crunch::testing
