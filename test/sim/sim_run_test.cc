// One simulated mapping run (crunch_sim/sim_run.h) and its report (sim_report.h): settings
// refused with their names before anything runs, the same map with and without the sweep's
// world lock, and the physics path's refusal of a missing models file.
#include "crunch_sim/sim_run.h"

#include <catch2/catch.hpp>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>

#include "crunch/mapping/map_io.h"
#include "crunch_sim/sim_report.h"

using namespace crunch;
using namespace crunch::sim;

namespace {
const std::string kTwoTables = std::string(CRUNCH_SOURCE_DIR) + "/test/scenes/two_tables.json";

SimRunOptions fast() {
  SimRunOptions o;
  o.mapping.sampler.schedule_steps = 4;
  o.mapping.global_sweeps = 0;
  return o;
}

std::string tablesOf(const Map& map) {
  const std::string j = mapToJson(map);
  return j.substr(0, j.find("\"stats\""));  // everything but the measured wall time
}
}  // namespace

TEST_CASE("Sim run: sensor names, and the scene file or the default arena", "[sim_run]") {
  CHECK(sensorKindByName("physics").value() == SensorKind::kPhysics);
  CHECK(std::string(sensorKindName(sensorKindByName("ideal").value())) == "ideal");
  CHECK_THAT(sensorKindByName("sonar").error().message,
             Catch::Contains("--sensor-model") && Catch::Contains("sonar"));
  CHECK(loadSimScene(std::nullopt).value().tables.size() == defaultArena().tables.size());
  CHECK_THAT(loadSimScene(std::string("/nonexistent.json")).error().message,
             Catch::Contains("/nonexistent.json"));
}

TEST_CASE("Sim run: bad settings are refused with their names before mapping", "[sim_run]") {
  const SimScene scene = SimScene::build(loadSimScene(kTwoTables).value());
  SimRunOptions o = fast();
  o.mapping.working_memory = 0;
  CHECK_THAT(runSimulation(scene, o).error().message,
             Catch::Contains("mapping options") && Catch::Contains("working_memory"));
  o = fast();
  o.noise.sigma_r = -1.0;
  CHECK_THAT(runSimulation(scene, o).error().message, Catch::Contains("noise: "));
  o = fast();
  o.snapshot_pose = static_cast<int>(scene.poses.size());
  CHECK_THAT(runSimulation(scene, o).error().message, Catch::Contains("no such pose"));
  o = fast();
  o.snapshot_temperature = 0;  // without --snapshot
  CHECK_THAT(runSimulation(scene, o).error().message, Catch::Contains("--snapshot-temperature 0"));
  o = fast();
  o.sensor = SensorKind::kPhysics;
  o.models_path = "/nonexistent/models.json";
  CHECK_THAT(runSimulation(scene, o).error().message,
             Catch::Contains("--sensor-model physics") && Catch::Contains("crunchhost train"));
}

TEST_CASE("Sim run: deterministic by seed, with or without the world lock", "[sim_run]") {
  const SimScene scene = SimScene::build(loadSimScene(kTwoTables).value());
  SimRunOptions o = fast();
  o.seed = 3;
  const auto a = runSimulation(scene, o);
  REQUIRE(a);
  std::mutex world;
  o.world_mutex = &world;
  const auto b = runSimulation(scene, o);
  REQUIRE(b);
  CHECK(tablesOf(a.value().map) == tablesOf(b.value().map));
  CHECK(a.value().evaluation.true_tables == 2);
  CHECK(a.value().noise.name == "realistic");
  CHECK(a.value().model.sigma_r_shapelet >= NoiseRegime::realistic().sigma_r);
  o.sensor = SensorKind::kIdeal;
  CHECK(runSimulation(scene, o).value().noise.name == "ideal");
}

TEST_CASE("Sim report: report.json names the run and holds its accuracy", "[sim_run]") {
  const SimScene scene = SimScene::build(loadSimScene(kTwoTables).value());
  const SimRunOptions o = fast();
  const SimRun run = runSimulation(scene, o).value();
  const auto j = nlohmann::json::parse(simReportJson(scene.scene, run, o, 1.5));
  CHECK(j["schema"] == "crunch.report/1");
  CHECK(j["sensor_model"] == "gaussian");
  CHECK(j["accuracy"]["true_tables"] == 2);
  CHECK(j["timings_s"]["total"] == 1.5);
  CHECK(j["sampler"]["schedule_steps"] == 4);
  CHECK_FALSE(j.contains("physics"));
}
