// Scenes where the methods fail (issue 6): each scene of test/scenes/ below is mapped exactly as
// `crunchhost --sim --model paper --scene test/scenes/NAME.json --seed 1` maps it (the paper's
// model, the default when the bounds were measured; app::runSim: the ray sensor
// with the gaussian noise model, realistic noise, the default sampler and global inference), and
// its accuracy (report.json), model size (map.json stats.peak_live_*) and run time are bounded.
//
// How the bounds were set: every number was measured first, seed 1 (the one tested) and seeds 2-3
// beside it, in a Release build on the project's 2-core machine (docs/RESULTS.md, "Scenes where
// the methods fail", has the table). A run is deterministic for its seed, but another compiler or
// build type may round differently and send the sampler down another path, which is like another
// seed; so each bound covers seeds 1-3 and leaves a stated margin: recall one real table below
// seed 1 (one table is the smallest change the metric can make) and never above the worst of
// seeds 1-3, precision and phantom counts a comparable step, position error about 1.5 times the
// worst of seeds 1-3, peak live tables 1.5 times the largest. The bounds pin today's behaviour, failures included: a scene whose
// recall is low here is documented as a failure, not hidden, and a change that makes it worse
// fails the test.
//
// Model size: a live leg survives the pruning after each temperature only near a shapelet and a
// live table only with a child leg near one, so peak_live_legs <= shapelets and
// peak_live_tables <= peak_live_legs bound memory by the evidence (measured: legs are 0.4-0.7 of
// the shapelets); each scene also bounds peak_live_tables against its real tables. Wall time: a hang guard, about ten
// times the Release measurement (sanitizer builds run several times slower).
#include "sim_mode.h"

#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "crunch/mapping/map_io.h"

using namespace crunch;
namespace fs = std::filesystem;

namespace {

struct Bounds {
  double min_recall = 0.0;
  double min_precision = 0.0;
  int max_wall_phantoms = 0;
  int max_other_phantoms = 0;
  double max_position_error = 0.0;  // metres, mean over matched tables
  int max_peak_tables = 0;          // peak_live_tables
  double max_seconds = 0.0;         // whole runSim, hang guard
};

struct Outcome {
  nlohmann::json report;
  Map map;
  double seconds = 0.0;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// `crunchhost --sim --model paper --scene test/scenes/<name>.json --seed 1 --out <tmp>`, or
// another model and seed.
Outcome runScene(const std::string& name, ObjectModel model = ObjectModel::kPaper,
                 uint64_t seed = 1, double side_prior_draws = 0.0) {
  const fs::path dir = fs::temp_directory_path() / ("crunch_failure_scenes_" + name);
  fs::remove_all(dir);
  app::SimOptions opt;
  opt.scene_path = std::string(CRUNCH_SOURCE_DIR) + "/test/scenes/" + name + ".json";
  opt.seed = seed;
  opt.mapping.model.objects = model;
  opt.mapping.sampler.side_prior_draws = side_prior_draws;
  opt.out_dir = dir.string();
  std::ostringstream out, err;
  const auto t0 = std::chrono::steady_clock::now();
  const int code = app::runSim(opt, out, err);
  Outcome o;
  o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  INFO(err.str());
  REQUIRE(code == 0);
  o.report = nlohmann::json::parse(slurp(dir / "report.json"));
  auto map = parseMapJson(slurp(dir / "map.json"), (dir / "map.json").string());
  INFO((map.ok() ? std::string() : map.error().message));
  REQUIRE(map.ok());
  o.map = std::move(map).value();
  fs::remove_all(dir);
  return o;
}

// Runs the scene and checks everything every scene must satisfy, and its own bounds.
Outcome checkScene(const std::string& name, const Bounds& b) {
  Outcome o = runScene(name);
  const nlohmann::json& a = o.report.at("accuracy");
  const nlohmann::json& c = o.report.at("counts");
  const MapStats& s = o.map.stats;
  const int shapelets = c.at("shapelets").get<int>();
  INFO(name << ": " << a.dump() << " " << c.dump() << " peak_live_tables " << s.peak_live_tables
            << " peak_live_legs " << s.peak_live_legs << " in " << o.seconds << " s");

  // Finite outputs.
  for (const char* key : {"precision", "recall", "f1", "mean_position_error_m",
                          "mean_angle_error_rad", "per_pose_match_fraction"}) {
    INFO(key);
    CHECK(std::isfinite(a.at(key).get<double>()));
  }
  for (const MapTable& t : o.map.tables)
    CHECK((std::isfinite(t.pose.x) && std::isfinite(t.pose.y) && std::isfinite(t.pose.theta) &&
           std::isfinite(t.score)));
  CHECK(std::isfinite(s.wall_s));
  CHECK(s.shapelets == shapelets);
  CHECK(static_cast<int>(o.map.tables.size()) == a.at("fused_tables").get<int>());

  // Accuracy against the scene's own bounds.
  CHECK(a.at("recall").get<double>() >= b.min_recall - 1e-9);
  CHECK(a.at("precision").get<double>() >= b.min_precision - 1e-9);
  CHECK(a.at("phantoms_near_walls").get<int>() <= b.max_wall_phantoms);
  CHECK(a.at("phantoms_elsewhere").get<int>() <= b.max_other_phantoms);
  CHECK(a.at("mean_position_error_m").get<double>() <= b.max_position_error);

  // Model size: bounded by the evidence and by the scene.
  CHECK(s.peak_live_legs <= shapelets);
  CHECK(s.peak_live_tables <= s.peak_live_legs);
  CHECK(s.peak_live_tables <= b.max_peak_tables);

  CHECK(o.seconds < b.max_seconds);
  return o;
}

}  // namespace

TEST_CASE("Failure scenes: empty arena maps only wall phantoms", "[app][scenes]") {
  // Measured (seed 1): 80 shapelets, all on the four boundary walls; 3 fused tables, every one
  // within 0.3 m of a wall; peak 8 live tables / 53 legs (seeds 2, 3: 0 and 2 fused tables, all
  // at walls; peak 9 / 61 and 10 / 55). There is no WALL concept (paper §4's
  // "perceptual relativism"), so a table whose legs stand on wall shapelets explains them better
  // than the null prior c_S; negative evidence removes those whose other legs would stand in
  // swept free space, and the ones left stand flush against a wall, where no whisker can sweep.
  // Bound: nothing away from the walls, at most 6 wall phantoms (twice seed 1's), peak live
  // tables <= 15 (1.5 x 10).
  const Outcome o = checkScene("empty_arena", {.min_recall = 1.0,
                             .min_precision = 0.0,
                             .max_wall_phantoms = 6,
                             .max_other_phantoms = 0,
                             .max_position_error = 0.0,
                             .max_peak_tables = 15,
                             .max_seconds = 10.0});
  const nlohmann::json& a = o.report.at("accuracy");
  INFO(a.dump());
  CHECK(a.at("true_tables").get<int>() == 0);
  CHECK(a.at("phantoms_elsewhere").get<int>() == 0);
  CHECK(a.at("phantoms_near_walls").get<int>() == static_cast<int>(o.map.tables.size()));
  CHECK(o.map.tables.size() <= 6);
}

TEST_CASE("Failure scenes: tables touching each other", "[app][scenes]") {
  // Two pairs of standard tables, one touching along the long sides, one end to end: where two
  // tables touch, two legs stand side by side as one 0.10 x 0.05 m block, and a table straddling
  // the pair explains the block's faces as well as either real table. Measured (seed 1): recall
  // 0.75 (3 of 4), precision 0.6, 2 wall phantoms, 6.0 mm mean error, peak 11 tables / 75 legs,
  // 0.87 s; seeds 2, 3: recall 0.5, 0.5, precision 0.5, 1.0, error 3.2, 5.4 mm, peak 13, 12.
  // Bounds: recall >= 0.5 (one table fewer; seeds 2-3's), precision >= 0.4, <= 4 wall phantoms,
  // <= 1 elsewhere, error <= 10 mm, peak tables <= 20. Since the robot's disc at every pose is
  // free space (run_mapping.h) seeds 1-3 give precision 0.33, 0.33, 1.0 (4, 4, 0 wall
  // phantoms; recall 0.5 each, error 4.2-6.3 mm, peak 13, 13, 10): the paper's model, without
  // walls, moves its phantoms to other wall contacts (over seeds 1-5 its wall phantoms went
  // from 9 to 13, docs/RESULTS.md "The body at every pose"), so precision >= 0.3.
  checkScene("adjacent_tables", {.min_recall = 0.5,
                                 .min_precision = 0.3,
                                 .max_wall_phantoms = 4,
                                 .max_other_phantoms = 1,
                                 .max_position_error = 0.010,
                                 .max_peak_tables = 20,
                                 .max_seconds = 10.0});
}

TEST_CASE("Failure scenes: tables against a wall", "[app][scenes]") {
  // Three tables flush against the boundary walls (one in a corner) and one free: the wall side
  // of a flush table can never be touched, so its wall legs are sensed on one face at most, and
  // they stand among wall shapelets. Measured (seed 1): recall 0.75 (3 of 4), precision 0.75,
  // 1 wall phantom, 1.4 mm error, peak 12 tables / 74 legs, 0.80 s; seeds 2, 3: recall 0.75,
  // 1.0, precision 1.0, 0.8, error 2.7, 4.4 mm, peak 14, 11. Bounds: recall >= 0.5, precision
  // >= 0.5, <= 3 wall phantoms, <= 1 elsewhere, error <= 7 mm, peak tables <= 21.
  checkScene("table_at_wall", {.min_recall = 0.5,
                               .min_precision = 0.5,
                               .max_wall_phantoms = 3,
                               .max_other_phantoms = 1,
                               .max_position_error = 0.007,
                               .max_peak_tables = 21,
                               .max_seconds = 10.0});
}

TEST_CASE("Failure scenes: interior walls", "[app][scenes]") {
  // Four rooms (walls with doors) and a free-standing wall segment, one table per room: the
  // interior walls double the wall shapelets (331 against ~150 in an open arena), and every one
  // is a place for a phantom. Measured (seed 1): recall 1.0, precision 0.5 (4 wall phantoms),
  // 3.2 mm error, peak 13 tables / 133 legs, 1.9 s; seeds 2, 3: recall 1.0, 1.0, precision
  // 1.0, 0.67 (0 and 2 wall phantoms), error 2.6, 4.2 mm, peak 13, 14. Bounds: recall >= 0.75,
  // precision >= 0.35, <= 7 wall phantoms, <= 1 elsewhere, error <= 7 mm, peak tables <= 21.
  checkScene("interior_walls", {.min_recall = 0.75,
                                .min_precision = 0.35,
                                .max_wall_phantoms = 7,
                                .max_other_phantoms = 1,
                                .max_position_error = 0.007,
                                .max_peak_tables = 21,
                                .max_seconds = 20.0});
}

TEST_CASE("Failure scenes: a sparse pose grid", "[app][scenes]") {
  // The default arena's six tables seen from a 5 x 5 x 4 grid (0.85 m apart) instead of
  // 10 x 10 x 4 (0.38 m): 63 shapelets instead of ~150, and most tables are touched on one or
  // two legs. Measured (seed 1): recall 0.33 (2 of 6), precision 1.0, no phantoms, 5.1 mm
  // error, peak 5 tables / 43 legs, 0.26 s; seeds 2, 3: recall 0.17, 0.33, precision 1.0,
  // 0.67 (one wall phantom), error 5.7, 2.9 mm, peak 8, 7. Bounds: recall >= 1/6 (one table
  // fewer; seed 2's), precision >= 0.5, <= 2 wall phantoms, <= 1 elsewhere, error <= 10 mm,
  // peak tables <= 12.
  checkScene("sparse_poses", {.min_recall = 1.0 / 6.0,
                              .min_precision = 0.5,
                              .max_wall_phantoms = 2,
                              .max_other_phantoms = 1,
                              .max_position_error = 0.010,
                              .max_peak_tables = 12,
                              .max_seconds = 10.0});
}

TEST_CASE("Failure scenes: a dense room of 12 tables", "[app][scenes]") {
  // Twelve tables in a 5 x 5 m room, 0.2-0.4 m apart: 176 of the 576 grid poses collide with a
  // table and are skipped, and the robot cannot pass between most tables, so their inner legs
  // are never touched. Measured (seed 1): recall 0.42 (5 of 12), precision 1.0, no phantoms,
  // 3.0 mm error, peak 13 tables / 89 legs, 0.85 s; seeds 2, 3: recall 0.33, 0.42, precision
  // 0.8, 0.83 (one wall phantom each), error 10.4, 14.0 mm, peak 17, 13. Bounds: recall >= 4/12
  // (one table fewer; seed 2's), precision >= 0.6, <= 2 wall phantoms, <= 1 elsewhere, error
  // <= 20 mm, peak tables <= 26.
  checkScene("dense_room", {.min_recall = 4.0 / 12.0,
                            .min_precision = 0.6,
                            .max_wall_phantoms = 2,
                            .max_other_phantoms = 1,
                            .max_position_error = 0.020,
                            .max_peak_tables = 26,
                            .max_seconds = 10.0});
}

TEST_CASE("Failure scenes: a large floor, 20 x 20 m with 100 tables", "[app][scenes]") {
  // 100 standard tables on a 2 m lattice (jittered, random angles), seen from a 52 x 52 x 4
  // grid: the default arena's pose spacing (0.38 m), 10,816 candidate poses of which 9,468 are
  // reachable. Measured (seed 1, Release, 2 cores): recall 0.96, precision 0.92 (8 wall
  // phantoms), 4.4 mm error, 1,586 shapelets, peak 129 tables / 696 legs, 17.4 s; seed 2: recall
  // 0.93, precision 0.93 (7 wall phantoms), 4.0 mm, peak 128 / 704, 16.3 s. (A 40 x 40 x 4
  // grid, 0.5 m apart, ran in 9.6 s but found only half the tables: see the sparse-grid scene.)
  // Bounds: recall >= 0.9 (six tables fewer than seed 1; 0.93 on seed 2), precision >= 0.85,
  // <= 14 wall phantoms, <= 3 elsewhere, error <= 7 mm, peak tables <= 1.5 x 129 = 194 (about 2 per real table), and 150 s: a hang guard
  // for a run that takes ~17 s in Release and several times that under the sanitizers.
  checkScene("large_floor", {.min_recall = 0.9,
                             .min_precision = 0.85,
                             .max_wall_phantoms = 14,
                             .max_other_phantoms = 3,
                             .max_position_error = 0.007,
                             .max_peak_tables = 194,
                             .max_seconds = 150.0});
}

TEST_CASE("Failure scenes: thin-legged chairs, rooms model", "[app][scenes]") {
  // A 0.35 m stool on 0.025 m legs and a 0.42 x 0.40 m chair on 0.022 m legs, too low for the
  // robot to drive under: every leg is touched from outside only, so its contacts fix its outer
  // faces and nothing fixes its side, and a leg born too wide (its side drawn from the prior)
  // cannot join a table of thin legs. Mapped with `--model rooms` (the paper's model has one
  // size), with half the leg-side steps drawn from the prior (SamplerOptions::side_prior_draws
  // 0.5; docs/BLACKBOARD.md "A leg's side, seen from outside"). Measured (seeds 1-12, since walls
  // end at walls, 2026-12-02): recall 0.5, 0.5, 0, 0, 0.5, 0.5, 0.5, 0, 0.5, 1, 1, 1 (mean 0.50;
  // before, 0.58: the arena's joined corners change every chain's draws, and which seeds find a
  // chair moved), precision 1.0, no phantoms; with local side steps only (the default) mean 0.10
  // over seeds 1-5 (tools/scene-table.py). Bounds over seeds 1-3: at least 1 of the 6 objects
  // (one fewer than measured), no phantom on any seed.
  int found = 0;
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    const Outcome o = runScene("thin_legs", ObjectModel::kRooms, seed, 0.5);
    const nlohmann::json& a = o.report.at("accuracy");
    INFO("seed " << seed << ": " << a.dump());
    CHECK(a.at("true_tables").get<int>() == 2);
    CHECK(a.at("phantoms_near_walls").get<int>() == 0);
    CHECK(a.at("phantoms_elsewhere").get<int>() == 0);
    found += static_cast<int>(std::lround(a.at("recall").get<double>() * 2));
  }
  CHECK(found >= 1);
}
