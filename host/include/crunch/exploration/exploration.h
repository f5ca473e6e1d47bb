// An exploration run's settings and what it reports (ARCHITECTURE.md §4: report.json
// `exploration`, the --explore, --travel-budget, --whisk-budget flags; docs/EXPLORATION.md).
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "crunch/core/geometry.h"
#include "crunch/core/result.h"
#include "crunch/exploration/path_planner.h"
#include "crunch/exploration/policy.h"

namespace crunch::exploration {

struct ExploreOptions {
  ExplorePolicyKind policy = ExplorePolicyKind::kGrid;
  // --teleport: the paper's idealisation, the robot jumps from whisk pose to whisk pose (travel
  // is still measured, as the straight-line distance). Off: the base drives the planned path.
  bool teleport = false;
  double travel_budget_m = std::numeric_limits<double>::infinity();  // > 0
  int whisk_budget = 0;          // 0: none; else >= 1
  PolicyOptions policy_options;
  PlannerOptions planner;
  double cell = 0.05;            // KnownSpace cell, metres; 0.01..0.5
  // --start x,y,theta: where the run begins (checked against the world by the run: inside an
  // obstacle or outside the region is an Error naming --start). nullopt: the run's default.
  std::optional<Pose2> start;
  // Posterior draws for policies that want them (Mapper::drawSamples): inverse temperature and
  // sweeps between draws.
  double sample_beta = 1.0;      // > 0
  int sample_sweeps = 4;         // >= 1
  // The recall-against-travel curve (with ground truth: --sim) scores the map the run would end
  // with (Mapper::inferNow: the global inference) after the first whisk, after the first whisk
  // past every further curve_step_m metres of travel, and at the end (the final map itself).
  double curve_step_m = 2.0;     // > 0

  // okStatus(), or an Error naming the flag: "--travel-budget -1: ...", "--whisk-budget ...".
  Status validate() const;
};

// One point of the recall-against-travel curve: the map the run would end with, after a whisk.
struct CurvePoint {
  double travel_m = 0.0;
  int whisks = 0;
  double recall = 0.0;
  double precision = 0.0;
  double f1 = 0.0;
};

// report.json `exploration`.
struct ExplorationReport {
  std::string policy;
  bool teleport = false;          // --teleport: travel is the straight-line distance
  double travel_m = 0.0;
  int whisks = 0;
  int bumps = 0;
  double sim_time_s = 0.0;        // simulated (sim) or the base's (robot) seconds
  double decision_ms = 0.0;       // mean wall time of one policy decision
  double decision_ms_max = 0.0;
  std::string stop_reason;        // e.g. "travel budget reached", "no candidate worth its travel"
  std::vector<CurvePoint> curve;  // empty without ground truth (the robot)
  std::vector<Pose2> path;        // the base's poses as driven, sampled every ~5 cm
  std::vector<Pose2> whisk_poses; // where each whisk began
  std::vector<Vec2> bump_points;  // where the bumper hit
};

// One decision: the costmap over `known`, the distance field from the robot, then the policy
// (ExploreState says what each argument means).
// `decision_ms` receives the wall time of the whole (costmap, field, policy), milliseconds.
Decision decide(ExplorePolicy& policy, const KnownSpace& known, const PlannerOptions& planner,
                const Pose2& robot, std::span<const MapSample> samples,
                const std::vector<WhiskerMount>& mounts, const ModelParams& model,
                std::span<const Pose2> grid_poses, int whisks, double travel_m, bool teleport,
                double arrival_tolerance, std::span<const Vec2> given_up,
                double given_up_radius, Rng& rng, double* decision_ms);

// The command line's --explore POLICY [--travel-budget M] [--whisk-budget N], shared by --sim and
// --robot (each adds its own flags): nullopt without a policy; an Error naming the flag for an
// unknown policy, a budget without --explore, or a budget validate() refuses.
Result<std::optional<ExploreOptions>> exploreOptionsFromFlags(
    const std::optional<std::string>& policy, std::optional<double> travel_budget_m,
    std::optional<int> whisk_budget);

// report.json `exploration`: every field above but the path, whisk poses and bump points
// (map.png draws those); the curve as [{travel_m, whisks, recall, precision, f1}].
nlohmann::ordered_json explorationJson(const ExplorationReport& report);

}  // namespace crunch::exploration
