#include "crunch/blackboard/free_space.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace crunch {

FreeSpaceGrid::FreeSpaceGrid(const Vec2& lo, const Vec2& hi, double cell) : lo_(lo), cell_(cell) {
  nx_ = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) / cell)));
  ny_ = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / cell)));
  counts_.assign(static_cast<size_t>(nx_) * static_cast<size_t>(ny_), 0);
}

bool FreeSpaceGrid::index(const Vec2& p, int& ix, int& iy) const {
  const double fx = std::floor((p.x() - lo_.x()) / cell_);
  const double fy = std::floor((p.y() - lo_.y()) / cell_);
  if (!(fx >= 0 && fy >= 0 && fx < nx_ && fy < ny_)) return false;
  ix = static_cast<int>(fx);
  iy = static_cast<int>(fy);
  return true;
}

void FreeSpaceGrid::addRay(const FreeRay& ray) {
  ++rays_;
  const double len = (ray.b - ray.a).norm();
  const int steps = std::max(1, static_cast<int>(std::ceil(len / (0.25 * cell_))));
  int last_x = -1, last_y = -1;
  for (int i = 0; i <= steps; ++i) {
    const Vec2 p = ray.a + (ray.b - ray.a) * (static_cast<double>(i) / steps);
    int ix, iy;
    if (!index(p, ix, iy) || (ix == last_x && iy == last_y)) continue;
    last_x = ix;
    last_y = iy;
    uint16_t& c = counts_[static_cast<size_t>(iy) * static_cast<size_t>(nx_) + static_cast<size_t>(ix)];
    if (c < std::numeric_limits<uint16_t>::max()) ++c;
  }
}

int FreeSpaceGrid::count(const Vec2& p) const {
  int ix, iy;
  if (!index(p, ix, iy)) return 0;
  return counts_[static_cast<size_t>(iy) * static_cast<size_t>(nx_) + static_cast<size_t>(ix)];
}

int FreeSpaceGrid::maxInSquare(const Pose2& pose, double side, double margin) const {
  const double h = 0.5 * side - margin;
  if (h <= 0) return count(pose.position());
  // Visit the cells of the core's bounding box; keep those whose centre is inside the core.
  const double reach = h * std::sqrt(2.0);
  int x0, y0, x1, y1;
  const Vec2 lo = pose.position() - Vec2{reach, reach}, hi = pose.position() + Vec2{reach, reach};
  x0 = std::max(0, static_cast<int>(std::floor((lo.x() - lo_.x()) / cell_)));
  y0 = std::max(0, static_cast<int>(std::floor((lo.y() - lo_.y()) / cell_)));
  x1 = std::min(nx_ - 1, static_cast<int>(std::floor((hi.x() - lo_.x()) / cell_)));
  y1 = std::min(ny_ - 1, static_cast<int>(std::floor((hi.y() - lo_.y()) / cell_)));
  int best = 0;
  for (int iy = y0; iy <= y1; ++iy) {
    for (int ix = x0; ix <= x1; ++ix) {
      const Vec2 c = lo_ + Vec2{(ix + 0.5) * cell_, (iy + 0.5) * cell_};
      const Vec2 q = pose.toLocal(c);
      if (std::abs(q.x()) > h || std::abs(q.y()) > h) continue;
      best = std::max<int>(best, counts_[static_cast<size_t>(iy) * static_cast<size_t>(nx_) +
                                         static_cast<size_t>(ix)]);
    }
  }
  return best;
}

}  // namespace crunch
