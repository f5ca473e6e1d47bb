// The mapping run of paper §2.8: visit the poses in order, turn each pose's contact reports into
// shapelets, push them into the blackboard's working memory, anneal (Algorithm 1) and record
// MAP_t (eq. 27); then fuse the collation into one map (fused_map.h).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "crunch/blackboard/params.h"
#include "crunch/blackboard/sampler.h"
#include "crunch/mapping/fused_map.h"
#include "crunch/mapping/map.h"
#include "crunch/mapping/sensor_model.h"

namespace crunch {

struct MappingOptions {
  ModelParams model;
  SamplerOptions sampler;
  FuseOptions fuse;
  int working_memory = 7;  // the paper's queue of the seven most recent shapelets
  uint64_t seed = 1;
  // > 0: the fused map is one annealing over all shapelets with this many sweeps per
  // temperature (global inference); 0: clustering of the per-pose MAPs (fused_map.h).
  int global_sweeps = 8;
  int global_chains = 8;  // independent chains; a table needs half of them to agree
  // The global inference also weighs negative evidence: where whiskers swept and touched
  // nothing (free_space.h). Per-pose MAPs never do (the paper's collation).
  bool negative_evidence = true;
  // Called after each pose with (poses done, poses total); may be empty.
  std::function<void(int, int)> progress;
  // Blackboard snapshots (`crunchhost --sim --snapshot K`, paper Figs. 3-4): called by
  // Mapper::addPose after every pose, with the pose's index in the run's order (0-based), the
  // pose, whether it annealed (false: no new shapelet, the blackboard is as the last annealing
  // left it) and const access to the blackboard at the end of that annealing (its coldest
  // temperature, so its live tables are MAP_t). Empty by default: nothing is called or copied.
  std::function<void(int, const Pose2&, bool, const Blackboard&)> after_pose;
};

// Maps the world seen through `sensor` from `poses` (already filtered for reachability;
// `skipped` says how many were dropped). Deterministic for a given seed: sensor noise and the
// sampler draw from separate streams, so sampler settings do not change the sensed data.
// Inference runs at poses that sensed at least one new shapelet; per_pose lists those poses.
Map runMapping(SensorModel& sensor, const std::vector<Pose2>& poses, int skipped,
               const MappingOptions& options);

}  // namespace crunch
