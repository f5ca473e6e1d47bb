#include "sim_mode.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <ostream>

#include "crunch/mapping/evaluation.h"
#include "crunch/mapping/map_io.h"
#include "crunch/render/map_render.h"
#include "crunch/scene/scene.h"
#include "crunch/signal/models_io.h"
#include "crunch_sim/physics_sensor.h"
#include "crunch_sim/ray_sensor.h"
#include "crunch_sim/world.h"

namespace crunch::app {

namespace {

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

// The physics path's own measurements, and the gaussian run on the same scene beside them.
struct PhysicsSummary {
  sim::ReportErrors errors;
  std::string models;
  Evaluation gaussian;
  double gaussian_s = 0.0;
};

std::string reportJson(const Scene& scene, const Map& map, const Evaluation& ev,
                       const SimOptions& opt, const ModelParams& model, const NoiseRegime& noise,
                       double total_s, const std::optional<PhysicsSummary>& physics) {
  nlohmann::ordered_json j;
  j["schema"] = "crunch.report/1";
  j["scene"] = scene.source;
  j["sensor_model"] = opt.sensor_model;
  j["noise"] = {{"name", noise.name}, {"sigma_r", noise.sigma_r}, {"sigma_phi", noise.sigma_phi}};
  j["seed"] = opt.seed;
  nlohmann::ordered_json accuracy = accuracyJson(ev);
  accuracy["per_pose_tables"] = ev.per_pose_tables;
  accuracy["per_pose_match_fraction"] = ev.per_pose_match_fraction;
  accuracy["phantoms_near_walls"] = ev.phantoms_near_walls;
  accuracy["phantoms_elsewhere"] = ev.phantoms_elsewhere;
  accuracy["match_tolerance"] = {{"position_m", 0.15}, {"angle_rad", 15.0 * kPi / 180.0}};
  j["accuracy"] = accuracy;
  j["counts"] = {{"poses", map.stats.poses},
                 {"skipped_poses", map.stats.skipped_poses},
                 {"inferring_poses", map.per_pose.size()},
                 {"shapelets", map.stats.shapelets},
                 {"rejected_reports", map.stats.rejected_reports},
                 {"proposals", map.stats.proposals},
                 {"peak_live_tables", map.stats.peak_live_tables},
                 {"peak_live_legs", map.stats.peak_live_legs}};
  j["timings_s"] = {{"sense_and_infer", map.stats.wall_s}, {"total", total_s}};
  if (physics) {
    const sim::ReportErrors& e = physics->errors;
    j["physics"] = {
        {"models", physics->models},
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
          {"accuracy", accuracyJson(physics->gaussian)},
          {"sense_and_infer_s", physics->gaussian_s}}}};
  }
  const SamplerOptions& s = opt.mapping.sampler;
  j["model"] = {{"sigma_r_shapelet", model.sigma_r_shapelet},
                {"sigma_theta_shapelet", model.sigma_theta_shapelet},
                {"sigma_r_leg", model.sigma_r_leg},
                {"sigma_theta_leg", model.sigma_theta_leg}};
  j["sampler"] = {{"schedule_steps", s.schedule_steps},
                  {"schedule_log_top", s.schedule_log_top},
                  {"schedule_log_step", s.schedule_log_step},
                  {"sweeps_per_temperature", s.sweeps_per_temperature},
                  {"working_memory", opt.mapping.working_memory},
                  {"global_sweeps", opt.mapping.global_sweeps},
                  {"global_chains", opt.mapping.global_chains},
                  {"smart_proposals", s.smart_parent}};
  return j.dump(2) + "\n";
}

class ProgressBar {
 public:
  ProgressBar(std::ostream& os, bool json) : os_(os), json_(json) {}
  void operator()(int done, int total) {
    if (json_) {
      if (done == total || done % 20 == 0)
        os_ << "{\"event\":\"progress\",\"done\":" << done << ",\"total\":" << total << "}\n";
      return;
    }
    const int width = 40;
    const int filled = total > 0 ? done * width / total : width;
    if (filled == last_ && done != total) return;
    last_ = filled;
    os_ << "\r[" << std::string(static_cast<size_t>(filled), '#')
        << std::string(static_cast<size_t>(width - filled), ' ') << "] " << done << "/" << total
        << " poses" << (done == total ? "\n" : "") << std::flush;
  }

 private:
  std::ostream& os_;
  bool json_;
  int last_ = -1;
};

}  // namespace

int runSim(const SimOptions& opt, std::ostream& out, std::ostream& err) {
  const auto t0 = std::chrono::steady_clock::now();
  // ---- Validate everything before anything is written.
  Scene scene = defaultArena();
  if (opt.scene_path) {
    auto loaded = loadScene(*opt.scene_path);
    if (!loaded) {
      err << "crunchhost: " << loaded.error().message << "\n";
      return 2;
    }
    scene = std::move(loaded).value();
  }
  const bool physics = opt.sensor_model == "physics";
  std::optional<signal::SignalModels> models;
  const std::string models_path =
      opt.models_path.empty() ? std::string(CRUNCH_DEFAULT_MODELS) : opt.models_path;
  if (physics) {
    auto loaded = signal::loadModels(models_path);
    if (!loaded) {
      err << "crunchhost: --sensor-model physics: " << loaded.error().message
          << " (train models with `crunchhost train`, or pass --models FILE)\n";
      return 2;
    }
    models = std::move(loaded).value();
  }
  if (!physics && opt.sensor_model != "gaussian" && opt.sensor_model != "ideal") {
    err << "crunchhost: --sensor-model: unknown model '" << opt.sensor_model
        << "' (expected physics, gaussian or ideal)\n";
    return 2;
  }
  auto named = noiseRegimeByName(opt.noise);
  if (!named) {
    err << "crunchhost: --" << named.error().message << "\n";
    return 2;
  }
  std::optional<NoiseRegime> noise = named.value();
  if (opt.sensor_model == "ideal") noise = NoiseRegime::ideal();
  // The physics path has no injected noise: its noise is what its classifiers make (§4), and
  // the blackboard's sensor sigmas (eq. 12) are the paper's measured classifier errors.
  if (physics) noise = NoiseRegime::classifiers();
  if (auto st = opt.mapping.validate(); !st) {
    err << "crunchhost: mapping options: " << st.error().message << "\n";
    return 2;
  }

  // ---- Simulate and map.
  auto world = sim::World::build(scene);
  int skipped = 0;
  const std::vector<Pose2> poses = world->reachablePoses(scene.poses, &skipped);
  sim::RaySensorModel ray_sensor(*world, defaultWhiskerArray(), *noise, {});
  std::unique_ptr<sim::PhysicsSensorModel> physics_sensor;
  if (physics) {
    auto created = sim::PhysicsSensorModel::create(*world, defaultWhiskerArray(), *models, poses,
                                                   sim::physicsSensorOptions(opt.seed));
    if (!created) {
      err << "crunchhost: --sensor-model physics: " << created.error().message << "\n";
      return 2;
    }
    physics_sensor = std::move(created).value();
  }
  if (opt.snapshot_pose &&
      (*opt.snapshot_pose < 0 || *opt.snapshot_pose >= static_cast<int>(poses.size()))) {
    err << "crunchhost: --snapshot " << *opt.snapshot_pose << ": no such pose; the run has "
        << poses.size() << " reachable poses, numbered 0 to " << int(poses.size()) - 1 << "\n";
    return 2;
  }
  if (opt.snapshot_temperature &&
      (!opt.snapshot_pose || *opt.snapshot_temperature < 0 ||
       *opt.snapshot_temperature >= opt.mapping.sampler.schedule_steps)) {
    err << "crunchhost: --snapshot-temperature " << *opt.snapshot_temperature
        << ": needs --snapshot K and a step from 0 (the hottest) to "
        << opt.mapping.sampler.schedule_steps - 1 << " (the coldest)\n";
    return 2;
  }
  SensorModel& sensor = physics ? static_cast<SensorModel&>(*physics_sensor) : ray_sensor;
  MappingOptions mopt = opt.mapping;
  mopt.seed = opt.seed;
  mopt.model = withSensorNoise(mopt.model, *noise);
  ProgressBar bar(opt.json_progress ? out : err, opt.json_progress);
  mopt.progress = [&](int done, int total) { bar(done, total); };
  std::optional<BlackboardSnapshot> snap;
  // Copies the blackboard once: at pose K, after the chosen temperature (--snapshot-
  // temperature) or at the end of the annealing (the coldest: its live tables are MAP_t).
  // (Declared here: the hooks below hold references to it while runMapping runs.)
  const SamplerOptions& so = mopt.sampler;
  // `at_end`: the annealing is over, so the live tables are MAP_t (drawn bold).
  auto take = [&snap, &so](int t, const Pose2& pose, const Blackboard& board,
                           const std::string& when, bool at_end) {
      BlackboardSnapshot s;
      s.pose_index = t;
      s.robot = pose;
      s.whiskers = defaultWhiskerArray();
      const ModelParams& m = board.params();
      s.table_width = m.table_width;
      s.table_depth = m.table_depth;
      s.leg_side = m.leg_side;
      for (int slot = 0; slot < board.workingMemoryCapacity(); ++slot)
        if (board.slotUsed(slot)) s.shapelets.push_back(board.shapelet(slot));
      for (int32_t id = 0; id < board.tableExtent(); ++id)
        if (board.table(id).alive) s.tables.push_back({board.table(id).pose, at_end});
      for (int32_t id = 0; id < board.legExtent(); ++id) {
        const LegHyp& l = board.leg(id);
        if (!l.alive) continue;
        const bool in_table = l.parent != kNone && board.table(l.parent).alive;
        s.legs.push_back({l.pose, l.side, in_table});
      }
      char buf[240];
      std::snprintf(buf, sizeof buf, "pose %d (%.2f, %.2f, %.0f deg), %s, %d sweep(s) each |", t,
                    pose.x, pose.y, pose.theta * 180.0 / kPi, when.c_str(),
                    so.sweeps_per_temperature);
      s.title = buf;
      snap = std::move(s);
    };
  if (opt.snapshot_pose) {
    const int k = *opt.snapshot_pose;
    const std::optional<int> step = opt.snapshot_temperature;
    if (step) {
      // During pose K's annealing: the pose index is the one after the last after_pose call.
      auto next_pose = std::make_shared<int>(0);
      mopt.after_pose = [next_pose](int t, const Pose2&, bool, const Blackboard&) {
        *next_pose = t + 1;
      };
      const std::vector<Pose2>* pose_list = &poses;
      const int chosen = *step;
      mopt.sampler.after_temperature = [&take, &snap, &so, next_pose, pose_list, k, chosen](
                                           int i, double beta, const Blackboard& board) {
        if (*next_pose != k || i != chosen || snap) return;
        char when[120];
        std::snprintf(when, sizeof when, "after temperature %d of %d (0 hottest), beta = %.3g", i,
                      so.schedule_steps, beta);
        take(k, (*pose_list)[static_cast<std::size_t>(k)], board, when,
             i == so.schedule_steps - 1);
      };
    } else {
      mopt.after_pose = [&take, k, &so](int t, const Pose2& pose, bool annealed,
                                        const Blackboard& board) {
        if (t != k) return;
        char when[120];
        std::snprintf(when, sizeof when, "%s at T = exp(-%.1f), coldest of %d",
                      annealed ? "annealed" : "no new shapelet; as last annealed",
                      so.schedule_log_top, so.schedule_steps);
        take(t, pose, board, when, true);
      };
    }
  }
  const Map map = runMapping(sensor, poses, skipped, mopt).value();  // validated above
  if (opt.snapshot_temperature && !snap) {
    err << "crunchhost: --snapshot " << *opt.snapshot_pose << ": pose " << *opt.snapshot_pose
        << " sensed nothing new and did not anneal, so there is no temperature to draw; "
           "no snapshot written (without --snapshot-temperature it shows the blackboard as the "
           "last annealing left it)\n";
  }
  const Evaluation ev = evaluate(map, scene);
  std::optional<PhysicsSummary> physics_summary;
  if (physics) {
    // The gaussian shortcut on the same scene and seed, for report.json's comparison.
    PhysicsSummary ps;
    ps.errors = physics_sensor->errors();
    ps.models = models_path;
    sim::RaySensorModel reference(*world, defaultWhiskerArray(), NoiseRegime::realistic(), {});
    MappingOptions ref_opt = mopt;
    ref_opt.progress = nullptr;
    ref_opt.after_pose = nullptr;
    const Map ref_map = runMapping(reference, poses, skipped, ref_opt).value();
    ps.gaussian = evaluate(ref_map, scene);
    ps.gaussian_s = ref_map.stats.wall_s;
    physics_summary = ps;
  }

  // ---- Write: each file complete or not at all.
  if (auto s = ensureDirectory(opt.out_dir); !s) {
    err << "crunchhost: " << s.error().message << "\n";
    return 1;
  }
  const std::string dir = opt.out_dir + "/";
  RenderOptions ropt;
  ropt.title = "crunchhost --sim, noise " + noise->name + ", seed " + std::to_string(opt.seed);
  const double total_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // Stop at the first failure: a later file is not written after an earlier one failed.
  const std::function<Status()> writes[] = {
      [&] { return writeFileAtomic(dir + "map.json", mapToJson(map)); },
      [&] { return renderMapPng(map, scene, dir + "map.png", ropt); },
      [&] {
        return writeFileAtomic(dir + "report.json",
                               reportJson(scene, map, ev, opt, mopt.model, *noise, total_s,
                                          physics_summary));
      },
      [&]() -> Status {
        if (!snap) return okStatus();
        const std::string base = dir + "snapshot_" + std::to_string(snap->pose_index);
        if (Status st = renderSnapshotPng(*snap, scene, base + ".png"); !st) return st;
        return renderSnapshotSvg(*snap, scene, base + ".svg");
      }};
  for (const auto& write : writes) {
    if (const Status status = write(); !status) {
      err << "crunchhost: " << status.error().message << "\n";
      return 1;
    }
  }
  if (opt.json_progress) {
    out << "{\"event\":\"done\",\"recall\":" << ev.recall << ",\"precision\":" << ev.precision
        << ",\"out\":\"" << opt.out_dir << "\"}\n";
  } else {
    out << "mapped " << scene.source << ": " << map.stats.poses << " poses ("
        << map.stats.skipped_poses << " skipped), " << map.stats.shapelets << " shapelets, "
        << map.tables.size() << " tables in the fused map\n"
        << "recall " << ev.recall << ", precision " << ev.precision << " ("
        << ev.phantoms_near_walls << " phantoms near walls, " << ev.phantoms_elsewhere
        << " elsewhere), mean error " << ev.mean_position_error << " m / "
        << ev.mean_angle_error * 180.0 / kPi << " deg\n"
        << "inference " << map.stats.wall_s << " s; wrote " << dir << "{map.json,map.png,report.json}\n";
    if (snap) out << "wrote " << dir << "snapshot_" << snap->pose_index << ".{png,svg}\n";
  }
  return 0;
}

}  // namespace crunch::app
