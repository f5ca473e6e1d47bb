// Planar geometry shared by every area: poses, angle wrapping, oriented rectangles.
// Units: metres and radians, angles counter-clockwise from +x (ARCHITECTURE.md §4).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <numbers>

namespace crunch {

using Vec2 = Eigen::Vector2d;

inline constexpr double kPi = std::numbers::pi;

// A robot or object pose in the arena frame.
struct Pose2 {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;

  Vec2 position() const { return {x, y}; }
  // Maps a point from this pose's local frame into the arena frame.
  Vec2 toWorld(const Vec2& local) const { return toWorld(local, std::cos(theta), std::sin(theta)); }
  // The same with c = cos(theta), s = sin(theta) already known (a hot loop keeps them with the
  // pose instead of calling libm for every point: issue 15).
  Vec2 toWorld(const Vec2& local, double c, double s) const {
    return {x + c * local.x() - s * local.y(), y + s * local.x() + c * local.y()};
  }
  // Maps a point from the arena frame into this pose's local frame.
  Vec2 toLocal(const Vec2& world) const { return toLocal(world, std::cos(theta), std::sin(theta)); }
  Vec2 toLocal(const Vec2& world, double c, double s) const {
    const double dx = world.x() - x, dy = world.y() - y;
    return {c * dx + s * dy, -s * dx + c * dy};
  }
};

namespace detail {
// fmod(x, period) folded into [0, period) for x in [-period, 2 period) without the libm call,
// bit for bit what the fmod form gives (x - period is exact there by Sterbenz's lemma; fmod is
// exact, so x + period after a negative fmod is the same rounding); anything else takes fmod.
inline double foldPeriod(double x, double period) {
  if (x >= 0.0) {
    if (x < period) return x;
    if (x < 2.0 * period) return x - period;
  } else if (x >= -period) {
    return x + period;
  }
  double r = std::fmod(x, period);
  if (r < 0) r += period;
  return r;
}
}  // namespace detail

// Wraps an angle into [-pi, pi).
inline double wrapPi(double a) { return detail::foldPeriod(a + kPi, 2.0 * kPi) - kPi; }

// The pose `local`, given in the frame of `frame`, in the frame `frame` is given in (frame o
// local): e.g. the map pose of odometry `local` for a robot that started at `frame`.
inline Pose2 compose(const Pose2& frame, const Pose2& local) {
  const Vec2 p = frame.toWorld(local.position());
  return {p.x(), p.y(), wrapPi(frame.theta + local.theta)};
}

// Wraps an angle into [-period/2, period/2): the signed difference of two angles that are
// meaningful modulo `period` (pi for a line or a symmetric table, pi/2 for a square leg).
inline double wrapPeriod(double a, double period) {
  return detail::foldPeriod(a + 0.5 * period, period) - 0.5 * period;
}

// The 2-D cross product u x v (the z of the 3-D one): |u||v| sin of the angle from u to v.
inline double cross2d(const Vec2& u, const Vec2& v) { return u.x() * v.y() - u.y() * v.x(); }

// The difference of two line directions modulo pi, in [0, pi/2].
inline double lineAngleDiff(double a, double b) { return std::abs(wrapPeriod(a - b, kPi)); }

// An orientation modulo pi (a line's, a surface's), as a value in [0, pi).
inline double wrapHalfTurn(double a) {
  double w = wrapPeriod(a, kPi);
  if (w < 0.0) w += kPi;
  if (w >= kPi) w -= kPi;  // -tiny + pi can round up to pi
  return w;
}

// An oriented rectangle: centre pose and full side lengths along its own x and y.
struct OrientedRect {
  Pose2 pose;
  double size_x = 0.0;
  double size_y = 0.0;

  // Corners counter-clockwise starting at (+x, +y) in the local frame.
  std::array<Vec2, 4> corners() const { return corners(std::cos(pose.theta), std::sin(pose.theta)); }
  // The same with c, s the cosine and sine of pose.theta.
  std::array<Vec2, 4> corners(double c, double s) const {
    const double hx = 0.5 * size_x, hy = 0.5 * size_y;
    return {pose.toWorld({hx, hy}, c, s), pose.toWorld({-hx, hy}, c, s),
            pose.toWorld({-hx, -hy}, c, s), pose.toWorld({hx, -hy}, c, s)};
  }
  double circumradius() const { return 0.5 * std::hypot(size_x, size_y); }
};

// Closest point on the perimeter of `r` to `p`, with the index of the side it lies on
// (0: +x face, 1: +y face, 2: -x face, 3: -y face) and the unsigned distance to it.
struct PerimeterPoint {
  Vec2 point;
  int side = 0;
  double distance = 0.0;
};
PerimeterPoint closestOnPerimeter(const OrientedRect& r, const Vec2& p);
// The same with c, s the cosine and sine of r.pose.theta (the same result, no libm call).
PerimeterPoint closestOnPerimeter(const OrientedRect& r, const Vec2& p, double c, double s);

// True if the two rectangles' interiors intersect (separating-axis test).
bool overlaps(const OrientedRect& a, const OrientedRect& b);
// The same with each rectangle's cosine and sine of its angle and its circumradius known.
struct RectTrig {
  double c = 1.0, s = 0.0, radius = 0.0;
};
bool overlaps(const OrientedRect& a, const RectTrig& ta, const OrientedRect& b, const RectTrig& tb);

// Distance from point p to the segment [a, b].
double distanceToSegment(const Vec2& p, const Vec2& a, const Vec2& b);

// Smallest distance between a rectangle's boundary/interior and a segment (0 if they touch).
double distanceRectSegment(const OrientedRect& r, const Vec2& a, const Vec2& b);

// The rigid frame (rotation and translation, no scale) that best carries the points `local[i]`
// (in the frame) onto `world[i]`, i < n, in least squares: argmin over poses F of
// sum |F.toWorld(local[i]) - world[i]|^2 (2-D Procrustes, closed form: the centroids give the
// translation, the summed cross and dot products of the centred pairs the angle). n >= 2 with
// the local points not all equal; otherwise (nothing fixes the angle) the frame at angle
// `theta` that carries the centroid onto the centroid. theta of the result in [0, 2 pi).
Pose2 fitRigid(const Vec2* local, const Vec2* world, int n, double theta);

}  // namespace crunch
