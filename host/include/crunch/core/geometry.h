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
  Vec2 toWorld(const Vec2& local) const {
    const double c = std::cos(theta), s = std::sin(theta);
    return {x + c * local.x() - s * local.y(), y + s * local.x() + c * local.y()};
  }
  // Maps a point from the arena frame into this pose's local frame.
  Vec2 toLocal(const Vec2& world) const {
    const double c = std::cos(theta), s = std::sin(theta);
    const double dx = world.x() - x, dy = world.y() - y;
    return {c * dx + s * dy, -s * dx + c * dy};
  }
};

// Wraps an angle into [-pi, pi).
inline double wrapPi(double a) {
  a = std::fmod(a + kPi, 2.0 * kPi);
  if (a < 0) a += 2.0 * kPi;
  return a - kPi;
}

// The pose `local`, given in the frame of `frame`, in the frame `frame` is given in (frame o
// local): e.g. the map pose of odometry `local` for a robot that started at `frame`.
inline Pose2 compose(const Pose2& frame, const Pose2& local) {
  const Vec2 p = frame.toWorld(local.position());
  return {p.x(), p.y(), wrapPi(frame.theta + local.theta)};
}

// Wraps an angle into [-period/2, period/2): the signed difference of two angles that are
// meaningful modulo `period` (pi for a line or a symmetric table, pi/2 for a square leg).
inline double wrapPeriod(double a, double period) {
  a = std::fmod(a + 0.5 * period, period);
  if (a < 0) a += period;
  return a - 0.5 * period;
}

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
  std::array<Vec2, 4> corners() const {
    const double hx = 0.5 * size_x, hy = 0.5 * size_y;
    return {pose.toWorld({hx, hy}), pose.toWorld({-hx, hy}), pose.toWorld({-hx, -hy}),
            pose.toWorld({hx, -hy})};
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

// True if the two rectangles' interiors intersect (separating-axis test).
bool overlaps(const OrientedRect& a, const OrientedRect& b);

// Distance from point p to the segment [a, b].
double distanceToSegment(const Vec2& p, const Vec2& a, const Vec2& b);

// Smallest distance between a rectangle's boundary/interior and a segment (0 if they touch).
double distanceRectSegment(const OrientedRect& r, const Vec2& a, const Vec2& b);

}  // namespace crunch
