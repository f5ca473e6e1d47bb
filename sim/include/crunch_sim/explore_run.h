// The driven `--sim --explore` run (issue 14; docs/EXPLORATION.md "Driving and the simple
// policies"): the scene's World, the simulator's KinematicBase (the Create's geometry, bumpers
// against the walls and legs) driven by the session's ExploreLoop in simulated time (steps of
// ExploreSimOptions::dt), the whiskers' touches while driving from the World's ray casts along
// each whisker (the simulator standing in for the contact detector), and at each whisk the
// SensorModel sensing the body whisk at the pose where it began: its reports and free rays go to
// the Mapper and to the KnownSpace, the Mapper's snapshot() map is evaluated against the scene
// into the recall-against-travel curve and its tables and walls become the planner's map
// obstacles. --teleport jumps from whisk pose to whisk pose instead (travel is the straight-line
// distance; no transit touches, no bumps).
//
// The robot is told the extent of the room (the scene's arena rectangle: the KnownSpace's region,
// its edge a wall for the planner), not what is in it. The start pose is ExploreOptions::start or
// the first reachable pose of the scene's list.
//
// Errors (nothing run): invalid ExploreOptions (the flag named), a start outside the arena or
// where the body overlaps a wall or leg ("--start x,y,theta: ..."), no start at all.
// Thread-safety: with `world_mutex`, every World query holds it (sim_run.h).
#pragma once

#include <cstdint>
#include <functional>
#include <mutex>

#include "crunch/exploration/exploration.h"
#include "crunch/mapping/map.h"
#include "crunch/mapping/mapping_options.h"
#include "crunch/mapping/run_mapping.h"
#include "crunch/mapping/sensor_model.h"
#include "crunch_sim/sim_run.h"

namespace crunch::sim {

struct ExploreSimOptions {
  double dt = 0.02;                 // s of simulated time per control step
  double max_sim_time_s = 6 * 3600.0;  // the run ends here whatever the policy says
  // Driven runs: called after every control step with the base's pose and simulated time (a
  // live view's path, `--serve`); reads only, so the run is the same with or without it.
  std::function<void(const Pose2& pose, double sim_t)> moved;
  // Called after each whisk is mapped, with the mapper (read-only; runMapping's MapperObserver).
  MapperObserver observe;
};

struct ExploreRun {
  Map map;  // Mapper::finish()
  exploration::ExplorationReport report;
};

// `mapping` is the run's (seed, model with the sensor's noise, chain fusion already set).
Result<ExploreRun> runExploration(const SimScene& scene, SensorModel& sensor,
                                  const MappingOptions& mapping,
                                  const exploration::ExploreOptions& explore,
                                  std::mutex* world_mutex, const ExploreSimOptions& sim = {});

}  // namespace crunch::sim
