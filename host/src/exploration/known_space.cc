#include "crunch/exploration/known_space.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace crunch::exploration {

namespace {
// Distance from p to the oriented rectangle r (0 inside).
double distanceToRect(const OrientedRect& r, const Vec2& p) {
  const Vec2 l = r.pose.toLocal(p);
  const double dx = std::max(std::abs(l.x()) - 0.5 * r.size_x, 0.0);
  const double dy = std::max(std::abs(l.y()) - 0.5 * r.size_y, 0.0);
  return std::hypot(dx, dy);
}
}  // namespace

KnownSpace::KnownSpace(const Vec2& lo, const Vec2& hi, double cell) : lo_(lo), cell_(cell) {
  assert(cell > 0.0 && std::isfinite(cell));
  nx_ = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) / cell - 1e-9)));
  ny_ = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / cell - 1e-9)));
  const std::size_t n = static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_);
  swept_.assign(n, 0);
  touched_.assign(n, 0);
  mapped_.assign(n, 0);
  visited_.assign(n, 0);
  bumped_.assign(n, 0);
}

bool KnownSpace::index(const Vec2& p, int& ix, int& iy) const {
  if (!std::isfinite(p.x()) || !std::isfinite(p.y())) return false;
  const double fx = std::floor((p.x() - lo_.x()) / cell_);
  const double fy = std::floor((p.y() - lo_.y()) / cell_);
  if (fx < 0 || fy < 0 || fx >= nx_ || fy >= ny_) return false;
  ix = static_cast<int>(fx);
  iy = static_cast<int>(fy);
  return true;
}

bool KnownSpace::outside(const Vec2& p) const {
  int ix, iy;
  return !index(p, ix, iy);
}

void KnownSpace::markFreeRay(const FreeRay& ray) {
  // Samples at a quarter cell: every cell the segment crosses by more than a corner's sliver.
  const Vec2 d = ray.b - ray.a;
  const double len = d.norm();
  if (!std::isfinite(len)) return;
  const int n = static_cast<int>(std::ceil(len / (0.25 * cell_))) + 1;
  for (int k = 0; k <= n; ++k) {
    int ix, iy;
    if (index(ray.a + d * (static_cast<double>(k) / n), ix, iy)) swept_[iy * nx_ + ix] = 1;
  }
}

void KnownSpace::markBody(const Vec2& position, double radius) {
  int cx, cy;
  if (!std::isfinite(radius) || radius < 0) return;
  const int r = static_cast<int>(std::ceil(radius / cell_)) + 1;
  if (!std::isfinite(position.x()) || !std::isfinite(position.y())) return;
  cx = static_cast<int>(std::floor((position.x() - lo_.x()) / cell_));
  cy = static_cast<int>(std::floor((position.y() - lo_.y()) / cell_));
  for (int iy = std::max(0, cy - r); iy <= std::min(ny_ - 1, cy + r); ++iy) {
    for (int ix = std::max(0, cx - r); ix <= std::min(nx_ - 1, cx + r); ++ix) {
      if ((centre(ix, iy) - position).norm() <= radius) swept_[iy * nx_ + ix] = 1;
    }
  }
}

void KnownSpace::markContact(const Vec2& point) {
  int ix, iy;
  if (index(point, ix, iy)) touched_[iy * nx_ + ix] = 1;
}

void KnownSpace::markBump(const Vec2& point) {
  int ix, iy;
  if (!index(point, ix, iy)) return;
  touched_[iy * nx_ + ix] = 1;
  bumped_[iy * nx_ + ix] = 1;
}

void KnownSpace::markVisited(const Vec2& a, const Vec2& b) {
  if (!a.allFinite() || !b.allFinite()) return;
  const Vec2 d = b - a;
  const int n = static_cast<int>(std::ceil(d.norm() / (0.25 * cell_))) + 1;
  int ix, iy;
  for (int k = 0; k <= n; ++k)
    if (index(a + d * (static_cast<double>(k) / n), ix, iy)) visited_[iy * nx_ + ix] = 1;
}

bool KnownSpace::visited(int ix, int iy) const {
  return ix >= 0 && iy >= 0 && ix < nx_ && iy < ny_ && visited_[iy * nx_ + ix];
}

bool KnownSpace::bumped(int ix, int iy) const {
  return ix >= 0 && iy >= 0 && ix < nx_ && iy < ny_ && bumped_[iy * nx_ + ix];
}

void KnownSpace::setMapObstacles(std::span<const MapTable> tables, std::span<const MapWall> walls) {
  std::fill(mapped_.begin(), mapped_.end(), 0);
  // A cell is covered when its centre lies within half a cell of the shape: a 5 cm leg on a
  // 5 cm grid always covers at least one cell.
  const double reach = 0.5 * cell_;
  auto cover = [&](const Vec2& lo, const Vec2& hi, auto&& dist) {
    int x0 = static_cast<int>(std::floor((lo.x() - reach - lo_.x()) / cell_));
    int y0 = static_cast<int>(std::floor((lo.y() - reach - lo_.y()) / cell_));
    int x1 = static_cast<int>(std::floor((hi.x() + reach - lo_.x()) / cell_));
    int y1 = static_cast<int>(std::floor((hi.y() + reach - lo_.y()) / cell_));
    x0 = std::max(x0, 0), y0 = std::max(y0, 0);
    x1 = std::min(x1, nx_ - 1), y1 = std::min(y1, ny_ - 1);
    for (int iy = y0; iy <= y1; ++iy) {
      for (int ix = x0; ix <= x1; ++ix) {
        if (dist(centre(ix, iy)) <= reach) mapped_[iy * nx_ + ix] = 1;
      }
    }
  };
  for (const MapTable& t : tables) {
    const TableSpec spec{t.pose, t.width, t.depth, t.leg};
    for (const OrientedRect& leg : spec.legs()) {
      if (!std::isfinite(leg.pose.x) || !std::isfinite(leg.pose.y)) continue;
      const double c = leg.circumradius();
      const Vec2 p = leg.pose.position();
      cover(p - Vec2(c, c), p + Vec2(c, c), [&](const Vec2& q) { return distanceToRect(leg, q); });
    }
  }
  for (const MapWall& w : walls) {
    if (!w.a.allFinite() || !w.b.allFinite()) continue;
    cover(w.a.cwiseMin(w.b), w.a.cwiseMax(w.b),
          [&](const Vec2& q) { return distanceToSegment(q, w.a, w.b); });
  }
}

KnownSpace::Cell KnownSpace::at(int ix, int iy) const {
  if (ix < 0 || iy < 0 || ix >= nx_ || iy >= ny_) return Cell::kOccupied;
  const int i = iy * nx_ + ix;
  if (touched_[i] || mapped_[i]) return Cell::kOccupied;
  return swept_[i] ? Cell::kFree : Cell::kUnknown;
}

KnownSpace::Cell KnownSpace::at(const Vec2& p) const {
  int ix, iy;
  if (!index(p, ix, iy)) return Cell::kOccupied;
  return at(ix, iy);
}

bool KnownSpace::frontier(int ix, int iy) const {
  if (at(ix, iy) != Cell::kUnknown) return false;
  static constexpr int kD[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  for (const auto& d : kD) {
    const int jx = ix + d[0], jy = iy + d[1];
    if (jx < 0 || jy < 0 || jx >= nx_ || jy >= ny_) continue;
    if (at(jx, jy) == Cell::kFree) return true;
  }
  return false;
}

double KnownSpace::knownFraction() const {
  std::size_t known = 0;
  for (std::size_t i = 0; i < swept_.size(); ++i) known += (swept_[i] | touched_[i] | mapped_[i]) ? 1 : 0;
  return static_cast<double>(known) / static_cast<double>(swept_.size());
}

}  // namespace crunch::exploration
