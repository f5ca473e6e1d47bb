// One simulated mapping run (`crunchhost --sim`, and each point of `crunchhost sweep`;
// ARCHITECTURE.md §2, §4): scene -> World -> reachable poses -> sensor model -> runMapping
// (paper §2.8) -> evaluate against the scene's ground truth.
//
// Sensor models (--sensor-model):
//   gaussian  the paper's own mapping experiment: ODE ray casts find the contacts, the reports
//             get the noise regime's Gaussian noise (RaySensorModel, eqs. 4-5);
//   ideal     the same ray sensor without noise (the regime is NoiseRegime::ideal());
//   physics   bending whiskers through the Hall model, the whisker-board firmware, the bridge
//             decoder and the paper's classifiers (PhysicsSensorModel). No injected noise: the
//             blackboard's sensor sigmas are the classifiers' measured errors
//             (NoiseRegime::classifiers()). The gaussian sensor at realistic noise is run on the
//             same scene and seed beside it, for report.json's comparison (PhysicsSummary).
// Every run raises eq. 12's shapelet sigmas to the regime's (withSensorNoise) and draws only from
// its seed (runMapping's sensor and sampler streams): the same options give the same map.
//
// Errors, all before mapping starts (the run writes nothing): invalid MappingOptions or noise
// ("mapping options: ...", "noise: ..."), a models file that does not load or a rig that cannot
// start ("--sensor-model physics: ..."), a snapshot pose or temperature out of range
// ("--snapshot K: ...", "--snapshot-temperature I: ...").
//
// Ownership: a SimScene owns its World; runs only read it. Thread-safety: ODE's collision scratch
// is global in this build (world.h), so runs on several threads must share one `world_mutex`:
// every World query (building the sensor, sensing) then holds it, and inference runs in parallel.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "crunch/exploration/exploration.h"
#include "crunch/mapping/evaluation.h"
#include "crunch/mapping/map.h"
#include "crunch/mapping/mapping_options.h"
#include "crunch/mapping/run_mapping.h"
#include "crunch/mapping/sensor_model.h"
#include "crunch/render/map_render.h"
#include "crunch/scene/scene.h"
#include "crunch_sim/physics_sensor.h"
#include "crunch_sim/world.h"

namespace crunch::sim {

enum class SensorKind { kGaussian, kIdeal, kPhysics };
// "gaussian", "ideal" or "physics"; an Error naming --sensor-model and the choices otherwise.
Result<SensorKind> sensorKindByName(const std::string& name);
const char* sensorKindName(SensorKind kind);

// The scene file (or, without a path, the built-in default arena). Errors name the file and field.
Result<Scene> loadSimScene(const std::optional<std::string>& path);

// A scene built for mapping: its World and the reachable poses of its pose list.
struct SimScene {
  Scene scene;
  std::unique_ptr<World> world;
  std::vector<Pose2> poses;  // the scene's poses where the body fits, in order
  int skipped = 0;           // poses dropped
  static SimScene build(Scene scene);
};

struct SimRunOptions {
  SensorKind sensor = SensorKind::kGaussian;
  NoiseRegime noise = NoiseRegime::realistic();  // gaussian only (ideal and physics: see above)
  std::string models_path;  // physics: the signal models file (signal/models_io.h)
  std::uint64_t seed = 1;   // replaces mapping.seed; seeds the physics rig's Hall noise too
  // progress and the hooks are called as runMapping calls them; the snapshot replaces the hooks.
  MappingOptions mapping;
  // false: mapping.chain_fusion is replaced by the sensor's (pool for physics, else vote);
  // true (`--chain-fusion` given, or a sweep's grid): mapping.chain_fusion is used as it is.
  bool chain_fusion_given = false;
  // false: mapping.global_chains is replaced by the sensor's (kInPlaceGlobalChains for physics,
  // else as given); true (`--global-chains` given, or a sweep's grid): used as it is.
  bool global_chains_given = false;
  // --snapshot K [--snapshot-temperature I] (render/blackboard_snapshot.h): K < poses.size(),
  // 0 <= I < schedule_steps, I only with K.
  std::optional<int> snapshot_pose;
  std::optional<int> snapshot_temperature;
  std::mutex* world_mutex = nullptr;  // see Thread-safety above; null: one thread
  // --explore and its flags (exploration/exploration.h; docs/EXPLORATION.md). nullopt: the
  // scene's pose list visited in order by teleporting, the paper's §2.8 run (every figure and
  // golden file so far).
  std::optional<exploration::ExploreOptions> explore;
  // A live view of the run (`--serve`): observe after each pose is mapped, with the mapper
  // (runMapping's MapperObserver; its snapshot() draws nothing, so the map is the same with or
  // without it); moved after every control step of a driven --explore run. Not the physics
  // run's gaussian comparison. Empty: nothing called.
  MapperObserver observe;
  std::function<void(const Pose2& pose, double sim_t)> moved;
};

// The physics path's own measurements, and the gaussian run on the same scene beside them.
struct PhysicsSummary {
  ReportErrors errors;
  std::string models;  // the models file
  Evaluation gaussian;
  double gaussian_s = 0.0;
};

struct SimRun {
  Map map;
  Evaluation evaluation;
  NoiseRegime noise;          // the regime the blackboard assumed (after the sensor's rule)
  ModelParams model;          // eq. 12's parameters as run (withSensorNoise)
  // The mapping options as run: the sensor's rules applied (the physics sensor pools the chains
  // unless --chain-fusion was given), for report.json `sampler`.
  MappingOptions mapping;
  std::optional<PhysicsSummary> physics;
  std::optional<BlackboardSnapshot> snapshot;
  std::string warning;  // empty, or why an asked-for snapshot was not taken
  // report.json `exploration` (with the recall-against-travel curve): set when options.explore is.
  std::optional<exploration::ExplorationReport> exploration;
};

Result<SimRun> runSimulation(const SimScene& scene, const SimRunOptions& options);

}  // namespace crunch::sim
