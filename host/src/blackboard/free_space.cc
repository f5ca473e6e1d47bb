#include "crunch/blackboard/free_space.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace crunch {

namespace {

// The widening of the analytic cell ranges (metres). The scan's own rounding error on a cell
// centre's local coordinates is a few ulp of the arena's coordinates (1e-14 m for a 20 m floor),
// so a cell 1 nm outside the exact outline is outside for the scan's arithmetic too, and one
// 1 nm inside is inside. Holds for arenas up to about a kilometre.
constexpr double kSafe = 1e-9;

// The whole cells c with c0 <= c and a <= origin + (c + 0.5) cell <= b, clamped to [c0, c1];
// empty (first > last) when none. Clamps before converting, so far-off bounds stay in range.
void cellRange(double a, double b, double origin, double cell, int c0, int c1, int& first,
               int& last) {
  const double fa = std::ceil((a - origin) / cell - 0.5);
  const double fb = std::floor((b - origin) / cell - 0.5);
  first = fa > c0 ? (fa > c1 ? c1 + 1 : static_cast<int>(fa)) : c0;
  last = fb < c1 ? (fb < c0 ? c0 - 1 : static_cast<int>(fb)) : c1;
}

// Narrows [lo, hi] to the u with |a u + b| <= bound.
void clampLinear(double a, double b, double bound, double& lo, double& hi) {
  if (a == 0.0) {
    if (std::abs(b) > bound) hi = lo - 1.0;  // empty
    return;
  }
  const double u0 = (-bound - b) / a, u1 = (bound - b) / a;
  lo = std::max(lo, std::min(u0, u1));
  hi = std::min(hi, std::max(u0, u1));
}

}  // namespace

// Read-only zeros shared by every grid: a tile no ray reached (in .rodata: a write would fault).
const FreeSpaceGrid::Tile FreeSpaceGrid::kZeroTile = {};

FreeSpaceGrid::FreeSpaceGrid(const Vec2& lo, const Vec2& hi, double cell) : lo_(lo), cell_(cell) {
  nx_ = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) / cell)));
  ny_ = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / cell)));
  tiles_x_ = (nx_ + kTile - 1) / kTile;
  const int tiles_y = (ny_ + kTile - 1) / kTile;
  tiles_.assign(static_cast<size_t>(tiles_x_) * static_cast<size_t>(tiles_y), kZeroTile.v);
}

uint16_t& FreeSpaceGrid::slot(int plane, int ix, int iy) {
  const uint16_t*& tile = tiles_[tileOf(ix, iy)];
  if (tile == kZeroTile.v) {
    owned_.push_back(std::make_unique<Tile>());  // value-initialised: zeros
    tile = owned_.back()->v;
  }
  // Not the shared zero tile, so one of owned_'s: writable.
  return const_cast<uint16_t*>(tile)[inTile(plane, ix, iy)];
}

bool FreeSpaceGrid::index(const Vec2& p, int& ix, int& iy) const {
  // floor(q) without libm's call (the hot path of every ray and every free-space look-up): for
  // q >= 0 truncation is floor, and floor(q) >= 0, floor(q) < n hold exactly when q >= 0, q < n
  // for an integer n; NaN fails both.
  const double qx = (p.x() - lo_.x()) / cell_;
  const double qy = (p.y() - lo_.y()) / cell_;
  if (!(qx >= 0 && qy >= 0 && qx < nx_ && qy < ny_)) return false;
  ix = static_cast<int>(qx);
  iy = static_cast<int>(qy);
  return true;
}

void FreeSpaceGrid::addRay(const FreeRay& ray) {
  ++rays_;
  const double len = (ray.b - ray.a).norm();
  const int steps = std::max(1, static_cast<int>(std::ceil(len / (0.25 * cell_))));
  // The samples p_i = a + (b - a) i / steps, each in the cell index() puts it in. Their cell
  // coordinates are read as q_i = q0 + i dq, without a division; that differs from index()'s own
  // arithmetic by far less than kEdge cells (a few ulp of the arena's extent in cells: 1e-10 for
  // a 200 m arena at 1 cm), so where it lies kEdge or more from every cell edge it names
  // index()'s cell, and elsewhere index() decides. q_i is monotone in i on each axis (rounding
  // is), so when samples i and j are both clear inside one cell, every sample between them is
  // in it too: a duplicate, skipped. The cells are index()'s, bit for bit, visiting about two
  // samples per cell crossed instead of four.
  constexpr double kEdge = 1e-6;
  const double inv = 1.0 / cell_;
  const Vec2 d = ray.b - ray.a;
  const double qx0 = (ray.a.x() - lo_.x()) * inv, qy0 = (ray.a.y() - lo_.y()) * inv;
  const double dqx = d.x() * inv / steps, dqy = d.y() * inv / steps;
  // Whether q lies clear inside cell c of an axis of n cells.
  const auto clearIn = [](double q, int c) { return q >= c + kEdge && q <= c + 1 - kEdge; };
  const auto clear = [&](double q, int n, int& c) {
    if (!(q >= kEdge && q < n - kEdge)) return false;
    c = static_cast<int>(q);
    return clearIn(q, c);
  };
  // The last sample index whose q on this axis the cell's clear interval still bounds.
  const auto lastIn = [&](double q0, double dq, int c) {
    if (dq == 0.0) return steps;
    const double k = dq > 0 ? (c + 1 - kEdge - q0) / dq : (c + kEdge - q0) / dq;
    return k >= steps ? steps : static_cast<int>(k);  // k >= the current sample's index >= 0
  };
  int last_x = -1, last_y = -1;
  for (int i = 0; i <= steps; ++i) {
    const double qx = qx0 + i * dqx, qy = qy0 + i * dqy;
    int ix, iy;
    if (clear(qx, nx_, ix) && clear(qy, ny_, iy)) {
      // Skip to the last sample still clear inside this cell (checked, not trusted).
      const int j = std::min(lastIn(qx0, dqx, ix), lastIn(qy0, dqy, iy));
      if (j > i && clearIn(qx0 + j * dqx, ix) && clearIn(qy0 + j * dqy, iy)) i = j;
    } else if (qx < -kEdge || qy < -kEdge || qx >= nx_ + kEdge || qy >= ny_ + kEdge ||
               !(qx == qx && qy == qy)) {
      continue;  // outside the grid (or NaN) by more than the error: index() says so too
    } else if (!index(ray.a + d * (static_cast<double>(i) / steps), ix, iy)) {
      continue;
    }
    if (ix == last_x && iy == last_y) continue;
    last_x = ix;
    last_y = iy;
    if (value(0, ix, iy) == std::numeric_limits<uint16_t>::max()) continue;
    const uint16_t c = ++slot(0, ix, iy);
    if (c <= window_cap_) raise(ix, iy, c);  // past the cap every window already holds it
  }
}

void FreeSpaceGrid::addSweep(const Vec2& a, const Vec2& b, double radius, int passes) {
  if (!(radius >= 0) || passes <= 0 || !std::isfinite(a.x()) || !std::isfinite(a.y()) ||
      !std::isfinite(b.x()) || !std::isfinite(b.y()))
    return;
  ++rays_;
  const Vec2 d = b - a;
  const double len2 = d.squaredNorm();
  const auto cellOf = [this](double v, double lo) { return static_cast<int>(std::floor((v - lo) / cell_)); };
  const int x0 = std::max(0, cellOf(std::min(a.x(), b.x()) - radius, lo_.x()));
  const int y0 = std::max(0, cellOf(std::min(a.y(), b.y()) - radius, lo_.y()));
  const int x1 = std::min(nx_ - 1, cellOf(std::max(a.x(), b.x()) + radius, lo_.x()));
  const int y1 = std::min(ny_ - 1, cellOf(std::max(a.y(), b.y()) + radius, lo_.y()));
  const double r2 = radius * radius;
  for (int iy = y0; iy <= y1; ++iy) {
    for (int ix = x0; ix <= x1; ++ix) {
      const Vec2 c = lo_ + Vec2((ix + 0.5) * cell_, (iy + 0.5) * cell_);
      const double t = len2 > 0 ? std::clamp((c - a).dot(d) / len2, 0.0, 1.0) : 0.0;
      if ((c - (a + t * d)).squaredNorm() > r2) continue;
      const int old = value(0, ix, iy);
      const int v = std::min<int>(std::numeric_limits<uint16_t>::max(), old + passes);
      if (v == old) continue;
      slot(0, ix, iy) = static_cast<uint16_t>(v);
      if (old < window_cap_) raise(ix, iy, static_cast<uint16_t>(std::min<int>(v, window_cap_)));
    }
  }
}

void FreeSpaceGrid::raise(int ix, int iy, uint16_t v) {
  // Every window of side 2s containing the cell contains the window of side s that holds the
  // cell in its quarter, and every stored maximum is exact: once no window of side s needed
  // raising, none of the larger ones does either.
  for (int j = 1; j <= kLevels; ++j) {
    const int s = 1 << j;
    bool raised = false;
    for (int y = std::max(0, iy - s + 1); y <= iy; ++y) {
      for (int x = std::max(0, ix - s + 1); x <= ix; ++x) {
        if (value(j, x, y) < v) {
          slot(j, x, y) = v;
          raised = true;
        }
      }
    }
    if (!raised) return;
  }
}

int FreeSpaceGrid::count(const Vec2& p) const {
  int ix, iy;
  if (!index(p, ix, iy)) return 0;
  return value(0, ix, iy);
}

int FreeSpaceGrid::countAt(int ix, int iy) const {
  if (ix < 0 || iy < 0 || ix >= nx_ || iy >= ny_) return 0;
  return value(0, ix, iy);
}

bool FreeSpaceGrid::sweptBounds(int& x0, int& y0, int& x1, int& y1) const {
  x0 = y0 = std::numeric_limits<int>::max();
  x1 = y1 = -1;
  const int tiles_y = static_cast<int>(tiles_.size()) / std::max(tiles_x_, 1);
  for (int ty = 0; ty < tiles_y; ++ty) {
    for (int tx = 0; tx < tiles_x_; ++tx) {
      const uint16_t* tile = tiles_[static_cast<size_t>(ty) * static_cast<size_t>(tiles_x_) +
                                    static_cast<size_t>(tx)];
      if (tile == kZeroTile.v) continue;  // no ray reached it
      for (int j = 0; j < kTile; ++j) {
        for (int i = 0; i < kTile; ++i) {
          if (tile[static_cast<size_t>((j << kTileBits) | i)] == 0) continue;  // plane 0: counts
          const int ix = (tx << kTileBits) + i, iy = (ty << kTileBits) + j;
          x0 = std::min(x0, ix);
          y0 = std::min(y0, iy);
          x1 = std::max(x1, ix);
          y1 = std::max(y1, iy);
        }
      }
    }
  }
  return x1 >= 0;
}

int FreeSpaceGrid::boxMax(int x0, int y0, int x1, int y1) const {
  // Windows of the largest side s that fits the box's shorter side, the last one in each
  // direction pulled back to end on the box's edge: 2 x 2 look-ups when the box is at most 2s
  // each way (any near-square box up to 8 cells), more for longer or larger boxes.
  const int shorter = std::min(x1 - x0, y1 - y0) + 1;
  const int j = std::min(kLevels, static_cast<int>(std::bit_width(static_cast<unsigned>(shorter))) - 1);
  const int s = 1 << j;
  int best = 0;
  for (int y = y0;; y += s) {
    const int wy = std::min(y, y1 - s + 1);
    for (int x = x0;; x += s) {
      const int wx = std::min(x, x1 - s + 1);
      best = std::max<int>(best, value(j, wx, wy));
      if (wx + s > x1) break;
    }
    if (wy + s > y1) break;
  }
  return best;
}

void FreeSpaceGrid::setWindowCap(int cap) {
  const int most = std::numeric_limits<uint16_t>::max();
  window_cap_ = static_cast<uint16_t>(std::clamp(cap, 0, most));
}

void FreeSpaceGrid::setRoom(const Vec2& lo, const Vec2& hi) {
  ++rays_;
  room_ = true;
  room_lo_ = lo;
  room_hi_ = hi;
}

int FreeSpaceGrid::maxInSquare(const Pose2& pose, double side, double margin) const {
  if (outsideRoom(pose.x, pose.y)) return std::numeric_limits<uint16_t>::max();
  const double h = 0.5 * side - margin;
  if (h <= 0) return count(pose.position());
  // The cells of the core's bounding box, as the reference scan (free_space_scan.h) takes them.
  const double reach = h * std::sqrt(2.0);
  int x0, y0, x1, y1;
  if (!cellBox(pose.position() - Vec2{reach, reach}, pose.position() + Vec2{reach, reach}, x0, y0,
               x1, y1))
    return 0;
  const int upper = boxMax(x0, y0, x1, y1);
  if (upper == 0) return 0;
  // The core, turned by any angle, holds the axis-aligned square of half-side h / sqrt(2) about
  // its centre (h / (|cos| + |sin|) at its own angle: not worth the trigonometry here); shrunk
  // by kSafe, the scan counts each of its cells in.
  const double g = h * std::sqrt(0.5) - kSafe;
  if (g > 0) {
    int ix0, ix1, iy0, iy1;
    cellRange(pose.x - g, pose.x + g, lo_.x(), cell_, x0, x1, ix0, ix1);
    cellRange(pose.y - g, pose.y + g, lo_.y(), cell_, y0, y1, iy0, iy1);
    if (ix0 <= ix1 && iy0 <= iy1 && boxMax(ix0, iy0, ix1, iy1) == upper) return upper;
  }
  return scanCore(pose, h, x0, y0, x1, y1, upper);
}

bool FreeSpaceGrid::sweptNear(const Vec2& p, double reach) const {
  if (outsideRoom(p.x(), p.y())) return true;
  if (!(reach >= 0.0) || !std::isfinite(p.x()) || !std::isfinite(p.y())) return false;
  int x0, y0, x1, y1;
  return cellBox(p - Vec2{reach, reach}, p + Vec2{reach, reach}, x0, y0, x1, y1) &&
         boxMax(x0, y0, x1, y1) > 0;
}

bool FreeSpaceGrid::cellBox(const Vec2& lo, const Vec2& hi, int& x0, int& y0, int& x1,
                            int& y1) const {
  x0 = std::max(0, static_cast<int>(std::floor((lo.x() - lo_.x()) / cell_)));
  y0 = std::max(0, static_cast<int>(std::floor((lo.y() - lo_.y()) / cell_)));
  x1 = std::min(nx_ - 1, static_cast<int>(std::floor((hi.x() - lo_.x()) / cell_)));
  y1 = std::min(ny_ - 1, static_cast<int>(std::floor((hi.y() - lo_.y()) / cell_)));
  return x0 <= x1 && y0 <= y1;
}

int FreeSpaceGrid::scanCore(const Pose2& pose, double h, int x0, int y0, int x1, int y1,
                            int upper) const {
  // Pose2::toLocal's arithmetic with cos and sin taken once: the same bits per cell.
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  // A NaN angle makes every local coordinate NaN, which the scan's test lets through.
  if (std::isnan(c) || std::isnan(s)) return upper;
  const double wide = h + kSafe;
  int best = 0;
  for (int iy = y0; iy <= y1; ++iy) {
    const double dy = (lo_.y() + (iy + 0.5) * cell_) - pose.y;
    // The x offsets whose local coordinates are within h + kSafe: q.x = c dx + s dy and
    // q.y = -s dx + c dy.
    double dlo = -std::numeric_limits<double>::infinity();
    double dhi = std::numeric_limits<double>::infinity();
    clampLinear(c, s * dy, wide, dlo, dhi);
    clampLinear(-s, c * dy, wide, dlo, dhi);
    if (!(dlo <= dhi)) continue;
    int ix0, ix1;
    cellRange(pose.x + dlo, pose.x + dhi, lo_.x(), cell_, x0, x1, ix0, ix1);
    for (int ix = ix0; ix <= ix1; ++ix) {
      const int n = value(0, ix, iy);
      if (n <= best) continue;
      const double dx = (lo_.x() + (ix + 0.5) * cell_) - pose.x;
      const double qx = c * dx + s * dy, qy = -s * dx + c * dy;
      if (std::abs(qx) > h || std::abs(qy) > h) continue;
      best = n;
      if (best == upper) return best;
    }
  }
  return best;
}

}  // namespace crunch
