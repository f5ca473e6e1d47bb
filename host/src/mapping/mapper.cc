#include "crunch/mapping/mapper.h"

#include <algorithm>
#include <utility>

#include "crunch/mapping/wall_fusion.h"

namespace crunch {

namespace {

// The fused map as one inference over every shapelet of the run (the paper's future work of
// "longer-term memories of shapelets", §4): a blackboard whose working memory holds them all,
// annealed with the same schedule and `global_sweeps` sweeps per temperature. The spatial hash
// keeps each move local, so the cost grows with the number of shapelets, not its square.
// Puts every shapelet of the run and the negative evidence on `board` (the global inference's
// working memory holds them all).
void holdWholeRun(Blackboard& board, const Map& map, const FreeSpaceGrid* free) {
  for (const Shapelet& s : map.shapelets) board.pushShapelet(s);
  board.setFreeSpace(free);
}

// The sampler's options with the global inference's sweeps per temperature.
SamplerOptions globalSampler(const MappingOptions& options) {
  SamplerOptions so = options.sampler;
  so.sweeps_per_temperature = options.global_sweeps;
  return so;
}

std::vector<MapTable> globalMap(Map& map, const MappingOptions& options,
                                const FreeSpaceGrid* free, Rng& rng) {
  // Independent chains from the same evidence. The log joint cannot pick among them: it grows
  // with every wall phantom, so the chain with the most phantoms would win. Instead a table is
  // kept when at least half the chains agree on it (fused_map.h's clustering over chains), or
  // all chains' tables compete in one more, cold chain (ChainFusion).
  const int n_chains = std::max(1, options.global_chains);
  std::vector<PoseMap> chains(static_cast<size_t>(n_chains));
  std::vector<Pose2> found;
  // Walls (ObjectModel::kRooms; none otherwise): each chain's, fused across chains below.
  std::vector<std::vector<WallHyp>> chain_walls;
  for (PoseMap& chain : chains) {
    Blackboard board(options.model, static_cast<int>(map.shapelets.size()),
                     4 * map.shapelets.size() + 64);
    holdWholeRun(board, map, free);
    Sampler sampler(board, globalSampler(options), rng);
    sampler.anneal();
    map.stats.proposals += sampler.stats().proposals;
    map.stats.peak_live_tables = std::max(map.stats.peak_live_tables, board.liveTables());
    map.stats.peak_live_legs = std::max(map.stats.peak_live_legs, board.liveLegs());
    sampler.mapTables(found);
    for (const Pose2& p : found) chain.tables.push_back(modelTable(p, options.model));
    if (options.model.objects == ObjectModel::kRooms) {
      chain_walls.emplace_back();
      sampler.mapWalls(chain_walls.back());
    }
  }
  map.walls = fuseWalls(chain_walls);
  FuseOptions agree = options.fuse;
  agree.min_support = options.chain_fusion == ChainFusion::kVote ? (n_chains + 1) / 2 : 1;
  std::vector<Pose2> poses;
  for (const MapTable& t : fuseTables(chains, agree)) poses.push_back(t.pose);
  if (options.chain_fusion == ChainFusion::kPool) {
    // Each table any chain found starts with a leg at every corner; the coldest temperatures
    // then let the posterior keep what the evidence pays for (a rival or a table without
    // support dies, two overlapping tables cannot both stay: eq. 25).
    Blackboard board(options.model, static_cast<int>(map.shapelets.size()),
                     4 * map.shapelets.size() + 8 * poses.size() + 64);
    holdWholeRun(board, map, free);
    // The fused walls compete too (none under kPaper): a table standing on one is charged.
    for (const MapWall& w : map.walls) board.addWall(w.a, w.b);
    for (const Pose2& p : poses) {
      const int32_t id = board.addTable(p);
      for (int c = 0; c < 4; ++c) {
        const Vec2 at = p.toWorld(options.model.cornerOffset(c));
        board.addLeg({at.x(), at.y(), wrapPeriod(p.theta, kPi / 2)}, id);
      }
    }
    SamplerOptions so = globalSampler(options);
    so.schedule_steps = options.pool_steps;  // beta_i for i < pool_steps: the coldest
    Sampler sampler(board, so, rng);
    sampler.anneal();
    map.stats.proposals += sampler.stats().proposals;
    sampler.mapTables(poses);
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


MapTable modelTable(const Pose2& pose, const ModelParams& model) {
  MapTable t;
  t.pose = pose;
  t.width = model.table_width;
  t.depth = model.table_depth;
  t.leg = model.leg_side;
  return t;
}

Mapper::Mapper(std::vector<WhiskerMount> mounts, const Vec2& lo, const Vec2& hi,
               const MappingOptions& options)
    : mounts_(std::move(mounts)),
      options_(options),
      start_(std::chrono::steady_clock::now()),
      rng_(options.seed ^ 0xB1ACB0A2Dull),
      board_(options.model, options.working_memory, 4096),
      sampler_(board_, options.sampler, rng_),
      free_space_(lo, hi) {}

int Mapper::addPose(const Pose2& pose, std::span<const ContactReport> reports,
                    std::span<const FreeRay> free_rays) {
  const int t = pose_count_++;
  for (const FreeRay& r : free_rays) free_space_.addRay(r);
  int fresh = 0;
  for (const ContactReport& rep : reports) {
    Shapelet s;
    if (!toShapelet(rep, mounts_, t, s)) {
      ++map_.stats.rejected_reports;
      continue;
    }
    board_.pushShapelet(s);
    map_.shapelets.push_back(s);
    ++fresh;
  }
  if (fresh > 0) {
    sampler_.anneal();
    map_.stats.peak_live_tables = std::max(map_.stats.peak_live_tables, board_.liveTables());
    map_.stats.peak_live_legs = std::max(map_.stats.peak_live_legs, board_.liveLegs());
    sampler_.mapTables(tables_);
    PoseMap pm;
    pm.pose = pose;
    pm.shapelets = fresh;
    for (const Pose2& p : tables_) pm.tables.push_back(modelTable(p, options_.model));
    map_.per_pose.push_back(std::move(pm));
  }
  if (options_.after_pose) options_.after_pose(t, pose, fresh > 0, board_);
  return fresh;
}

Map Mapper::snapshot() const {
  Map map = map_;
  map.stats.poses = pose_count_;
  map.stats.shapelets = static_cast<int>(map.shapelets.size());
  map.stats.proposals = sampler_.stats().proposals;
  map.tables = fuseTables(map.per_pose, options_.fuse);
  map.stats.wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  return map;
}

Map Mapper::finish() {
  Map map = std::move(map_);
  map_ = Map{};
  map.stats.poses = pose_count_;
  map.stats.shapelets = static_cast<int>(map.shapelets.size());
  map.stats.proposals = sampler_.stats().proposals;
  if (options_.global_sweeps > 0 && !map.shapelets.empty()) {
    map.tables =
        globalMap(map, options_, options_.negative_evidence ? &free_space_ : nullptr, rng_);
  } else {
    map.tables = fuseTables(map.per_pose, options_.fuse);
  }
  map.stats.wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  return map;
}

}  // namespace crunch
