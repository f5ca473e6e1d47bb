#include "crunch/mapping/pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "crunch/blackboard/blackboard.h"

namespace crunch {

namespace {
// A table of the model's one size at `pose`.
MapTable modelTable(const Pose2& pose, const ModelParams& model) {
  MapTable t;
  t.pose = pose;
  t.width = model.table_width;
  t.depth = model.table_depth;
  t.leg = model.leg_side;
  return t;
}

// The fused map as one inference over every shapelet of the run (the paper's future work of
// "longer-term memories of shapelets", §4): a blackboard whose working memory holds them all,
// annealed with the same schedule and `global_sweeps` sweeps per temperature. The spatial hash
// keeps each move local, so the cost grows with the number of shapelets, not its square.
std::vector<MapTable> globalMap(Map& map, const MappingOptions& options, Rng& rng) {
  // Independent chains from the same evidence; the one with the highest log joint wins.
  std::vector<Pose2> poses;
  double best = -std::numeric_limits<double>::infinity();
  for (int chain = 0; chain < std::max(1, options.global_chains); ++chain) {
    Blackboard board(options.model, static_cast<int>(map.shapelets.size()),
                     4 * map.shapelets.size() + 64);
    for (const Shapelet& s : map.shapelets) board.pushShapelet(s);
    SamplerOptions so = options.sampler;
    so.sweeps_per_temperature = options.global_sweeps;
    Sampler sampler(board, so, rng);
    sampler.anneal();
    map.stats.proposals += sampler.stats().proposals;
    const double energy = board.totalEnergy();
    if (energy > best) {
      best = energy;
      sampler.mapTables(poses);
    }
  }
  // Support: per-pose MAPs that agree with each global table.
  std::vector<MapTable> out;
  for (const Pose2& p : poses) {
    MapTable t = modelTable(p, options.model);
    for (const PoseMap& pm : map.per_pose)
      for (const MapTable& q : pm.tables) t.support += tablesAgree(q.pose, t.pose, options.fuse);
    out.push_back(t);
  }
  scoreBySupport(out, map.per_pose, options.fuse);
  return out;
}
}  // namespace

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
      for (const Pose2& p : tables) pm.tables.push_back(modelTable(p, options.model));
      map.per_pose.push_back(std::move(pm));
    }
    if (options.progress) options.progress(static_cast<int>(t + 1), static_cast<int>(poses.size()));
  }
  map.stats.shapelets = static_cast<int>(map.shapelets.size());
  map.stats.proposals = sampler.stats().proposals;
  if (options.global_sweeps > 0 && !map.shapelets.empty()) {
    map.tables = globalMap(map, options, sample_rng);
  } else {
    map.tables = fuseTables(map.per_pose, options.fuse);
  }
  map.stats.wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return map;
}

}  // namespace crunch
