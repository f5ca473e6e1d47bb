#include "crunch/core/geometry.h"

#include <algorithm>
#include <limits>

namespace crunch {

PerimeterPoint closestOnPerimeter(const OrientedRect& r, const Vec2& p) {
  return closestOnPerimeter(r, p, std::cos(r.pose.theta), std::sin(r.pose.theta));
}

PerimeterPoint closestOnPerimeter(const OrientedRect& r, const Vec2& p, double c, double s) {
  const Vec2 q = r.pose.toLocal(p, c, s);
  const double hx = 0.5 * r.size_x, hy = 0.5 * r.size_y;
  // Candidate on each face: clamp along the face.
  const std::array<Vec2, 4> cand = {Vec2{hx, std::clamp(q.y(), -hy, hy)},
                                    Vec2{std::clamp(q.x(), -hx, hx), hy},
                                    Vec2{-hx, std::clamp(q.y(), -hy, hy)},
                                    Vec2{std::clamp(q.x(), -hx, hx), -hy}};
  PerimeterPoint best;
  best.distance = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 4; ++i) {
    const double d = (cand[i] - q).norm();
    if (d < best.distance) {
      best.distance = d;
      best.side = i;
      best.point = cand[i];
    }
  }
  best.point = r.pose.toWorld(best.point, c, s);
  return best;
}

namespace {
// Projects the rectangle onto axis n; returns [min, max].
std::pair<double, double> project(const std::array<Vec2, 4>& c, const Vec2& n) {
  double lo = c[0].dot(n), hi = lo;
  for (int i = 1; i < 4; ++i) {
    const double v = c[i].dot(n);
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  return {lo, hi};
}
}  // namespace

bool overlaps(const OrientedRect& a, const OrientedRect& b) {
  const double dx = a.pose.x - b.pose.x, dy = a.pose.y - b.pose.y;
  const double reach = a.circumradius() + b.circumradius();
  if (dx * dx + dy * dy >= reach * reach) return false;
  return overlaps(a, {std::cos(a.pose.theta), std::sin(a.pose.theta), a.circumradius()}, b,
                  {std::cos(b.pose.theta), std::sin(b.pose.theta), b.circumradius()});
}

bool overlaps(const OrientedRect& a, const RectTrig& ta, const OrientedRect& b,
              const RectTrig& tb) {
  const double dx = a.pose.x - b.pose.x, dy = a.pose.y - b.pose.y;
  const double reach = ta.radius + tb.radius;
  if (dx * dx + dy * dy >= reach * reach) return false;
  const auto ca = a.corners(ta.c, ta.s), cb = b.corners(tb.c, tb.s);
  const std::array<Vec2, 4> axes = {Vec2{ta.c, ta.s}, Vec2{-ta.s, ta.c}, Vec2{tb.c, tb.s},
                                    Vec2{-tb.s, tb.c}};
  constexpr double kTouch = 1e-9;  // touching faces do not count as overlap
  for (const Vec2& n : axes) {
    const auto [alo, ahi] = project(ca, n);
    const auto [blo, bhi] = project(cb, n);
    if (ahi <= blo + kTouch || bhi <= alo + kTouch) return false;
  }
  return true;
}

double distanceToSegment(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

Pose2 fitRigid(const Vec2* local, const Vec2* world, int n, double theta) {
  Vec2 lc{0.0, 0.0}, wc{0.0, 0.0};
  for (int i = 0; i < n; ++i) {
    lc += local[i];
    wc += world[i];
  }
  lc /= std::max(n, 1);
  wc /= std::max(n, 1);
  double sc = 0.0, ss = 0.0, spread = 0.0;
  for (int i = 0; i < n; ++i) {
    const Vec2 a = local[i] - lc, b = world[i] - wc;
    sc += a.dot(b);
    ss += a.x() * b.y() - a.y() * b.x();
    spread += a.squaredNorm();
  }
  const double th = spread > 0.0 ? std::atan2(ss, sc) : theta;
  const double c = std::cos(th), s = std::sin(th);
  const Vec2 t = wc - Vec2{c * lc.x() - s * lc.y(), s * lc.x() + c * lc.y()};
  return {t.x(), t.y(), wrapPeriod(th, 2.0 * kPi)};
}

namespace {
bool segmentsIntersect(const Vec2& p1, const Vec2& p2, const Vec2& q1, const Vec2& q2) {
  const double d1 = cross2d(q2 - q1, p1 - q1), d2 = cross2d(q2 - q1, p2 - q1);
  const double d3 = cross2d(p2 - p1, q1 - p1), d4 = cross2d(p2 - p1, q2 - p1);
  return ((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0));
}
}  // namespace

double distanceRectSegment(const OrientedRect& r, const Vec2& a, const Vec2& b) {
  const Vec2 la = r.pose.toLocal(a);
  const double hx = 0.5 * r.size_x, hy = 0.5 * r.size_y;
  if (std::abs(la.x()) <= hx && std::abs(la.y()) <= hy) return 0.0;
  const auto c = r.corners();
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 4; ++i) {
    const Vec2& c0 = c[i];
    const Vec2& c1 = c[(i + 1) % 4];
    if (segmentsIntersect(a, b, c0, c1)) return 0.0;
    best = std::min({best, distanceToSegment(c0, a, b), distanceToSegment(a, c0, c1),
                     distanceToSegment(b, c0, c1)});
  }
  return best;
}

}  // namespace crunch
