// The settings of a mapping run (paper §2.8): the model's parameters, the sampler's schedule,
// working memory, fusion and the global inference. Used by Mapper (mapper.h) one pose at a time
// and by runMapping (run_mapping.h) over a pose list.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>

#include "crunch/blackboard/blackboard.h"
#include "crunch/blackboard/params.h"
#include "crunch/blackboard/sampler.h"
#include "crunch/mapping/fused_map.h"

namespace crunch {

// How the global inference's chains become the fused map (docs/BLACKBOARD.md, "Fusing the
// chains"). A fused table's score is its posterior probability as the chains estimate it, as a
// wall's is: under kVote the fraction of the chains in its cluster (>= 0.5 for every kept
// table), under kPool the fraction of the chains holding a table that agrees with the pooled
// one (tablesAgree), under kMarginal the fraction of samples. Without the global inference
// (global_sweeps 0) it is the per-pose support fraction of fused_map.h.
enum class ChainFusion {
  // A table at least half the chains agree on. With the paper's classifier a wall's contact
  // looks like a leg's face, so the model (which has no walls yet) explains walls by phantom
  // tables; they differ from chain to chain and the vote drops them.
  kVote,
  // Every chain's tables (clustered) start one more chain over all shapelets, annealed over
  // the schedule's `pool_steps` coldest temperatures: the posterior decides among them, so a
  // table one chain found is kept if the evidence pays for it. Needs evidence the model can
  // tell from what it cannot explain: the located chain's faces longer than a leg
  // (ContactReport::face_span) no leg can cause.
  kPool,
  // Posterior marginals (mapping/posterior_marginals.h): every chain's tables after each sweep
  // of the schedule's `marginal_steps` coldest temperatures are samples; a table is kept when
  // more than half of all samples (over chains and sweeps) hold a matching one, and its score is
  // that fraction. Rather than a majority of each chain's last state, a table a chain holds
  // part of the time counts for that part.
  kMarginal,
};

// "vote" | "pool" | "marginal"; an Error naming the choices otherwise.
Result<ChainFusion> chainFusionByName(const std::string& name);
const char* chainFusionName(ChainFusion f);

// The object model a run maps with unless told (`--model`; `crunchhost sweep`'s default axis
// too): walls and the paper's table. It maps every scene of test/scenes/ at least as well as the
// paper's model and the default arena with F1 1.0 against 0.84 (docs/BLACKBOARD.md "Object
// models"); `--model paper` keeps the paper's figures (tools/make-results.sh passes it).
ModelParams defaultMappingModel();

struct MappingOptions {
  ModelParams model = defaultMappingModel();
  SamplerOptions sampler;
  FuseOptions fuse;
  int working_memory = 7;  // the paper's queue of the seven most recent shapelets
  uint64_t seed = 1;
  // > 0: the fused map is one annealing over all shapelets with this many sweeps per
  // temperature (global inference); 0: clustering of the per-pose MAPs (fused_map.h).
  int global_sweeps = 8;
  int global_chains = 8;  // independent chains
  // The global chains' SamplerOptions::prime_explained: a shapelet already explained is primed
  // in one sweep of ten. Over the run's every shapelet priming is 80 % of the proposals and an
  // explained shapelet's prime is taken about once in 700-1000; at 0.1 the chains make ~70 %
  // fewer proposals at the same F1 (docs/BENCHMARKS.md "The move mix"). 1: the paper's sweep.
  double global_prime_explained = 0.1;
  // Threads the global inference's chains run on (`--threads`; 0: one per core,
  // core/parallel.h hardwareThreads()). Never changes a result: each chain draws from its own
  // stream and the chains are combined in chain order (global_chain.h). A property of the
  // machine, not of the run: not in a recording's metadata nor in report.json's settings.
  int threads = 0;
  ChainFusion chain_fusion = ChainFusion::kVote;
  int pool_steps = 4;  // kPool: the coldest temperatures of the schedule the pooled chain runs
  // kMarginal: the coldest temperatures of each chain's schedule whose sweeps are samples.
  int marginal_steps = 4;
  // kMarginal: a table is kept when its posterior probability (score) is above this.
  double marginal_keep = 0.5;
  // The global inference also weighs negative evidence: where whiskers swept and touched
  // nothing (free_space.h). Per-pose MAPs never do (the paper's collation).
  bool negative_evidence = true;
  // ... including where the robot's body drove (Mapper::addBodySweep). Recordings made before
  // it was recorded in their metadata replay without it (the map they were recorded with).
  bool body_sweep = true;
  // The room: where the robot's known region ends its walls stand, and no leg stands beyond
  // (FreeSpaceGrid::setRoom; with negative_evidence). --sim --explore: the arena; --robot: the
  // mapped area (recordings from before it was recorded: none). Unset: the paper's runs, whose
  // pose list says nothing of where the room ends.
  std::optional<std::pair<Vec2, Vec2>> room;
  // Called after each pose with (poses done, poses total); may be empty.
  std::function<void(int, int)> progress;
  // sampler.after_temperature and sampler.after_sweep are called by the per-pose annealings
  // only, never by the global inference's chains (which may run on several threads).
  // Blackboard snapshots (`crunchhost --sim --snapshot K`, paper Figs. 3-4): called by
  // Mapper::addPose after every pose, with the pose's index in the run's order (0-based), the
  // pose, whether it annealed (false: no new shapelet, the blackboard is as the last annealing
  // left it) and const access to the blackboard at the end of that annealing (its coldest
  // temperature, so its live tables are MAP_t). Empty by default: nothing is called or copied.
  std::function<void(int, const Pose2&, bool, const Blackboard&)> after_pose;

  // Every setting of the run: model.validate(), sampler.validate(), fuse.validate() (their
  // errors prefixed "model: ", "sampler: ", "fuse: "), working_memory 1..1000 (the blackboard
  // holds this many shapelets per annealing), global_sweeps 0..1000, global_chains 1..256,
  // global_prime_explained 0..1,
  // threads 0..256, pool_steps and marginal_steps 1..sampler.schedule_steps, marginal_keep in
  // [0, 1). Every acceptance runs with every object model (the reversible jump's walls and
  // sizes: Sampler::sweepReversible).
  // okStatus(), or an Error naming the first bad field. runMapping and session::RobotSession
  // call it; a Mapper must be given valid options.
  Status validate() const;
};

// Global chains for contacts located by whisking in place unless --global-chains is given
// (useInPlaceWhiskFusion).
inline constexpr int kInPlaceGlobalChains = 32;

// The fusion of a run whose contacts the located whisker chain makes by whisking in place: the
// physics sensor (`--sim --sensor-model physics`) and the exploring robot (`--robot --explore`),
// which run the same chain and the same whisk. Such a whisk meets a wall with two whiskers and
// tells its face from a leg's (ContactReport::face_span), so the chains' tables can compete in
// the posterior: chain_fusion kPool, unless `chain_fusion_given`, and kInPlaceGlobalChains
// chains, unless `global_chains_given` (a table no chain found is lost: 8 chains that each find
// it with p = 1/4 all miss it with (1 - p)^8 = 0.10, 32 with 1e-4). The roaming robot's single
// whisker touches of walls keep the vote (docs/BLACKBOARD.md, "Faces no leg can cause, and
// pooling the chains").
void useInPlaceWhiskFusion(MappingOptions& options, bool chain_fusion_given,
                           bool global_chains_given);

}  // namespace crunch
