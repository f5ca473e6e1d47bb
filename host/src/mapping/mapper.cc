#include "crunch/mapping/mapper.h"

#include <algorithm>
#include <limits>
#include <utility>

#include "crunch/core/parallel.h"
#include "crunch/mapping/global_chain.h"
#include "crunch/mapping/identified_tables.h"
#include "crunch/mapping/posterior_marginals.h"
#include "crunch/mapping/wall_fusion.h"
#include "crunch/robot/whiskers.h"  // kRobotRadius

namespace crunch {

namespace {

// Puts every shapelet of the run and the negative evidence on `board` (the pooled chain's working
// memory holds them all, as each global chain's does).
void holdWholeRun(Blackboard& board, const Map& map, const FreeSpaceGrid* free) {
  for (const Shapelet& s : map.shapelets) board.pushShapelet(s);
  board.setFreeSpace(free);
}

// Walls across chains, their joined ends met where the model counts an end joined.
WallFuseOptions wallFuseOptions(const MappingOptions& options) {
  WallFuseOptions o;
  o.junction = options.model.wallLinkRadius();
  return o;
}

// Per-pose MAPs that agree with each fused table.
void countSupport(std::vector<MapTable>& tables, const Map& map, const FuseOptions& fuse) {
  for (MapTable& t : tables)
    for (const PoseMap& pm : map.per_pose)
      for (const MapTable& q : pm.tables) t.support += tablesAgree(q, t, fuse);
}

// The global inference's chains (global_chain.h), each annealed once, on options.threads threads:
// chain c on its own stream, its result in slot c. Each chain is built inside its task, so at
// most `threads` blackboards over the whole run exist at once. The run's counts take every
// chain's, in chain order.
std::vector<ChainResult> runChains(Map& map, const MappingOptions& options,
                                   const FreeSpaceGrid* free, std::vector<Rng>& streams) {
  const int n_chains = std::max(1, options.global_chains);
  std::vector<ChainResult> results(static_cast<size_t>(n_chains));
  parallelFor(n_chains, resolveThreads(options.threads), [&](int c) {
    GlobalChain chain(map.shapelets, free, options, streams[static_cast<size_t>(c)]);
    chain.anneal();
    results[static_cast<size_t>(c)] = chain.result();
  });
  for (const ChainResult& r : results) {
    map.stats.proposals += r.proposals;
    addMoveCounts(map.stats.global_moves, r.moves);
    map.stats.peak_live_tables = std::max(map.stats.peak_live_tables, r.live_tables);
    map.stats.peak_live_legs = std::max(map.stats.peak_live_legs, r.live_legs);
  }
  return results;
}

// ChainFusion::kMarginal: the chains' states after each sweep of their coldest marginal_steps
// temperatures are samples; a table's score is the fraction of samples holding it
// (posterior_marginals.h), tables above marginal_keep are kept and, of two overlapping ones, the
// likelier (eq. 25: two tables cannot share space).
std::vector<MapTable> marginalMap(Map& map, const MappingOptions& options,
                                  const FreeSpaceGrid* free, uint64_t chain_seed) {
  std::vector<Rng> streams = globalChainStreams(chain_seed, std::max(1, options.global_chains));
  std::vector<ObjectSample> objects;
  std::vector<std::vector<WallHyp>> chain_walls;  // none unless ModelParams::walled()
  int n_samples = 0;
  for (ChainResult& r : runChains(map, options, free, streams)) {
    for (ObjectSample o : r.samples) {
      o.sample += n_samples;  // numbered over the chains in chain order
      objects.push_back(o);
    }
    n_samples += r.sample_count;
    if (options.model.walled()) chain_walls.push_back(std::move(r.walls));
  }
  map.walls = fuseWalls(chain_walls, wallFuseOptions(options));
  MarginalOptions mo;
  mo.radius = options.fuse.radius;
  mo.angle = options.fuse.angle;
  mo.angle_period = kPi;
  if (options.model.sized()) {
    // Tables of different sizes at one spot are different objects, as in the vote (FuseOptions).
    mo.shape_tolerance = options.fuse.size;
    mo.square_half_period = true;
  }
  std::vector<MapTable> likely;  // best first
  for (const MarginalObject& o : posteriorMarginals(objects, n_samples, mo)) {
    if (o.score <= options.marginal_keep) continue;
    MapTable t = modelTable(o.pose, options.model);
    t.width = o.shape[0];
    t.depth = o.shape[1];
    t.leg = o.shape[2];
    t.score = o.score;
    likely.push_back(t);
  }
  std::vector<MapTable> out = withoutClashes(likely, options.fuse);
  countSupport(out, map, options.fuse);
  return out;
}

// A global table's score (ARCHITECTURE.md §4: the posterior probability of that object): the
// fraction of the independent chains whose end state holds it, each chain's end state a draw
// from the annealed posterior; walls are scored the same way (wall_fusion.h). Under the vote,
// `kept` are the vote's clusters (fuseTables over the chains, `support` = chain tables in the
// cluster) and `out` the same tables in the same order; under the pool, `out` are the pooled
// chain's tables and a chain holds one when it has a table that agrees (tablesAgree).
void scoreByChains(std::vector<MapTable>& out, const std::vector<MapTable>& kept,
                   const std::vector<PoseMap>& chains, const MappingOptions& options) {
  const double n = static_cast<double>(std::max<size_t>(1, chains.size()));
  const bool vote = options.chain_fusion == ChainFusion::kVote;
  for (size_t i = 0; i < out.size(); ++i) {
    int holding = 0;
    if (vote) {
      holding = kept[i].support;
    } else {
      for (const PoseMap& c : chains)
        holding += std::any_of(c.tables.begin(), c.tables.end(), [&](const MapTable& q) {
          return tablesAgree(q, out[i], options.fuse);
        });
    }
    out[i].score = std::min(1.0, holding / n);
  }
}

// `chain_seed`: the seed the chains' streams are split from (globalChainStreams).
std::vector<MapTable> globalMap(Map& map, const MappingOptions& options,
                                const FreeSpaceGrid* free, uint64_t chain_seed) {
  // Independent chains from the same evidence. The log joint cannot pick among them: it grows
  // with every wall phantom, so the chain with the most phantoms would win. Instead a table is
  // kept when at least half the chains agree on it (fused_map.h's clustering over chains), or
  // all chains' tables compete in one more, cold chain (ChainFusion).
  const int n_chains = std::max(1, options.global_chains);
  if (options.chain_fusion == ChainFusion::kMarginal)
    return marginalMap(map, options, free, chain_seed);
  // One stream per chain and, last, the pooled chain's.
  std::vector<Rng> streams = globalChainStreams(chain_seed, n_chains + 1);
  std::vector<PoseMap> chains(static_cast<size_t>(n_chains));
  // Walls (ModelParams::walled(); none otherwise): each chain's, fused across chains below.
  std::vector<std::vector<WallHyp>> chain_walls;
  std::vector<ChainResult> results = runChains(map, options, free, streams);
  for (size_t c = 0; c < results.size(); ++c) {
    chains[c].tables = std::move(results[c].tables);
    if (options.model.walled()) chain_walls.push_back(std::move(results[c].walls));
  }
  map.walls = fuseWalls(chain_walls, wallFuseOptions(options));
  FuseOptions agree = options.fuse;
  agree.min_support = options.chain_fusion == ChainFusion::kVote ? (n_chains + 1) / 2 : 1;
  std::vector<Pose2> poses;
  std::vector<MapTable> kept = fuseTables(chains, agree);  // with sizes (the rooms model)
  for (const MapTable& t : kept) poses.push_back(t.pose);
  if (options.chain_fusion == ChainFusion::kPool) {
    // Each table any chain found starts with a leg at every corner; the coldest temperatures
    // then let the posterior keep what the evidence pays for (a rival or a table without
    // support dies, two overlapping tables cannot both stay: eq. 25).
    Blackboard board(options.model, static_cast<int>(map.shapelets.size()),
                     4 * map.shapelets.size() + 8 * poses.size() + 64);
    holdWholeRun(board, map, free);
    // The fused walls compete too (none under kPaper): a table standing on one is charged.
    for (const MapWall& w : map.walls) board.addWall(w.a, w.b);
    for (const MapTable& k : kept) {
      const Pose2& p = k.pose;
      const bool sized = options.model.sized();
      const int32_t id = sized ? board.addTable(p, k.width, k.depth, k.leg) : board.addTable(p);
      for (int c = 0; c < 4; ++c) {
        const Vec2 at = board.table(id).corner(c);
        if (sized) board.addLeg({at.x(), at.y(), wrapPeriod(p.theta, kPi / 2)}, k.leg, id);
        else board.addLeg({at.x(), at.y(), wrapPeriod(p.theta, kPi / 2)}, id);
      }
    }
    SamplerOptions so = globalSamplerOptions(options);
    so.schedule_steps = options.pool_steps;  // beta_i for i < pool_steps: the coldest
    Sampler sampler(board, so, streams.back());
    sampler.anneal();
    map.stats.proposals += sampler.stats().proposals;
    addMoveCounts(map.stats.global_moves, sampler.stats().by_move);
    sampler.mapTables(poses);
    if (options.model.walled()) {
      identifiedTablesOf(board, options.fuse.size, kept);
      poses.clear();
      for (const MapTable& k : kept) poses.push_back(k.pose);
    }
  }

  // Support: per-pose MAPs that agree with each global table.
  std::vector<MapTable> out;
  if (options.model.sized()) {
    for (MapTable t : kept) {
      t.support = 0;
      for (const PoseMap& pm : map.per_pose)
        for (const MapTable& q : pm.tables) t.support += tablesAgree(q, t, options.fuse);
      out.push_back(t);
    }
    scoreByChains(out, kept, chains, options);
    return out;
  }
  for (const Pose2& p : poses) {
    MapTable t = modelTable(p, options.model);
    for (const PoseMap& pm : map.per_pose)
      for (const MapTable& q : pm.tables) t.support += tablesAgree(q.pose, t.pose, options.fuse);
    out.push_back(t);
  }
  scoreByChains(out, kept, chains, options);
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

MapTable sizedTable(const TableHyp& h) {
  MapTable t;
  t.pose = h.pose;
  t.width = h.width;
  t.depth = h.depth;
  t.leg = h.leg;
  if (t.depth > t.width) {
    std::swap(t.width, t.depth);
    t.pose.theta += kPi / 2;
  }
  t.pose.theta = wrapHalfTurn(t.pose.theta);
  return t;
}

void mapTablesOf(const Sampler& sampler, const ModelParams& model, std::vector<MapTable>& out,
                 std::vector<TableHyp>& scratch) {
  out.clear();
  sampler.mapTables(scratch);
  for (const TableHyp& h : scratch) {
    if (model.sized()) {
      out.push_back(sizedTable(h));
    } else {
      out.push_back(modelTable(h.pose, model));
    }
  }
}

Mapper::Mapper(std::vector<WhiskerMount> mounts, const Vec2& lo, const Vec2& hi,
               const MappingOptions& options)
    : mounts_(std::move(mounts)),
      options_(options),
      start_(std::chrono::steady_clock::now()),
      rng_(options.seed ^ 0xB1ACB0A2Dull),
      board_(options.model, options.working_memory, 4096),
      sampler_(board_, options.sampler, rng_),
      free_space_(lo, hi),
      sample_rng_(options.seed ^ 0x5A3B1E5ull) {
  // Tables of different sizes at one spot are different objects (a chair and a table).
  options_.fuse.compare_sizes = options_.model.sized();
  if (options_.room) free_space_.setRoom(options_.room->first, options_.room->second);
  // The blackboard reads at most free_pass_cap passes of any square (Blackboard::freeTerm).
  free_space_.setWindowCap(options_.model.free_pass_cap);
}

void Mapper::addBodySweep(const Vec2& a, const Vec2& b) {
  if (!options_.body_sweep || !options_.negative_evidence) return;
  free_space_.addSweep(a, b, kRobotRadius, options_.model.free_pass_cap);
}

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
    PoseMap pm;
    pm.pose = pose;
    pm.shapelets = fresh;
    if (options_.model.sized()) {
      mapTablesOf(sampler_, options_.model, pm.tables, sized_tables_);
    } else {
      sampler_.mapTables(tables_);
      for (const Pose2& p : tables_) pm.tables.push_back(modelTable(p, options_.model));
    }
    map_.per_pose.push_back(std::move(pm));
  }
  if (options_.after_pose) options_.after_pose(t, pose, fresh > 0, board_);
  return fresh;
}

void Mapper::drawSamples(int n, double beta, int sweeps_between, std::vector<MapSample>& out) {
  while (!continueSamples(n, beta, sweeps_between, out, std::numeric_limits<int>::max())) {
  }
}

bool Mapper::continueSamples(int n, double beta, int sweeps_between, std::vector<MapSample>& out,
                             int max_sweeps) {
  const std::vector<Shapelet>& run = map_.shapelets;
  if (!request_.active) {
    if (run.empty() || n <= 0) return true;
    const bool fresh = sample_fed_ < run.size();
    if (!sample_board_ ||
        static_cast<std::size_t>(sample_board_->workingMemoryCapacity()) < run.size()) {
      const int capacity = static_cast<int>(std::max<std::size_t>(256, 2 * run.size()));
      sample_sampler_.reset();
      // The draws are posterior samples at beta = 1, where the catalog's density over a side
      // nothing measures is right (its tiny volume balances it); only the annealed maps, whose
      // cold end keeps densities but not volumes, count the fixed sides alone (params.h).
      ModelParams draws = options_.model;
      draws.catalog_fixed_sides = false;
      sample_board_ = std::make_unique<Blackboard>(draws, capacity, 4 * capacity + 64);
      sample_board_->setFreeSpace(options_.negative_evidence ? &free_space_ : nullptr);
      sample_sampler_ = std::make_unique<Sampler>(*sample_board_, options_.sampler, sample_rng_);
      sample_fed_ = 0;
    }
    for (; sample_fed_ < run.size(); ++sample_fed_) sample_board_->pushShapelet(run[sample_fed_]);
    request_ = SampleRequest{true, 0, fresh ? sample_sampler_->annealSweeps() : 0, 0, 0};
  }
  for (int budget = max_sweeps;;) {
    const bool annealing = request_.anneal_next < request_.anneal_total;
    if (annealing || request_.between < sweeps_between) {
      if (budget-- <= 0) return false;
      if (annealing) {
        sample_sampler_->annealSweep(request_.anneal_next++);
      } else {
        sample_sampler_->sweep(beta);
        ++request_.between;
      }
      continue;
    }
    drawOne(out);
    request_.between = 0;
    if (++request_.drawn == n) {
      request_.active = false;
      return true;
    }
  }
}

void Mapper::drawOne(std::vector<MapSample>& out) {
  MapSample draw;
  Blackboard& bb = *sample_board_;
  if (options_.model.walled()) {
    // What the evidence leaves open (an untouched side, a mirror image) drawn from its
    // conditional: the chain at beta = 1 would repeat one guess in every draw.
    for (int32_t id = 0; id < bb.tableExtent(); ++id)
      if (bb.table(id).alive)
        draw.tables.push_back(drawOpenTable(bb, id, options_.fuse.size / 5.0, sample_rng_));
  } else {
    mapTablesOf(*sample_sampler_, options_.model, draw.tables, sized_tables_);
  }
  for (int32_t id = 0; id < bb.legExtent(); ++id) {
    const LegHyp& l = bb.leg(id);
    if (l.alive && l.parent == kNone) draw.legs.push_back({l.pose, l.side});
  }
  if (options_.model.walled()) {
    std::vector<WallHyp> walls;
    sample_sampler_->mapWalls(walls);
    for (const WallHyp& w : walls) draw.walls.push_back({w.a, w.b, 1.0});
  }
  out.push_back(std::move(draw));
}

FreeSpaceLayer sweptLayer(const FreeSpaceGrid& grid) {
  FreeSpaceLayer f;
  int x0, y0, x1, y1;
  if (!grid.sweptBounds(x0, y0, x1, y1)) return f;  // nothing swept: no layer (no key in the file)
  // Blocks of k x k grid cells, k the smallest power of two that keeps the layer within
  // kMaxFreeSpaceLayerCells (1 cm up to about 20 x 20 m of swept floor).
  const long long w = x1 - x0 + 1, h = y1 - y0 + 1;
  int k = 1;
  while (((w + k - 1) / k) * ((h + k - 1) / k) > kMaxFreeSpaceLayerCells) k *= 2;
  f.cell = grid.cell() * k;
  f.origin = grid.origin() + Vec2(x0 * grid.cell(), y0 * grid.cell());
  f.nx = static_cast<int>((w + k - 1) / k);
  f.ny = static_cast<int>((h + k - 1) / k);
  f.swept.assign(static_cast<std::size_t>(f.nx) * static_cast<std::size_t>(f.ny), 0);
  for (int iy = y0; iy <= y1; ++iy) {
    for (int ix = x0; ix <= x1; ++ix) {
      if (grid.countAt(ix, iy) == 0) continue;
      f.swept[static_cast<std::size_t>((iy - y0) / k) * static_cast<std::size_t>(f.nx) +
              static_cast<std::size_t>((ix - x0) / k)] = 1;
    }
  }
  return f;
}

Map Mapper::snapshot() const {
  Map map = map_;
  map.free_space = sweptLayer(free_space_);
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
  infer(map, options_.seed);
  return map;
}

Map Mapper::inferNow(Rng& rng) const {
  Map map = map_;
  infer(map, rng.next());
  return map;
}

void Mapper::infer(Map& map, uint64_t chain_seed) const {
  map.free_space = sweptLayer(free_space_);
  map.stats.poses = pose_count_;
  map.stats.shapelets = static_cast<int>(map.shapelets.size());
  map.stats.proposals = sampler_.stats().proposals;
  if (options_.global_sweeps > 0 && !map.shapelets.empty()) {
    const auto t0 = std::chrono::steady_clock::now();
    map.tables =
        globalMap(map, options_, options_.negative_evidence ? &free_space_ : nullptr, chain_seed);
    if (options_.model.walled())
      keepOneWorld(map.tables, map.walls, options_.model.wall_solid_depth);
    map.stats.global_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    map.stats.global_threads =
        std::min(resolveThreads(options_.threads), std::max(1, options_.global_chains));
  } else {
    map.tables = fuseTables(map.per_pose, options_.fuse);
  }
  map.stats.wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

}  // namespace crunch
