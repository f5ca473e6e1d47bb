#include "crunch_sim/sim_run.h"

#include "crunch/mapping/run_mapping.h"
#include "crunch/render/blackboard_snapshot.h"
#include "crunch/signal/models_io.h"
#include "crunch_sim/explore_run.h"
#include "crunch_sim/ray_sensor.h"

namespace crunch::sim {

namespace {

// A sensor whose every call into the World holds `mutex`.
class LockedSensor final : public SensorModel {
 public:
  LockedSensor(SensorModel& inner, std::mutex& mutex) : inner_(inner), mutex_(mutex) {}
  void sense(const Pose2& pose, Rng& rng, std::vector<ContactReport>& out) override {
    std::lock_guard<std::mutex> lock(mutex_);
    inner_.sense(pose, rng, out);
  }
  const std::vector<WhiskerMount>& mounts() const override { return inner_.mounts(); }
  void freeRays(std::vector<FreeRay>& out) const override {
    std::lock_guard<std::mutex> lock(mutex_);
    inner_.freeRays(out);
  }

 private:
  SensorModel& inner_;
  std::mutex& mutex_;
};

// Locks `mutex` if there is one.
std::unique_lock<std::mutex> lockWorld(std::mutex* mutex) {
  return mutex ? std::unique_lock<std::mutex>(*mutex) : std::unique_lock<std::mutex>();
}

Status checkSnapshot(const SimRunOptions& o, std::size_t poses) {
  if (o.snapshot_pose && (*o.snapshot_pose < 0 || *o.snapshot_pose >= static_cast<int>(poses))) {
    return Error{"--snapshot " + std::to_string(*o.snapshot_pose) +
                 ": no such pose; the run has " + std::to_string(poses) +
                 " reachable poses, numbered 0 to " + std::to_string(int(poses) - 1)};
  }
  if (o.snapshot_temperature &&
      (!o.snapshot_pose || *o.snapshot_temperature < 0 ||
       *o.snapshot_temperature >= o.mapping.sampler.schedule_steps)) {
    return Error{"--snapshot-temperature " + std::to_string(*o.snapshot_temperature) +
                 ": needs --snapshot K and a step from 0 (the hottest) to " +
                 std::to_string(o.mapping.sampler.schedule_steps - 1) + " (the coldest)"};
  }
  return okStatus();
}

// The physics sensor on `scene`, calibrated at its first clear pose.
Result<std::unique_ptr<PhysicsSensorModel>> physicsSensor(const SimScene& scene,
                                                          const SimRunOptions& o) {
  auto models = signal::loadModels(o.models_path);
  if (!models) {
    return Error{"--sensor-model physics: " + models.error().message +
                 " (train models with `crunchhost train`, or pass --models FILE)"};
  }
  auto created = PhysicsSensorModel::create(*scene.world, defaultWhiskerArray(), models.value(),
                                            scene.poses, physicsSensorOptions(o.seed));
  if (!created) return Error{"--sensor-model physics: " + created.error().message};
  return std::move(created).value();
}

// The gaussian shortcut at realistic noise on the same scene and settings, for the comparison.
PhysicsSummary physicsSummary(const SimScene& scene, const PhysicsSensorModel& sensor,
                              const SimRunOptions& o, MappingOptions mopt) {
  PhysicsSummary ps;
  ps.errors = sensor.errors();
  ps.models = o.models_path;
  RaySensorModel reference(*scene.world, defaultWhiskerArray(), NoiseRegime::realistic(), {});
  mopt.progress = nullptr;
  mopt.chain_fusion = ChainFusion::kVote;  // the classifiers' evidence: as any gaussian run
  mopt.after_pose = nullptr;
  mopt.sampler.after_temperature = nullptr;
  const Map ref_map = runMapping(reference, scene.poses, scene.skipped, mopt).value();
  ps.gaussian = evaluate(ref_map, scene.scene, matchToleranceFor(mopt.model));
  ps.gaussian_s = ref_map.stats.wall_s;
  return ps;
}

}  // namespace

Result<SensorKind> sensorKindByName(const std::string& name) {
  if (name == "gaussian") return SensorKind::kGaussian;
  if (name == "ideal") return SensorKind::kIdeal;
  if (name == "physics") return SensorKind::kPhysics;
  return Error{"--sensor-model: unknown model '" + name +
               "' (expected physics, gaussian or ideal)"};
}

const char* sensorKindName(SensorKind kind) {
  switch (kind) {
    case SensorKind::kIdeal: return "ideal";
    case SensorKind::kPhysics: return "physics";
    case SensorKind::kGaussian: break;
  }
  return "gaussian";
}

Result<Scene> loadSimScene(const std::optional<std::string>& path) {
  if (!path) return defaultArena();
  return loadScene(*path);
}

SimScene SimScene::build(Scene scene) {
  SimScene s;
  s.scene = std::move(scene);
  s.world = World::build(s.scene);
  s.poses = s.world->reachablePoses(s.scene.poses, &s.skipped);
  return s;
}

Result<SimRun> runSimulation(const SimScene& scene, const SimRunOptions& o) {
  const bool physics = o.sensor == SensorKind::kPhysics;
  SimRun run;
  run.noise = o.sensor == SensorKind::kIdeal ? NoiseRegime::ideal()
              : physics                      ? NoiseRegime::classifiers()
                                             : o.noise;
  if (auto st = run.noise.validate(); !st) return Error{"noise: " + st.error().message};
  if (auto st = o.mapping.validate(); !st) return Error{"mapping options: " + st.error().message};
  std::unique_ptr<SensorModel> sensor;
  std::unique_ptr<PhysicsSensorModel> physics_sensor;
  {
    auto lock = lockWorld(o.world_mutex);
    if (physics) {
      auto created = physicsSensor(scene, o);
      if (!created) return created.error();
      physics_sensor = std::move(created).value();
    } else {
      sensor = std::make_unique<RaySensorModel>(*scene.world, defaultWhiskerArray(), run.noise,
                                                RaySensorModel::Options{});
    }
  }
  if (o.explore) {
    if (auto st = o.explore->validate(); !st) return st.error();
    if (o.snapshot_pose) {
      return Error{"--snapshot: not with --explore (the whisk poses are not known before the run)"};
    }
  }
  if (auto st = checkSnapshot(o, scene.poses.size()); !st) return st.error();
  SensorModel& chosen = physics ? *physics_sensor : *sensor;
  std::optional<LockedSensor> locked;
  if (o.world_mutex) locked.emplace(chosen, *o.world_mutex);
  MappingOptions mopt = o.mapping;
  mopt.seed = o.seed;
  mopt.model = withSensorNoise(mopt.model, run.noise);
  // The located chain whisks in place at every pose: pooled chains, 32 of them (their ODE
  // whisks take about 100 s of the default arena's run, 32 chains a few seconds). The
  // classifiers' contacts keep the vote (mapping_options.h, useInPlaceWhiskFusion).
  if (physics) useInPlaceWhiskFusion(mopt, o.chain_fusion_given, o.global_chains_given);
  std::optional<SnapshotRecorder> recorder;
  if (o.snapshot_pose) {
    recorder.emplace(*o.snapshot_pose, o.snapshot_temperature, scene.poses, defaultWhiskerArray());
    recorder->install(mopt);
  }
  SensorModel& used = locked ? static_cast<SensorModel&>(*locked) : chosen;
  if (o.explore) {
    ExploreSimOptions so;
    so.moved = o.moved;
    so.observe = o.observe;
    auto explored = runExploration(scene, used, mopt, *o.explore, o.world_mutex, so);
    if (!explored) return explored.error();
    run.map = std::move(explored.value().map);
    run.exploration = std::move(explored.value().report);
  } else {
    run.map = runMapping(used, scene.poses, scene.skipped, mopt, o.observe).value();  // validated above
  }
  run.model = mopt.model;
  run.mapping = mopt;
  run.evaluation = evaluate(run.map, scene.scene, matchToleranceFor(mopt.model));
  if (mopt.model.walled()) run.evaluation.walls = evaluateWalls(run.map, scene.scene);
  if (recorder) run.snapshot = recorder->snapshot();
  if (o.snapshot_temperature && !run.snapshot) {
    const std::string k = std::to_string(*o.snapshot_pose);
    run.warning = "--snapshot " + k + ": pose " + k +
                  " sensed nothing new and did not anneal, so there is no temperature to draw; "
                  "no snapshot written (without --snapshot-temperature it shows the blackboard "
                  "as the last annealing left it)";
  }
  if (physics) run.physics = physicsSummary(scene, *physics_sensor, o, mopt);
  return run;
}

}  // namespace crunch::sim
