// The mapping run of paper §2.8 one pose at a time, for a robot that decides where to go as it
// goes (`crunchhost --robot`, `--replay`) as well as for the pre-determined pose grid
// (runMapping, run_mapping.h): each pose's contact reports become shapelets (eqs. 4-6) in the
// blackboard's working memory, the blackboard is annealed (Algorithm 1) and MAP_t (eq. 27) is
// recorded; at the end the collation is fused into one map (fused_map.h), by one global
// inference over every shapelet when MappingOptions::global_sweeps > 0.
//
// Randomness: the per-pose sampler draws from its own stream seeded by options.seed, and each of
// the global inference's chains from a stream of its own split from the seed (global_chain.h),
// so the map depends only on the reports, their order, the seed and the chain count: not on
// options.threads. snapshot() draws nothing (it clusters the per-pose MAPs), so a run that
// writes maps as it goes ends with the same map as one that does not.
//
// Ownership: owns the blackboard, sampler and free-space grid. Not copyable or movable (the
// sampler references the blackboard). Thread-safety: none (one thread calls it); finish() runs
// the global chains on options.threads threads of its own, joined before it returns.
#pragma once

#include <memory>

#include <chrono>
#include <span>
#include <vector>

#include "crunch/blackboard/blackboard.h"
#include "crunch/blackboard/sampler.h"
#include "crunch/core/rng.h"
#include "crunch/blackboard/free_space.h"
#include "crunch/mapping/map.h"
#include "crunch/mapping/mapping_options.h"
#include "crunch/robot/shapelet.h"

namespace crunch {

class Mapper {
 public:
  // `lo`, `hi`: the region the robot and its whiskers can reach (the negative-evidence grid's
  // extent; rays outside it are not counted).
  Mapper(std::vector<WhiskerMount> mounts, const Vec2& lo, const Vec2& hi,
         const MappingOptions& options);
  Mapper(const Mapper&) = delete;
  Mapper& operator=(const Mapper&) = delete;

  // One pose (one body whisk): its reports and the rays its whiskers swept without touching.
  // Reports that toShapelet() rejects are counted in stats().rejected_reports. If at least one
  // shapelet is new, anneals and appends MAP_t to per_pose with `pose`. Returns the shapelets
  // added. Then calls options.after_pose, if set, with const access to the blackboard.
  int addPose(const Pose2& pose, std::span<const ContactReport> reports,
              std::span<const FreeRay> free_rays);

  // The robot's body moved from `a` to `b` (or stood at a == b): no leg can stand within
  // kRobotRadius of that segment, or the body would have hit it. Negative evidence for the
  // global inference and the posterior draws as certain as a whisker's full pass cap
  // (model.free_pass_cap passes in every cell swept). Nothing when options.body_sweep or
  // options.negative_evidence is off. The caller gives the moves its odometry saw: --robot's
  // session from the Create's stream (so --replay sweeps the same), --sim --explore from the
  // driven base's path; teleported poses sweep nothing.
  void addBodySweep(const Vec2& a, const Vec2& b);

  // The map so far: per-pose MAPs, shapelets, and tables fused by clustering (no random draws).
  Map snapshot() const;
  // The final map: the global inference (options.global_sweeps > 0; its chains in parallel on
  // options.threads threads) or the clustering; stats include wall_s since construction and
  // global_s. Call once, last. stats.peak_live_tables/_legs are the
  // maxima over every pose's annealing and, with the global inference, over its chains too
  // (each counted when its annealing ends); snapshot() gives the per-pose maxima so far.
  Map finish();
  // The map finish() would give if the run ended now, drawn from `rng` instead of the run's own
  // stream (one draw of it seeds the chains' streams, global_chain.h): the global inference over every shapelet so far (options.global_sweeps > 0), else
  // the clustering. The run is untouched, so its final map is the same whether or not this is
  // called (exploration scores its recall-against-travel curve with it: the snapshot's
  // clustering of per-pose MAPs lags the global inference by many metres).
  Map inferNow(Rng& rng) const;

  // Posterior draws of the whole run's map, for exploration (exploration/policy.h): a chain
  // that persists across calls over every shapelet so far (a blackboard whose working memory
  // holds the run, with the negative evidence, as the global inference's). Shapelets sensed
  // since the last call join it and it is annealed once (the model's schedule, ending cold);
  // then `n` draws are appended to `out`, each the chain's state after `sweeps_between` sweeps
  // at inverse temperature `beta` (1: the posterior itself, the paper's "hot sampler" of
  // §2.9). A draw holds the chain's tables, its orphan legs (MapSample::legs) and walls; under
  // the walls and rooms models what each table leaves open (an untouched side, a mirror image)
  // is drawn from its conditional (drawOpenTable, identified_tables.h), the chain left as it
  // was. Draws from its own stream (seeded from options.seed), so a run that draws samples
  // maps the same per-pose MAPs as one that does not. No draws (out unchanged) before any
  // shapelet.
  void drawSamples(int n, double beta, int sweeps_between, std::vector<MapSample>& out);
  // The same draws spread over calls, for a caller that must not wait for all of them (the
  // robot's control loop: a stall of 0.5 s stops the Create and fills the USB ring). Each call
  // runs at most `max_sweeps` of the chain's sweeps (annealing and between draws) and appends
  // the draws completed; true once `n` draws have been appended since the first call of this
  // request (then the next call starts a new one). Called until true with the same arguments,
  // it makes exactly drawSamples' draws. Shapelets sensed during a request join the next.
  bool continueSamples(int n, double beta, int sweeps_between, std::vector<MapSample>& out,
                       int max_sweeps);

  int poses() const { return pose_count_; }
  const std::vector<WhiskerMount>& mounts() const { return mounts_; }

 private:
  // finish()'s inference on `map` (the run's collation), its chains' streams split from
  // `chain_seed` (finish: options.seed; inferNow: a draw of its rng); sets map.tables and stats.
  void infer(Map& map, uint64_t chain_seed) const;

  std::vector<WhiskerMount> mounts_;
  MappingOptions options_;
  std::chrono::steady_clock::time_point start_;
  Rng rng_;
  Blackboard board_;
  Sampler sampler_;
  FreeSpaceGrid free_space_;
  Map map_;
  int pose_count_ = 0;
  std::vector<Pose2> tables_;  // scratch for MAP_t
  std::vector<TableHyp> sized_tables_;  // the same with sizes (the rooms model)
  // drawSamples' chain over the whole run, built at the first call and rebuilt larger when the
  // run outgrows its working memory; sample_fed_ shapelets of map_.shapelets are on it.
  Rng sample_rng_;
  std::unique_ptr<Blackboard> sample_board_;
  std::unique_ptr<Sampler> sample_sampler_;
  std::size_t sample_fed_ = 0;
  // continueSamples' request in progress (active): the annealing's next sweep (anneal_next of
  // anneal_total), the draws made, and the sweeps made toward the next draw.
  struct SampleRequest {
    bool active = false;
    int anneal_next = 0, anneal_total = 0;
    int drawn = 0, between = 0;
  } request_;
  void drawOne(std::vector<MapSample>& out);
};

// The cells of `grid` that at least one free whisker sample passed through (Map::free_space),
// over the smallest box holding them; empty when none. A box of more than
// kMaxFreeSpaceLayerCells grid cells is written in square blocks of 2, 4, ... cells (a block is
// swept when any of its cells is), so a map file stays small on any floor: 1 cm cells up to about
// 20 x 20 m of swept floor. snapshot(), finish() and inferNow() fill their map's free_space
// with it.
inline constexpr long long kMaxFreeSpaceLayerCells = 1LL << 22;
FreeSpaceLayer sweptLayer(const FreeSpaceGrid& grid);

// A table of the model's one size at `pose`.
MapTable modelTable(const Pose2& pose, const ModelParams& model);
// A table hypothesis of its own size as a map table, written with width >= depth (a w x d table
// at theta is the d x w table at theta + pi/2; theta modulo pi).
MapTable sizedTable(const TableHyp& t);
// The map tables of a sampler's MAP: each of its own size under the rooms model, the one size
// of the paper's otherwise. `scratch` keeps the sampler's output (no allocation once grown).
void mapTablesOf(const Sampler& sampler, const ModelParams& model, std::vector<MapTable>& out,
                 std::vector<TableHyp>& scratch);

}  // namespace crunch
