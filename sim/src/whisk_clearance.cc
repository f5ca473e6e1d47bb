#include "crunch_sim/whisk_clearance.h"

#include <algorithm>
#include <cmath>

namespace crunch::sim {

bool inPlaceWhiskClear(const World& world, std::span<const WhiskerMount> mounts, const Pose2& pose,
                       double from, double to, double margin) {
  if (!(std::isfinite(pose.x) && std::isfinite(pose.y) && std::isfinite(pose.theta) &&
        std::isfinite(from) && std::isfinite(to) && std::isfinite(margin)) ||
      !(margin > 0.0) || from > to) {
    return false;
  }
  // reach: the whisker point farthest from the turning centre (a segment's farthest point from
  // any point is one of its ends).
  double reach = 0.0;
  for (const WhiskerMount& m : mounts) {
    if (!(m.base.allFinite() && std::isfinite(m.bearing) && std::isfinite(m.length))) return false;
    const Vec2 tip = m.base + m.length * Vec2(std::cos(m.bearing), std::sin(m.bearing));
    reach = std::max({reach, m.base.norm(), tip.norm()});
  }
  // Headings `step` apart, so that a whisker between two of them is within reach * step / 2
  // (<= margin / 4) of where it was at the nearer one.
  const double slack_max = 0.25 * margin;
  const int intervals =
      reach > 0.0 ? std::max(1, static_cast<int>(std::ceil((to - from) * reach / (2.0 * slack_max))))
                  : 1;
  const double step = (to - from) / intervals;
  const double slack = 0.5 * reach * step;
  const double needed = margin + slack;

  const Vec2 centre = pose.position();
  for (const OrientedRect& box : world.footprints()) {
    // A box whose every point is farther than reach + needed from the centre cannot come within
    // `needed` of a whisker.
    if ((box.pose.position() - centre).norm() - box.circumradius() > reach + needed) continue;
    for (int k = 0; k <= intervals; ++k) {
      const Pose2 at{pose.x, pose.y, pose.theta + from + k * step};
      for (const WhiskerMount& m : mounts) {
        const Vec2 base = at.toWorld(m.base);
        const double a = at.theta + m.bearing;
        const Vec2 tip = base + m.length * Vec2(std::cos(a), std::sin(a));
        if (distanceRectSegment(box, base, tip) <= needed) return false;
      }
    }
  }
  return true;
}

bool straightPathClear(const World& world, std::span<const WhiskerMount> mounts, const Pose2& from,
                       double distance, double margin) {
  if (!(std::isfinite(from.x) && std::isfinite(from.y) && std::isfinite(from.theta) &&
        std::isfinite(distance) && std::isfinite(margin)) ||
      !(margin > 0.0) || distance < 0.0) {
    return false;
  }
  const int intervals = std::max(1, static_cast<int>(std::ceil(distance / (0.5 * margin))));
  const double step = distance / intervals;
  const double needed = margin + 0.5 * step;
  const Vec2 along{std::cos(from.theta), std::sin(from.theta)};
  for (int k = 0; k <= intervals; ++k) {
    const Vec2 at = from.position() + (k * step) * along;
    if (!inPlaceWhiskClear(world, mounts, Pose2{at.x(), at.y(), from.theta}, 0.0, 0.0, needed)) {
      return false;
    }
  }
  return true;
}

}  // namespace crunch::sim
