#include "crunch/robot/shapelet.h"

#include <algorithm>
#include <cmath>

namespace crunch {
namespace {

bool finite(const Pose2& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.theta);
}

}  // namespace

bool toShapelet(const ContactReport& rep, const std::vector<WhiskerMount>& mounts, int pose_index,
                Shapelet& out) {
  // A whisker index outside the array is treated like any other malformed report: it is
  // rejected and counted by the caller, never allowed to crash the mapping loop.
  if (rep.whisker < 0 || static_cast<size_t>(rep.whisker) >= mounts.size()) return false;
  const WhiskerMount& m = mounts[static_cast<size_t>(rep.whisker)];
  if (!std::isfinite(rep.r) || !std::isfinite(rep.phi) || !finite(rep.robot)) return false;
  // A noisy estimate a little past either end is still a contact on this whisker: the
  // estimator's answer is clamped to the whisker. One far outside it is not a measurement.
  if (rep.r < -m.length || rep.r > 2.0 * m.length) return false;
  if (!(rep.face_span >= 0.0 && rep.face_span < 1e3)) return false;
  const double r = std::clamp(rep.r, 0.0, m.length);

  const Vec2 contact = m.pointAt(rep.robot, r);
  const Vec2 origin = rep.robot.toWorld(m.base);

  out.x = contact.x();
  out.y = contact.y();
  out.phi = wrapHalfTurn(rep.phi + rep.robot.theta);
  out.tau = 1.0;
  out.oriented = rep.oriented;
  out.face_span = rep.face_span;
  out.ox = origin.x();
  out.oy = origin.y();
  out.pose_index = pose_index;
  out.whisker = rep.whisker;
  return true;
}

}  // namespace crunch
