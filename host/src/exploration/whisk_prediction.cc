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
  for (const MapLeg& l : sample.legs) legs.push_back(OrientedRect{l.pose, l.side, l.side});
  walls.assign(sample.walls.begin(), sample.walls.end());
  walls.insert(walls.end(), fixed.begin(), fixed.end());
  prepare();
}

namespace {
LegFrame frameOf(const OrientedRect& r) {
  return {r.pose.position(), std::cos(r.pose.theta), std::sin(r.pose.theta), 0.5 * r.size_x,
          0.5 * r.size_y, r.circumradius()};
}

// rayRect on a prepared square.
double rayFrame(const Vec2& origin, const Vec2& dir, double length, const LegFrame& f) {
  const double dx = origin.x() - f.centre.x(), dy = origin.y() - f.centre.y();
  const double o[2] = {f.c * dx + f.s * dy, -f.s * dx + f.c * dy};
  const double d[2] = {f.c * dir.x() + f.s * dir.y(), -f.s * dir.x() + f.c * dir.y()};
  const double h[2] = {f.hx, f.hy};
  double t0 = 0.0, t1 = length;
  for (int k = 0; k < 2; ++k) {
    if (std::abs(d[k]) < 1e-12) {
      if (o[k] < -h[k] || o[k] > h[k]) return -1.0;
      continue;
    }
    double ta = (-h[k] - o[k]) / d[k], tb = (h[k] - o[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return -1.0;
  }
  return t0;
}
}  // namespace

void WhiskObstacles::prepare() {
  frames.clear();
  for (const OrientedRect& r : legs) frames.push_back(frameOf(r));
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
  for (const WhiskerMount& m : mounts_) {
    // Largest angle between the whisker's direction and the line from the centre to a point of
    // it (0 for a radial whisker, the default array's), plus a margin for rounding.
    const double a0 = m.base.norm() > 1e-9 ? std::abs(wrapPi(std::atan2(m.base.y(), m.base.x()) - m.bearing)) : 0.0;
    const Vec2 tip = m.base + m.length * m.direction();
    const double a1 = std::abs(wrapPi(std::atan2(tip.y(), tip.x()) - m.bearing));
    spread_.push_back(std::max(a0, a1) + 1e-6);
  }
  for (const double o : offsets_) {
    const Pose2 turned{0.0, 0.0, o};
    for (const WhiskerMount& m : mounts_) {
      base_.push_back(turned.toWorld(m.base));
      dir_.push_back({std::cos(o + m.bearing), std::sin(o + m.bearing)});
    }
  }
}

void WhiskPredictor::nearReach(const Vec2& c, const WhiskObstacles& obs, std::vector<int>& legs,
                               std::vector<int>& walls) const {
  const bool prepared = obs.frames.size() == obs.legs.size();
  for (size_t i = 0; i < obs.legs.size(); ++i) {
    const OrientedRect& r = obs.legs[i];
    const double lim = reach_ + (prepared ? obs.frames[i].radius : r.circumradius());
    if ((r.pose.position() - c).squaredNorm() <= lim * lim) legs.push_back(static_cast<int>(i));
  }
  for (size_t i = 0; i < obs.walls.size(); ++i)
    if (distanceToSegment(c, obs.walls[i].a, obs.walls[i].b) <= reach_)
      walls.push_back(static_cast<int>(i));
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
  near_legs_.clear();
  near_walls_.clear();
  nearReach(pose.position(), obs, near_legs_, near_walls_);
  predictNear(pose, obs, near_legs_, near_walls_, out);
}

void WhiskPredictor::predictNear(const Pose2& pose, const WhiskObstacles& obs,
                                 std::span<const int> legs, std::span<const int> walls,
                                 std::vector<WhiskerContact>& out) {
  out.assign(mounts_.size(), WhiskerContact{});
  if (legs.empty() && walls.empty()) return;
  const bool prepared = obs.frames.size() == obs.legs.size();
  const int n_legs = static_cast<int>(obs.legs.size());
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  const Vec2 at = pose.position();
  const size_t nm = mounts_.size();
  // Angular screen: a leg at bearing phi from the centre, distance r, half-diagonal rho, can
  // meet a whisker only while the whisker's direction is within asin(rho / r) plus the
  // whisker's own angular spread (base off the radial line) of phi. Walls are not screened.
  leg_phi_.clear();
  leg_halfwidth_.clear();
  for (const int i : legs) {
    const size_t j = static_cast<size_t>(i);
    const Vec2 d = obs.legs[j].pose.position() - at;
    const double r = d.norm();
    const double rho = prepared ? obs.frames[j].radius : obs.legs[j].circumradius();
    leg_phi_.push_back(std::atan2(d.y(), d.x()));
    leg_halfwidth_.push_back(r <= rho ? kPi : std::asin(rho / r));
  }
  const double amp = options_.amplitude;
  for (size_t w = 0; w < nm; ++w) {
    const double length = mounts_[w].length;
    WhiskerContact& o = out[w];
    // The legs this whisker can meet during the sweep, and the offset window for each.
    rel_.clear();
    for (size_t q = 0; q < legs.size(); ++q) {
      const double delta = wrapPi(leg_phi_[q] - pose.theta - mounts_[w].bearing);
      const double half = leg_halfwidth_[q] + spread_[w];
      if (std::abs(delta) <= amp + half) rel_.push_back({q, delta - half, delta + half});
    }
    if (rel_.empty() && walls.empty()) continue;
    for (size_t k = 0; k < offsets_.size(); ++k) {
      const double off = offsets_[k];
      bool any = !walls.empty();
      for (const Window& r : rel_) any = any || (off >= r.lo && off <= r.hi);
      if (!any) continue;
      const Vec2& lb = base_[k * nm + w];
      const Vec2& ld = dir_[k * nm + w];
      const Vec2 base{at.x() + c * lb.x() - s * lb.y(), at.y() + s * lb.x() + c * lb.y()};
      const Vec2 dir{c * ld.x() - s * ld.y(), s * ld.x() + c * ld.y()};
      double best = std::numeric_limits<double>::infinity();
      int object = -1;
      for (const Window& r : rel_) {
        if (off < r.lo || off > r.hi) continue;
        const size_t j = static_cast<size_t>(legs[r.q]);
        const double t = prepared ? rayFrame(base, dir, length, obs.frames[j])
                                  : rayRect(base, dir, length, obs.legs[j]);
        if (t >= 0.0 && t < best) best = t, object = legs[r.q];
      }
      for (const int i : walls) {
        const MapWall& wall = obs.walls[static_cast<size_t>(i)];
        const double t = raySegment(base, dir, length, wall.a, wall.b);
        if (t >= 0.0 && t < best) best = t, object = n_legs + i;
      }
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
