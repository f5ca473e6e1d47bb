// The mapping run's parts of report.json (ARCHITECTURE.md §4: "accuracy against the scene,
// timings"), for every mode that writes one: accuracy (evaluation.h), the run's counts and
// timings (MapStats), the eq. 12 model sigmas and the sampler settings (MappingOptions). The
// simulator's report (crunch_sim/sim_report.h) assembles them with its own parts.
// Objects keep their keys in the order written (nlohmann::ordered_json).
#pragma once

#include <nlohmann/json.hpp>

#include "crunch/mapping/evaluation.h"
#include "crunch/mapping/map.h"
#include "crunch/mapping/mapping_options.h"

namespace crunch {

// true_tables, fused_tables, matched, precision, recall, f1, mean_position_error_m,
// mean_angle_error_rad.
nlohmann::ordered_json accuracyJson(const Evaluation& ev);

// accuracyJson plus per_pose_tables, per_pose_match_fraction, phantoms_near_walls,
// phantoms_elsewhere and match_tolerance {position_m, angle_rad}.
nlohmann::ordered_json evaluationJson(const Evaluation& ev, const MatchTolerance& tol = {});

// poses, skipped_poses, inferring_poses (map.per_pose), shapelets, rejected_reports, proposals,
// peak_live_tables, peak_live_legs.
nlohmann::ordered_json mapCountsJson(const Map& map);

// The global inference's wall time and threads: {"wall_s", "threads"} (MapStats::global_s,
// global_threads; 0 and 0 without one). Measured: differs from machine to machine and run to
// run, never part of a result.
nlohmann::ordered_json globalInferenceJson(const MapStats& stats);

// sigma_r_shapelet, sigma_theta_shapelet, sigma_r_leg, sigma_theta_leg (eq. 12).
nlohmann::ordered_json modelJson(const ModelParams& model);

// The schedule, sweeps, working memory, global inference and proposal settings.
nlohmann::ordered_json samplerJson(const MappingOptions& options);

}  // namespace crunch
