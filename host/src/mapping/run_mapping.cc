#include "crunch/mapping/run_mapping.h"

#include <algorithm>
#include <utility>

#include "crunch/mapping/mapper.h"

namespace crunch {

namespace {
// The extent of everything the whiskers can reach from `poses`: {lo, hi}.
std::pair<Vec2, Vec2> reachOf(const std::vector<Pose2>& poses, const std::vector<WhiskerMount>& mounts) {
  double reach = 0.0;
  for (const WhiskerMount& m : mounts) reach = std::max(reach, m.base.norm() + m.length);
  Vec2 lo{0, 0}, hi{0, 0};
  if (!poses.empty()) lo = hi = poses.front().position();
  for (const Pose2& p : poses) {
    lo = lo.cwiseMin(p.position());
    hi = hi.cwiseMax(p.position());
  }
  const Vec2 pad{reach + 0.05, reach + 0.05};
  return {lo - pad, hi + pad};
}

}  // namespace

Result<Map> runMapping(SensorModel& sensor, const std::vector<Pose2>& poses, int skipped,
                       const MappingOptions& options) {
  return runMapping(sensor, poses, skipped, options, MapperObserver());
}

Result<Map> runMapping(SensorModel& sensor, const std::vector<Pose2>& poses, int skipped,
                       const MappingOptions& options, const MapperObserver& observe) {
  if (auto s = options.validate(); !s) return s.error();
  Rng sense_rng(options.seed);
  const auto [lo, hi] = reachOf(poses, sensor.mounts());
  Mapper mapper(sensor.mounts(), lo, hi, options);
  std::vector<ContactReport> reports;
  std::vector<FreeRay> free_rays;
  for (size_t t = 0; t < poses.size(); ++t) {
    reports.clear();
    sensor.sense(poses[t], sense_rng, reports);
    free_rays.clear();
    sensor.freeRays(free_rays);
    // The body stands here (teleported: it swept nothing on the way), before this pose's
    // annealing weighs the free space.
    mapper.addBodySweep(poses[t].position(), poses[t].position());
    mapper.addPose(poses[t], reports, free_rays);
    if (observe) observe(mapper, poses[t]);
    if (options.progress) options.progress(static_cast<int>(t + 1), static_cast<int>(poses.size()));
  }
  Map map = mapper.finish();
  map.stats.poses = static_cast<int>(poses.size());
  map.stats.skipped_poses = skipped;
  return map;
}

}  // namespace crunch
