#include "crunch/mapping/pipeline.h"

#include <chrono>

#include "crunch/blackboard/blackboard.h"

namespace crunch {

Map runMapping(SensorModel& sensor, const std::vector<Pose2>& poses, int skipped,
               const MappingOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  Rng sense_rng(options.seed);
  Rng sample_rng(options.seed ^ 0xB1ACB0A2Dull);
  Blackboard board(options.model, options.working_memory, 4096);
  Sampler sampler(board, options.sampler, sample_rng);

  Map map;
  map.stats.poses = static_cast<int>(poses.size());
  map.stats.skipped_poses = skipped;
  std::vector<ContactReport> reports;
  std::vector<Pose2> tables;
  for (size_t t = 0; t < poses.size(); ++t) {
    reports.clear();
    sensor.sense(poses[t], sense_rng, reports);
    int fresh = 0;
    for (const ContactReport& rep : reports) {
      Shapelet s;
      if (!toShapelet(rep, sensor.mounts(), static_cast<int>(t), s)) {
        ++map.stats.rejected_reports;
        continue;
      }
      board.pushShapelet(s);
      map.shapelets.push_back(s);
      ++fresh;
    }
    if (fresh > 0) {
      sampler.anneal();
      sampler.mapTables(tables);
      PoseMap pm;
      pm.pose = poses[t];
      pm.shapelets = fresh;
      for (const Pose2& p : tables) {
        MapTable mt;
        mt.pose = p;
        mt.width = options.model.table_width;
        mt.depth = options.model.table_depth;
        mt.leg = options.model.leg_side;
        pm.tables.push_back(mt);
      }
      map.per_pose.push_back(std::move(pm));
    }
    if (options.progress) options.progress(static_cast<int>(t + 1), static_cast<int>(poses.size()));
  }
  map.stats.shapelets = static_cast<int>(map.shapelets.size());
  map.stats.proposals = sampler.stats().proposals;
  map.tables = fuseTables(map.per_pose, options.fuse);
  map.stats.wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return map;
}

}  // namespace crunch
