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
          {"sigma_phi_rad", e.sigmaPhi()},
          {"mean_phi_error_rad", e.meanPhi()},
          {"whisks", e.whisks},
          {"episodes", e.episodes},
          {"touches_without_radial_estimate", e.no_radial},
          {"touches_without_orientation", e.no_orientation},
          {"simulated_s", e.simulated_s},
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
  j["accuracy"] = evaluationJson(run.evaluation);
  j["counts"] = mapCountsJson(run.map);
  j["timings_s"] = {{"sense_and_infer", run.map.stats.wall_s}, {"total", total_s}};
  if (run.physics) j["physics"] = physicsJson(*run.physics);
  j["model"] = modelJson(run.model);
  j["sampler"] = samplerJson(options.mapping);
  return j.dump(2) + "\n";
}

}  // namespace crunch::sim
