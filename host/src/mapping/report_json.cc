#include "crunch/mapping/report_json.h"

#include <cmath>

namespace crunch {

nlohmann::ordered_json accuracyJson(const Evaluation& ev) {
  return {{"true_tables", ev.true_tables},
          {"fused_tables", ev.fused_tables},
          {"matched", ev.matched},
          {"precision", ev.precision},
          {"recall", ev.recall},
          {"f1", ev.f1},
          {"mean_position_error_m", ev.mean_position_error},
          {"mean_angle_error_rad", ev.mean_angle_error}};
}

nlohmann::ordered_json evaluationJson(const Evaluation& ev, const MatchTolerance& tol) {
  nlohmann::ordered_json accuracy = accuracyJson(ev);
  accuracy["per_pose_tables"] = ev.per_pose_tables;
  accuracy["per_pose_match_fraction"] = ev.per_pose_match_fraction;
  accuracy["phantoms_near_walls"] = ev.phantoms_near_walls;
  accuracy["phantoms_elsewhere"] = ev.phantoms_elsewhere;
  if (ev.walls.evaluated) {
    const WallEvaluation& w = ev.walls;
    accuracy["walls"] = {{"mapped_walls", w.mapped_walls},
                         {"mapped_length_m", w.mapped_length},
                         {"boundary_touched_m", w.boundary_touched},
                         {"boundary_coverage", w.boundary_coverage},
                         {"interior_length_m", w.interior_length},
                         {"interior_found", w.interior_found},
                         {"interior_touched_m", w.interior_touched},
                         {"interior_touched_coverage", w.interior_touched_coverage},
                         {"false_length_m", w.false_length},
                         {"wall_phantoms", ev.phantoms_near_walls}};
  }
  accuracy["match_tolerance"] = {{"position_m", tol.position}, {"angle_rad", tol.angle}};
  if (std::isfinite(tol.size)) {  // sizes judged (the rooms model); the paper's report as before
    accuracy["match_tolerance"]["size_m"] = tol.size;
    accuracy["size_error_m"] = {{"mean_width", ev.mean_width_error},
                                {"max_width", ev.max_width_error},
                                {"mean_depth", ev.mean_depth_error},
                                {"max_depth", ev.max_depth_error},
                                {"mean_leg", ev.mean_leg_error},
                                {"max_leg", ev.max_leg_error}};
    accuracy["split_objects"] = ev.split_objects;
    accuracy["merged_objects"] = ev.merged_objects;
  }
  return accuracy;
}

nlohmann::ordered_json mapCountsJson(const Map& map) {
  return {{"poses", map.stats.poses},
          {"skipped_poses", map.stats.skipped_poses},
          {"inferring_poses", map.per_pose.size()},
          {"shapelets", map.stats.shapelets},
          {"rejected_reports", map.stats.rejected_reports},
          {"proposals", map.stats.proposals},
          {"peak_live_tables", map.stats.peak_live_tables},
          {"peak_live_legs", map.stats.peak_live_legs}};
}

nlohmann::ordered_json globalInferenceJson(const MapStats& stats) {
  nlohmann::ordered_json moves = nlohmann::ordered_json::object();
  for (size_t k = 0; k < kMoveKinds; ++k) {
    const MoveCount& c = stats.global_moves[k];
    if (c.proposals == 0) continue;
    moves[moveKindName(static_cast<MoveKind>(k))] = {{"proposals", c.proposals},
                                                     {"accepted", c.accepted}};
  }
  return {{"wall_s", stats.global_s}, {"threads", stats.global_threads}, {"moves", moves}};
}

nlohmann::ordered_json modelJson(const ModelParams& model) {
  return {{"objects", objectModelName(model.objects)},
          {"sigma_r_shapelet", model.sigma_r_shapelet},
          {"sigma_theta_shapelet", model.sigma_theta_shapelet},
          {"sigma_r_leg", model.sigma_r_leg},
          {"sigma_theta_leg", model.sigma_theta_leg}};
}

nlohmann::ordered_json samplerJson(const MappingOptions& options) {
  const SamplerOptions& s = options.sampler;
  return {{"schedule_steps", s.schedule_steps},
          {"schedule_log_top", s.schedule_log_top},
          {"schedule_log_step", s.schedule_log_step},
          {"sweeps_per_temperature", s.sweeps_per_temperature},
          {"working_memory", options.working_memory},
          {"global_sweeps", options.global_sweeps},
          {"global_chains", options.global_chains},
          {"global_prime_explained", options.global_prime_explained},
          {"smart_proposals", s.smart_parent},
          {"acceptance", acceptanceName(s.acceptance)},
          {"chain_fusion", chainFusionName(options.chain_fusion)},
          {"marginal_steps", options.marginal_steps}};
}

}  // namespace crunch
