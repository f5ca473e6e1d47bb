// The brute-force reference for FreeSpaceGrid::maxInSquare (free_space.h): the scan the grid
// used before issue 15, kept verbatim over the grid's public layout. The tests compare the
// look-up with it cell for cell, and bench/free_space_bench.cc times it as the baseline.
#pragma once

#include <algorithm>
#include <cmath>

#include "crunch/blackboard/free_space.h"

namespace crunch::test {

// Visits the cells of the core's bounding box and keeps those whose centre is inside the core.
inline int scanMaxInSquare(const FreeSpaceGrid& g, const Pose2& pose, double side,
                           double margin) {
  const double h = 0.5 * side - margin;
  if (h <= 0) return g.count(pose.position());
  const double reach = h * std::sqrt(2.0);
  const Vec2 origin = g.origin();
  const double cell = g.cell();
  const Vec2 lo = pose.position() - Vec2{reach, reach}, hi = pose.position() + Vec2{reach, reach};
  const int x0 = std::max(0, static_cast<int>(std::floor((lo.x() - origin.x()) / cell)));
  const int y0 = std::max(0, static_cast<int>(std::floor((lo.y() - origin.y()) / cell)));
  const int x1 = std::min(g.cellsX() - 1, static_cast<int>(std::floor((hi.x() - origin.x()) / cell)));
  const int y1 = std::min(g.cellsY() - 1, static_cast<int>(std::floor((hi.y() - origin.y()) / cell)));
  int best = 0;
  for (int iy = y0; iy <= y1; ++iy) {
    for (int ix = x0; ix <= x1; ++ix) {
      const Vec2 c = origin + Vec2{(ix + 0.5) * cell, (iy + 0.5) * cell};
      const Vec2 q = pose.toLocal(c);
      if (std::abs(q.x()) > h || std::abs(q.y()) > h) continue;
      best = std::max(best, g.countAt(ix, iy));
    }
  }
  return best;
}

}  // namespace crunch::test
