// TEMPORARY (i14-infogain only, reverted before merging DRIVE's part): minimal KnownSpace,
// Costmap and DistanceField so the infogain/entropy policies can be unit-tested before DRIVE's
// implementations are on main.
#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>

#include "crunch/exploration/known_space.h"
#include "crunch/exploration/path_planner.h"

namespace crunch::exploration {

KnownSpace::KnownSpace(const Vec2& lo, const Vec2& hi, double cell) : lo_(lo), cell_(cell) {
  nx_ = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) / cell)));
  ny_ = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / cell)));
  swept_.assign(static_cast<size_t>(nx_ * ny_), 0);
  touched_ = swept_;
  mapped_ = swept_;
}
bool KnownSpace::index(const Vec2& p, int& ix, int& iy) const {
  ix = static_cast<int>(std::floor((p.x() - lo_.x()) / cell_));
  iy = static_cast<int>(std::floor((p.y() - lo_.y()) / cell_));
  return ix >= 0 && iy >= 0 && ix < nx_ && iy < ny_;
}
bool KnownSpace::outside(const Vec2& p) const {
  int ix, iy;
  return !index(p, ix, iy);
}
void KnownSpace::markFreeRay(const FreeRay& ray) {
  const Vec2 d = ray.b - ray.a;
  const int n = std::max(1, static_cast<int>(std::ceil(d.norm() / (0.25 * cell_))));
  for (int k = 0; k <= n; ++k) {
    int ix, iy;
    if (index(ray.a + d * (double(k) / n), ix, iy)) swept_[static_cast<size_t>(iy * nx_ + ix)] = 1;
  }
}
void KnownSpace::markBody(const Vec2& p, double r) {
  for (int iy = 0; iy < ny_; ++iy)
    for (int ix = 0; ix < nx_; ++ix)
      if ((centre(ix, iy) - p).norm() <= r) swept_[static_cast<size_t>(iy * nx_ + ix)] = 1;
}
void KnownSpace::markContact(const Vec2& p) {
  int ix, iy;
  if (index(p, ix, iy)) touched_[static_cast<size_t>(iy * nx_ + ix)] = 1;
}
void KnownSpace::setMapObstacles(std::span<const MapTable>, std::span<const MapWall>) {}
KnownSpace::Cell KnownSpace::at(int ix, int iy) const {
  if (ix < 0 || iy < 0 || ix >= nx_ || iy >= ny_) return Cell::kOccupied;
  const size_t i = static_cast<size_t>(iy * nx_ + ix);
  if (touched_[i] || mapped_[i]) return Cell::kOccupied;
  return swept_[i] ? Cell::kFree : Cell::kUnknown;
}
KnownSpace::Cell KnownSpace::at(const Vec2& p) const {
  int ix, iy;
  if (!index(p, ix, iy)) return Cell::kOccupied;
  return at(ix, iy);
}
bool KnownSpace::frontier(int, int) const { return false; }
double KnownSpace::knownFraction() const { return 0.0; }

Costmap::Costmap(const KnownSpace& known, const PlannerOptions& options)
    : known_(known), options_(options) {
  const int nx = known.nx(), ny = known.ny();
  blocked_.assign(static_cast<size_t>(nx * ny), 0);
  const double r = options.robot_radius + options.margin;
  const int k = static_cast<int>(std::ceil(r / known.cell()));
  for (int iy = 0; iy < ny; ++iy)
    for (int ix = 0; ix < nx; ++ix) {
      const Vec2 c = known.centre(ix, iy);
      if (c.x() - known.lo().x() < r || c.y() - known.lo().y() < r ||
          known.hi().x() - c.x() < r || known.hi().y() - c.y() < r) {
        blocked_[static_cast<size_t>(iy * nx + ix)] = 1;
        continue;
      }
      if (known.at(ix, iy) != KnownSpace::Cell::kOccupied) continue;
      for (int dy = -k; dy <= k; ++dy)
        for (int dx = -k; dx <= k; ++dx) {
          const int jx = ix + dx, jy = iy + dy;
          if (jx < 0 || jy < 0 || jx >= nx || jy >= ny) continue;
          if ((known.centre(jx, jy) - c).norm() <= r) blocked_[static_cast<size_t>(jy * nx + jx)] = 1;
        }
    }
}
bool Costmap::blocked(int ix, int iy) const {
  if (ix < 0 || iy < 0 || ix >= known_.nx() || iy >= known_.ny()) return true;
  return blocked_[static_cast<size_t>(iy * known_.nx() + ix)] != 0;
}
bool Costmap::blocked(const Vec2& p) const {
  int ix, iy;
  if (!known_.index(p, ix, iy)) return true;
  return blocked(ix, iy);
}

DistanceField::DistanceField(const Costmap& costmap, const Vec2& from) : costmap_(costmap) {
  const KnownSpace& k = costmap.known();
  const int nx = k.nx(), ny = k.ny();
  dist_.assign(static_cast<size_t>(nx * ny), std::numeric_limits<double>::infinity());
  int sx, sy;
  if (!k.index(from, sx, sy)) return;
  using Q = std::pair<double, int>;
  std::priority_queue<Q, std::vector<Q>, std::greater<Q>> open;
  dist_[static_cast<size_t>(sy * nx + sx)] = 0.0;
  open.push({0.0, sy * nx + sx});
  while (!open.empty()) {
    auto [d, i] = open.top();
    open.pop();
    if (d > dist_[static_cast<size_t>(i)]) continue;
    const int ix = i % nx, iy = i / nx;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (!dx && !dy) continue;
        const int jx = ix + dx, jy = iy + dy;
        if (costmap.blocked(jx, jy)) continue;
        const double step = k.cell() * ((dx && dy) ? std::sqrt(2.0) : 1.0) *
                            (k.at(jx, jy) == KnownSpace::Cell::kUnknown ? costmap.options().unknown_cost : 1.0);
        const size_t j = static_cast<size_t>(jy * nx + jx);
        if (d + step < dist_[j]) {
          dist_[j] = d + step;
          open.push({dist_[j], jy * nx + jx});
        }
      }
  }
}
double DistanceField::to(int ix, int iy) const {
  const KnownSpace& k = costmap_.known();
  if (ix < 0 || iy < 0 || ix >= k.nx() || iy >= k.ny()) return std::numeric_limits<double>::infinity();
  return dist_[static_cast<size_t>(iy * k.nx() + ix)];
}
double DistanceField::to(const Vec2& p) const {
  int ix, iy;
  if (!costmap_.known().index(p, ix, iy)) return std::numeric_limits<double>::infinity();
  return to(ix, iy);
}

}  // namespace crunch::exploration
