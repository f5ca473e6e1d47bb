// The mapping run of paper §2.8: visit the poses in order, turn each pose's contact reports into
// shapelets, push them into the blackboard's working memory, anneal (Algorithm 1) and record
// MAP_t (eq. 27); then fuse the collation into one map (fused_map.h).
#pragma once

#include <functional>
#include <vector>

#include "crunch/mapping/map.h"
#include "crunch/mapping/mapping_options.h"
#include "crunch/mapping/sensor_model.h"

namespace crunch {

class Mapper;  // mapper.h

// Maps the world seen through `sensor` from `poses` (already filtered for reachability;
// `skipped` says how many were dropped). Deterministic for a given seed: sensor noise and the
// sampler draw from separate streams, so sampler settings do not change the sensed data.
// Inference runs at poses that sensed at least one new shapelet; per_pose lists those poses.
// The robot's body stands at every pose, so its disc is free space (Mapper::addBodySweep with
// the pose as both ends, options.body_sweep): no leg or table corner stands where the robot was.
// An Error (nothing sensed) when options.validate() fails.
Result<Map> runMapping(SensorModel& sensor, const std::vector<Pose2>& poses, int skipped,
               const MappingOptions& options);

// Called after each pose is mapped with the mapper (read-only) and the pose: a live view of the
// run (`--serve`, serve/live_view.h). Mapper::snapshot() draws nothing, so an observer that
// reads it leaves the map as it would be without one.
using MapperObserver = std::function<void(const Mapper& mapper, const Pose2& pose)>;

// runMapping with `observe` (may be empty) called after each pose, before options.progress.
Result<Map> runMapping(SensorModel& sensor, const std::vector<Pose2>& poses, int skipped,
                       const MappingOptions& options, const MapperObserver& observe);

}  // namespace crunch
