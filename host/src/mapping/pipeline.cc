#include "crunch/mapping/pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "crunch/blackboard/blackboard.h"

namespace crunch {

namespace {
// A grid covering everything the whiskers can reach from `poses`.
FreeSpaceGrid freeSpaceFor(const std::vector<Pose2>& poses, const std::vector<WhiskerMount>& mounts) {
  double reach = 0.0;
  for (const WhiskerMount& m : mounts) reach = std::max(reach, m.base.norm() + m.length);
  Vec2 lo{0, 0}, hi{0, 0};
  if (!poses.empty()) lo = hi = poses.front().position();
  for (const Pose2& p : poses) {
    lo = lo.cwiseMin(p.position());
    hi = hi.cwiseMax(p.position());
  }
  const Vec2 pad{reach + 0.05, reach + 0.05};
  return FreeSpaceGrid(lo - pad, hi + pad);
}

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
std::vector<MapTable> globalMap(Map& map, const MappingOptions& options,
                                const FreeSpaceGrid* free, Rng& rng) {
  // Independent chains from the same evidence. The log joint cannot pick among them: it grows
  // with every wall phantom, so the chain with the most phantoms would win. Instead a table is
  // kept when at least half the chains agree on it (fused_map.h's clustering over chains).
  const int n_chains = std::max(1, options.global_chains);
  std::vector<PoseMap> chains(static_cast<size_t>(n_chains));
  std::vector<Pose2> found;
  for (PoseMap& chain : chains) {
    Blackboard board(options.model, static_cast<int>(map.shapelets.size()),
                     4 * map.shapelets.size() + 64);
    for (const Shapelet& s : map.shapelets) board.pushShapelet(s);
    board.setFreeSpace(free);
    SamplerOptions so = options.sampler;
    so.sweeps_per_temperature = options.global_sweeps;
    Sampler sampler(board, so, rng);
    sampler.anneal();
    map.stats.proposals += sampler.stats().proposals;
    sampler.mapTables(found);
    for (const Pose2& p : found) chain.tables.push_back(modelTable(p, options.model));
  }
  FuseOptions agree = options.fuse;
  agree.min_support = (n_chains + 1) / 2;
  std::vector<Pose2> poses;
  for (const MapTable& t : fuseTables(chains, agree)) poses.push_back(t.pose);

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
  std::vector<FreeRay> free_rays;
  FreeSpaceGrid free_space = freeSpaceFor(poses, sensor.mounts());
  for (size_t t = 0; t < poses.size(); ++t) {
    reports.clear();
    sensor.sense(poses[t], sense_rng, reports);
    free_rays.clear();
    sensor.freeRays(free_rays);
    for (const FreeRay& r : free_rays) free_space.addRay(r);
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
    map.tables =
        globalMap(map, options, options.negative_evidence ? &free_space : nullptr, sample_rng);
  } else {
    map.tables = fuseTables(map.per_pose, options.fuse);
  }
  map.stats.wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return map;
}

}  // namespace crunch
