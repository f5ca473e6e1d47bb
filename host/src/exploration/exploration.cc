#include "crunch/exploration/exploration.h"

#include <chrono>
#include <cmath>
#include <sstream>

namespace crunch::exploration {

namespace {
std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}
}  // namespace

Status ExploreOptions::validate() const {
  if (std::isnan(travel_budget_m) || travel_budget_m <= 0) {
    return Error{"--travel-budget " + num(travel_budget_m) + ": must be above 0 (metres)"};
  }
  if (whisk_budget < 0) {
    return Error{"--whisk-budget " + std::to_string(whisk_budget) +
                 ": must be 1 or more (0: no budget)"};
  }
  if (!std::isfinite(cell) || cell < 0.01 || cell > 0.5) {
    return Error{"exploration cell " + num(cell) + ": must be 0.01 to 0.5 metres"};
  }
  if (!std::isfinite(sample_beta) || sample_beta <= 0) {
    return Error{"exploration sample_beta " + num(sample_beta) + ": must be above 0"};
  }
  if (!std::isfinite(curve_step_m) || curve_step_m <= 0) {
    return Error{"exploration curve_step_m " + num(curve_step_m) + ": must be above 0 (metres)"};
  }
  if (sample_sweeps < 1) {
    return Error{"exploration sample_sweeps " + std::to_string(sample_sweeps) + ": must be 1 or more"};
  }
  if (start && (!std::isfinite(start->x) || !std::isfinite(start->y) ||
                !std::isfinite(start->theta))) {
    return Error{"--start: x, y and theta must be finite numbers"};
  }
  if (auto st = policy_options.validate(); !st) return st.error();
  if (auto st = planner.validate(); !st) return st.error();
  return okStatus();
}

Decision decide(ExplorePolicy& policy, const KnownSpace& known, const PlannerOptions& planner,
                const Pose2& robot, std::span<const MapSample> samples,
                const std::vector<WhiskerMount>& mounts, const ModelParams& model,
                std::span<const Pose2> grid_poses, int whisks, double travel_m, bool teleport,
                double arrival_tolerance, std::span<const Vec2> given_up,
                double given_up_radius, Rng& rng, double* decision_ms) {
  const auto t0 = std::chrono::steady_clock::now();
  const Costmap costmap(known, planner);
  const DistanceField field(costmap, robot.position());
  const ExploreState state{robot, known, costmap, field, samples, mounts, model,
                           grid_poses, whisks, travel_m, teleport, arrival_tolerance,
                           given_up, given_up_radius};
  Decision d = policy.next(state, rng);
  if (decision_ms) {
    *decision_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }
  return d;
}

// report.json `exploration` (ARCHITECTURE.md §4, docs/EXPLORATION.md).
nlohmann::ordered_json explorationJson(const ExplorationReport& x) {
  nlohmann::ordered_json curve = nlohmann::ordered_json::array();
  for (const CurvePoint& c : x.curve) {
    curve.push_back({{"travel_m", c.travel_m}, {"whisks", c.whisks}, {"recall", c.recall},
                     {"precision", c.precision}, {"f1", c.f1}});
  }
  return {{"policy", x.policy},         {"teleport", x.teleport},
          {"travel_m", x.travel_m},     {"whisks", x.whisks},
          {"bumps", x.bumps},           {"sim_time_s", x.sim_time_s},
          {"decision_ms", x.decision_ms}, {"decision_ms_max", x.decision_ms_max},
          {"stop_reason", x.stop_reason}, {"curve", curve}};
}


Result<std::optional<ExploreOptions>> exploreOptionsFromFlags(
    const std::optional<std::string>& policy, std::optional<double> travel_budget_m,
    std::optional<int> whisk_budget) {
  if (!policy) {
    if (travel_budget_m) return Error{"--travel-budget: needs --explore POLICY"};
    if (whisk_budget) return Error{"--whisk-budget: needs --explore POLICY"};
    return std::optional<ExploreOptions>{};
  }
  auto kind = explorePolicyByName(*policy);
  if (!kind) return kind.error();
  ExploreOptions e;
  e.policy = kind.value();
  if (travel_budget_m) e.travel_budget_m = *travel_budget_m;
  if (whisk_budget) e.whisk_budget = *whisk_budget;
  if (auto st = e.validate(); !st) return st.error();
  return std::optional<ExploreOptions>{e};
}

}  // namespace crunch::exploration
