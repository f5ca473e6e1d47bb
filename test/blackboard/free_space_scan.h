// The brute-force references for FreeSpaceGrid::maxInSquare and addRay (free_space.h): the scan
// the grid used before issue 15 and the ray walk it used before the division-free one, kept
// verbatim over the grid's public layout. The tests compare the grid with them cell for cell,
// and bench/free_space_bench.cc times the scan as the baseline.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

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

// Adds one pass to counts[iy * cellsX() + ix] for every cell the ray's samples at a quarter
// cell apart fall in, each cell once per ray: the walk addRay made with a division per sample.
inline void walkRay(const FreeSpaceGrid& g, const FreeRay& ray, std::vector<int>& counts) {
  const double len = (ray.b - ray.a).norm();
  const int steps = std::max(1, static_cast<int>(std::ceil(len / (0.25 * g.cell()))));
  int last_x = -1, last_y = -1;
  for (int i = 0; i <= steps; ++i) {
    const Vec2 p = ray.a + (ray.b - ray.a) * (static_cast<double>(i) / steps);
    const double fx = std::floor((p.x() - g.origin().x()) / g.cell());
    const double fy = std::floor((p.y() - g.origin().y()) / g.cell());
    if (!(fx >= 0 && fy >= 0 && fx < g.cellsX() && fy < g.cellsY())) continue;
    const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
    if (ix == last_x && iy == last_y) continue;
    last_x = ix;
    last_y = iy;
    ++counts[static_cast<size_t>(iy) * static_cast<size_t>(g.cellsX()) + static_cast<size_t>(ix)];
  }
}

}  // namespace crunch::test
