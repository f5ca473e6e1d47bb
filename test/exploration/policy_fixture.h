// A small world for the policy tests: a KnownSpace, its costmap and distance field from a robot.
#pragma once

#include <memory>
#include <vector>

#include "crunch/blackboard/params.h"
#include "crunch/exploration/policy.h"

namespace crunch::exploration::testing {

struct PolicyWorld {
  KnownSpace known;
  PlannerOptions planner;
  std::vector<WhiskerMount> mounts = defaultWhiskerArray();
  ModelParams model;
  std::vector<Pose2> grid;
  std::unique_ptr<Costmap> costmap;
  std::unique_ptr<DistanceField> field;

  explicit PolicyWorld(const Vec2& hi) : known({0, 0}, hi, 0.05) {}
  ExploreState state(const Pose2& robot, bool teleport = false) {
    costmap = std::make_unique<Costmap>(known, planner);
    field = std::make_unique<DistanceField>(*costmap, robot.position());
    return ExploreState{robot, known, *costmap, *field, {}, mounts, model, grid, 0, 0.0, teleport};
  }
};

}  // namespace crunch::exploration::testing
