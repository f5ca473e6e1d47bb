#include "crunch_sim/sim_report.h"

#include "crunch/mapping/report_json.h"

namespace crunch::sim {

namespace {

nlohmann::ordered_json physicsJson(const PhysicsSummary& physics) {
  const ReportErrors& e = physics.errors;
  return {{"models", physics.models},
          {"reports_scored", e.reports},
          {"reports_unscored", e.unscored},
          {"sigma_r_m", e.sigmaR()},
          {"mean_r_error_m", e.meanR()},
          {"contact_position_error_m",
           {{"median", quantile(e.position_errors, 0.5)},
            {"p90", quantile(e.position_errors, 0.9)},
            {"reports", e.position_errors.size()},
            {"legs", {{"median", quantile(e.leg_position_errors, 0.5)},
                      {"p90", quantile(e.leg_position_errors, 0.9)},
                      {"reports", e.leg_position_errors.size()},
                      {"to_first_touch", {{"median", quantile(e.leg_first_touch_errors, 0.5)},
                                          {"p90", quantile(e.leg_first_touch_errors, 0.9)}}}}},
            {"walls", {{"median", quantile(e.wall_position_errors, 0.5)},
                       {"p90", quantile(e.wall_position_errors, 0.9)},
                       {"reports", e.wall_position_errors.size()}}}}},
          {"tip_shaft",
           {{"true_tip_reported_tip", e.tip_confusion[0][0]},
            {"true_tip_reported_shaft", e.tip_confusion[0][1]},
            {"true_shaft_reported_tip", e.tip_confusion[1][0]},
            {"true_shaft_reported_shaft", e.tip_confusion[1][1]}}},
          {"oriented_reports", e.oriented},
          {"sigma_phi_rad", e.sigmaPhi()},
          {"mean_phi_error_rad", e.meanPhi()},
          {"whisks", e.whisks},
          {"episodes", e.episodes},
          {"touches_without_radial_estimate", e.no_radial},
          {"touches_without_orientation", e.no_orientation},
          {"touches_without_ramp", e.no_ramp},
          {"simulated_s", e.simulated_s},
          {"whisker_steps", e.whisker_steps},
          {"whisker_steps_in_ode", e.ode_whisker_steps},
          {"gaussian_same_scene",
           {{"noise", "realistic"},
            {"accuracy", accuracyJson(physics.gaussian)},
            {"sense_and_infer_s", physics.gaussian_s}}}};
}

}  // namespace

std::string simReportJson(const Scene& scene, const SimRun& run, const SimRunOptions& options,
                          double total_s) {
  nlohmann::ordered_json j;
  j["schema"] = "crunch.report/1";
  j["scene"] = scene.source;
  j["sensor_model"] = sensorKindName(options.sensor);
  j["noise"] = {
      {"name", run.noise.name}, {"sigma_r", run.noise.sigma_r}, {"sigma_phi", run.noise.sigma_phi}};
  j["seed"] = options.seed;
  j["accuracy"] = evaluationJson(run.evaluation, matchToleranceFor(run.model));
  j["counts"] = mapCountsJson(run.map);
  j["timings_s"] = {{"sense_and_infer", run.map.stats.wall_s}, {"total", total_s}};
  j["global_inference"] = globalInferenceJson(run.map.stats);
  if (run.physics) j["physics"] = physicsJson(*run.physics);
  if (run.exploration) j["exploration"] = exploration::explorationJson(*run.exploration);
  j["model"] = modelJson(run.model);
  j["sampler"] = samplerJson(run.mapping);
  return j.dump(2) + "\n";
}

}  // namespace crunch::sim
