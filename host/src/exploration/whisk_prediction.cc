#include "crunch/exploration/whisk_prediction.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <utility>

namespace crunch::exploration {

std::array<OrientedRect, 4> legSquares(const MapTable& t) {
  // As TableSpec::legs(): leg centres half a leg in from each corner of the top.
  const double hx = 0.5 * (t.width - t.leg), hy = 0.5 * (t.depth - t.leg);
  const std::array<Vec2, 4> local = {Vec2{hx, hy}, Vec2{-hx, hy}, Vec2{-hx, -hy}, Vec2{hx, -hy}};
  std::array<OrientedRect, 4> out;
  for (int i = 0; i < 4; ++i) {
    const Vec2 c = t.pose.toWorld(local[static_cast<size_t>(i)]);
    out[static_cast<size_t>(i)] = OrientedRect{Pose2{c.x(), c.y(), t.pose.theta}, t.leg, t.leg};
  }
  return out;
}

void WhiskObstacles::assign(const MapSample& sample, std::span<const MapWall> fixed) {
  clear();
  for (const MapTable& t : sample.tables)
    for (const OrientedRect& r : legSquares(t)) legs.push_back(r);
  walls.assign(sample.walls.begin(), sample.walls.end());
  walls.insert(walls.end(), fixed.begin(), fixed.end());
}

double rayRect(const Vec2& origin, const Vec2& dir, double length, const OrientedRect& r) {
  // Slab test in the rectangle's frame.
  const Vec2 o = r.pose.toLocal(origin);
  const double c = std::cos(r.pose.theta), s = std::sin(r.pose.theta);
  const Vec2 d{c * dir.x() + s * dir.y(), -s * dir.x() + c * dir.y()};
  const double h[2] = {0.5 * r.size_x, 0.5 * r.size_y};
  double t0 = 0.0, t1 = length;
  for (int k = 0; k < 2; ++k) {
    const double ok = o[k], dk = d[k];
    if (std::abs(dk) < 1e-12) {
      if (ok < -h[k] || ok > h[k]) return -1.0;
      continue;
    }
    double ta = (-h[k] - ok) / dk, tb = (h[k] - ok) / dk;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return -1.0;
  }
  return t0;  // 0 when the origin is inside (the whisker's base in a leg: touched at once)
}

double raySegment(const Vec2& origin, const Vec2& dir, double length, const Vec2& a,
                  const Vec2& b) {
  const Vec2 e = b - a;
  const double den = dir.x() * e.y() - dir.y() * e.x();
  if (std::abs(den) < 1e-12) return -1.0;  // parallel: a grazing whisker slides along
  const Vec2 w = a - origin;
  const double t = (w.x() * e.y() - w.y() * e.x()) / den;
  const double u = (w.x() * dir.y() - w.y() * dir.x()) / den;
  if (t < 0.0 || t > length || u < 0.0 || u > 1.0) return -1.0;
  return t;
}

WhiskPredictor::WhiskPredictor(std::vector<WhiskerMount> mounts, WhiskPredictionOptions options)
    : mounts_(std::move(mounts)), options_(options) {
  assert(options_.sweep_step > 0.0 && options_.amplitude >= 0.0);
  const double amp = options_.amplitude;
  const int n = amp > 0.0 ? static_cast<int>(std::ceil(amp / options_.sweep_step)) : 0;
  offsets_.push_back(0.0);
  for (int k = 1; k <= n; ++k) offsets_.push_back(amp * k / n);
  for (int k = 1; k <= n; ++k) offsets_.push_back(-amp * k / n);
  for (const WhiskerMount& m : mounts_) reach_ = std::max(reach_, (m.base + m.length * m.direction()).norm());
}

bool WhiskPredictor::anyInReach(const Vec2& position, const WhiskObstacles& obs) const {
  for (const OrientedRect& r : obs.legs)
    if ((r.pose.position() - position).norm() <= reach_ + r.circumradius()) return true;
  for (const MapWall& w : obs.walls)
    if (distanceToSegment(position, w.a, w.b) <= reach_) return true;
  return false;
}

void WhiskPredictor::predict(const Pose2& pose, const WhiskObstacles& obs,
                             std::vector<WhiskerContact>& out) {
  out.assign(mounts_.size(), WhiskerContact{});
  near_legs_.clear();
  near_walls_.clear();
  const Vec2 c = pose.position();
  for (size_t i = 0; i < obs.legs.size(); ++i) {
    const OrientedRect& r = obs.legs[i];
    if ((r.pose.position() - c).norm() <= reach_ + r.circumradius())
      near_legs_.push_back(static_cast<int>(i));
  }
  for (size_t i = 0; i < obs.walls.size(); ++i)
    if (distanceToSegment(c, obs.walls[i].a, obs.walls[i].b) <= reach_)
      near_walls_.push_back(static_cast<int>(i));
  if (near_legs_.empty() && near_walls_.empty()) return;
  const int n_legs = static_cast<int>(obs.legs.size());
  for (const double offset : offsets_) {
    const Pose2 at{pose.x, pose.y, pose.theta + offset};
    for (size_t w = 0; w < mounts_.size(); ++w) {
      const WhiskerMount& m = mounts_[w];
      const Vec2 base = at.toWorld(m.base);
      const double heading = at.theta + m.bearing;
      const Vec2 dir{std::cos(heading), std::sin(heading)};
      double best = std::numeric_limits<double>::infinity();
      int object = -1;
      for (const int i : near_legs_) {
        const double t = rayRect(base, dir, m.length, obs.legs[static_cast<size_t>(i)]);
        if (t >= 0.0 && t < best) best = t, object = i;
      }
      for (const int i : near_walls_) {
        const MapWall& wall = obs.walls[static_cast<size_t>(i)];
        const double t = raySegment(base, dir, m.length, wall.a, wall.b);
        if (t >= 0.0 && t < best) best = t, object = n_legs + i;
      }
      WhiskerContact& o = out[w];
      // Strictly smaller: on a tie the earlier sample of the whisk wins (as RaySensorModel).
      if (object >= 0 && (!o.hit || best < o.distance)) {
        o.hit = true;
        o.distance = best;
        o.point = base + best * dir;
        o.object = object;
      }
    }
  }
}

bool sameOutcome(std::span<const WhiskerContact> a, std::span<const WhiskerContact> b,
                 double resolution) {
  if (a.size() != b.size()) return false;
  const double r2 = resolution * resolution;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i].hit != b[i].hit) return false;
    if (a[i].hit && (a[i].point - b[i].point).squaredNorm() > r2) return false;
  }
  return true;
}

}  // namespace crunch::exploration
