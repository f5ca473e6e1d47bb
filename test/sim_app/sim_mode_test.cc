#include "sim_mode.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "crunch/mapping/map_io.h"

using namespace crunch;
namespace fs = std::filesystem;

namespace {
fs::path freshDir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("crunch_app_test_" + name);
  fs::remove_all(d);
  return d;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

struct RunResult {
  int code;
  std::string out, err;
};

RunResult run(app::SimOptions opt) {
  std::ostringstream out, err;
  const int code = app::runSim(opt, out, err);
  return {code, out.str(), err.str()};
}

nlohmann::json report(const fs::path& dir) { return nlohmann::json::parse(slurp(dir / "report.json")); }
}  // namespace

TEST_CASE("crunchhost --sim: default arena, realistic noise, finds the tables", "[app]") {
  // The issue's target: recall 1.0 at 0.15 m / 15 deg. Measured over seeds 1-10: recall 1.0 on
  // 7, 0.83 (one table missed) on 3; precision 0.67-1.0 (every phantom at a wall). Which seeds
  // miss depends on the random path, so the test bounds four seeds together rather than pinning
  // one: each finds at least five of six tables, and on average they find at least 95% of the
  // tables (three of the four find all six) with at least 70% precision (seeds 1-4: 0.75).
  constexpr double kMinRecallEach = 5.0 / 6.0 - 1e-9;
  constexpr double kMinRecallMean = 0.95;
  constexpr double kMinPrecisionMean = 0.70;
  double recall_sum = 0, precision_sum = 0;
  const std::vector<uint64_t> seeds = {1, 2, 3, 4};
  for (uint64_t seed : seeds) {
    const fs::path dir = freshDir("default_" + std::to_string(seed));
    app::SimOptions opt;
    opt.seed = seed;
    opt.out_dir = dir.string();
    const RunResult r = run(opt);
    INFO("seed " << seed << ": " << r.err);
    REQUIRE(r.code == 0);
    const auto rep = report(dir);
    CHECK(rep["accuracy"]["true_tables"] == 6);
    const double recall = rep["accuracy"]["recall"].get<double>();
    CHECK(recall >= kMinRecallEach);
    recall_sum += recall;
    precision_sum += rep["accuracy"]["precision"].get<double>();
    // Phantoms are expected at walls (walls are not modelled); never elsewhere so far.
    CHECK(rep["accuracy"]["phantoms_elsewhere"].get<int>() == 0);
    CHECK(rep["accuracy"]["mean_position_error_m"].get<double>() < 0.02);  // measured 4-7 mm
    CHECK(fs::file_size(dir / "map.png") > 10000);
    const auto map = parseMapJson(slurp(dir / "map.json"), "map.json");
    REQUIRE(map.ok());
    CHECK(map.value().per_pose.size() > 50);
    CHECK(map.value().stats.poses + map.value().stats.skipped_poses == 400);
  }
  CHECK(recall_sum / seeds.size() >= kMinRecallMean);
  CHECK(precision_sum / seeds.size() >= kMinPrecisionMean);
}

TEST_CASE("crunchhost --sim: every noise regime runs and writes all three files", "[app]") {
  for (const char* noise : {"ideal", "realistic", "noisy"}) {
    const fs::path dir = freshDir(std::string("noise_") + noise);
    app::SimOptions opt;
    opt.noise = noise;
    opt.out_dir = dir.string();
    const RunResult r = run(opt);
    REQUIRE(r.code == 0);
    CHECK(fs::exists(dir / "map.json"));
    CHECK(fs::exists(dir / "map.png"));
    CHECK(report(dir)["noise"]["name"] == noise);
  }
}

TEST_CASE("crunchhost --sim: same seed, same map", "[app]") {
  const fs::path a = freshDir("det_a"), b = freshDir("det_b");
  app::SimOptions opt;
  opt.seed = 9;
  opt.out_dir = a.string();
  REQUIRE(run(opt).code == 0);
  opt.out_dir = b.string();
  REQUIRE(run(opt).code == 0);
  auto ja = nlohmann::json::parse(slurp(a / "map.json"));
  auto jb = nlohmann::json::parse(slurp(b / "map.json"));
  ja["stats"].erase("wall_s");
  jb["stats"].erase("wall_s");
  CHECK(ja == jb);
}

TEST_CASE("crunchhost --sim: a bad scene is exit 2 naming file and field, nothing written",
          "[app]") {
  const fs::path dir = freshDir("bad_scene");
  app::SimOptions opt;
  opt.scene_path = std::string(CRUNCH_SOURCE_DIR) + "/test/scenes/bad_unknown_key.json";
  opt.out_dir = dir.string();
  const RunResult r = run(opt);
  CHECK(r.code == 2);
  CHECK(r.err.find("bad_unknown_key.json") != std::string::npos);
  CHECK_FALSE(fs::exists(dir));
}

TEST_CASE("crunchhost --sim: physics with a missing models file is exit 2 naming it",
          "[app]") {
  const fs::path dir = freshDir("physics_missing");
  app::SimOptions opt;
  opt.sensor_model = "physics";
  opt.models_path = (freshDir("no_models") / "models.json").string();
  opt.out_dir = dir.string();
  const RunResult r = run(opt);
  CHECK(r.code == 2);
  CHECK(r.err.find(opt.models_path) != std::string::npos);
  CHECK(r.err.find("crunchhost train") != std::string::npos);
  CHECK_FALSE(fs::exists(dir));
}

// The whole physics chain: ODE whiskers -> Hall model -> firmware on virtual boards -> bridge
// decoder -> signal pipeline with the shipped models -> shapelets -> blackboard -> map.
TEST_CASE("crunchhost --sim --sensor-model physics: end to end on one table", "[app]") {
  const fs::path dir = freshDir("physics_one_table");
  app::SimOptions opt;
  opt.sensor_model = "physics";
  opt.scene_path = std::string(CRUNCH_SOURCE_DIR) + "/test/scenes/physics_one_table.json";
  opt.out_dir = dir.string();
  const RunResult r = run(opt);
  INFO(r.err);
  REQUIRE(r.code == 0);
  const nlohmann::json rep = report(dir);
  REQUIRE(rep.contains("physics"));
  const auto& ph = rep["physics"];
  // Contacts were made, classified and scored against the simulator's truth.
  CHECK(ph["whisks"].get<int>() == rep["counts"]["poses"].get<int>() -
                                       rep["counts"]["skipped_poses"].get<int>());
  CHECK(ph["reports_scored"].get<int>() >= 10);
  CHECK(std::isfinite(ph["sigma_r_m"].get<double>()));
  CHECK(std::isfinite(ph["sigma_phi_rad"].get<double>()));
  // Reports are where the whiskers are: radial errors of the order of the whisker's reach, not
  // of the arena (the bound is loose on purpose; docs/TRAINING.md has the measured sigma).
  CHECK(ph["sigma_r_m"].get<double>() < 0.05);
  CHECK(rep["counts"]["shapelets"].get<int>() > 0);
  // The model's size (docs/RESULTS.md): never more live legs than shapelets to explain.
  CHECK(rep["counts"]["peak_live_legs"].get<int>() <= rep["counts"]["shapelets"].get<int>());
  CHECK(rep["counts"]["peak_live_tables"].get<int>() <= rep["counts"]["peak_live_legs"].get<int>());
  CHECK(rep["physics"]["gaussian_same_scene"]["accuracy"].contains("recall"));
  CHECK(fs::exists(dir / "map.json"));
  CHECK(fs::exists(dir / "map.png"));
}

TEST_CASE("crunchhost --sim: an empty arena gives an empty, valid map", "[app]") {
  const fs::path dir = freshDir("empty");
  fs::create_directories(dir);
  std::ofstream(dir / "scene.json") << R"({"arena": {"width": 3.0, "depth": 3.0}})";
  app::SimOptions opt;
  opt.scene_path = (dir / "scene.json").string();
  opt.out_dir = (dir / "out").string();
  const RunResult r = run(opt);
  REQUIRE(r.code == 0);
  const auto map = parseMapJson(slurp(dir / "out/map.json"), "map.json");
  REQUIRE(map.ok());
  // Only wall shapelets exist; any table is a wall phantom, which the report classifies.
  const auto rep = report(dir / "out");
  CHECK(rep["accuracy"]["phantoms_elsewhere"] == 0);
  CHECK(rep["accuracy"]["recall"] == 1.0);
}

TEST_CASE("crunchhost --sim: no contacts at all gives an empty map", "[app]") {
  const fs::path dir = freshDir("nocontact");
  fs::create_directories(dir);
  std::ofstream(dir / "scene.json")
      << R"({"arena": {"width": 4.0, "depth": 4.0}, "poses": {"list": [[2.0, 2.0, 0.0], [2.0, 2.0, 1.5]]}})";
  app::SimOptions opt;
  opt.scene_path = (dir / "scene.json").string();
  opt.out_dir = (dir / "out").string();
  REQUIRE(run(opt).code == 0);
  const auto map = parseMapJson(slurp(dir / "out/map.json"), "map.json");
  REQUIRE(map.ok());
  CHECK(map.value().tables.empty());
  CHECK(map.value().per_pose.empty());
  CHECK(map.value().stats.shapelets == 0);
}
