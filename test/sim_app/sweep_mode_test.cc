// crunchhost sweep / sweep-merge (sim/app/sweep_mode.h, host/app/sweep_merge.h): determinism, shards and merge, threads,
// CSV = JSON, bad input. The grid is tiny: two_tables.json (24 candidate poses) at schedule 4 and
// 8 x seeds 1 and 2 = 4 runs.
#include "sweep_mode.h"

#include "crunch/mapping/sweep.h"
#include "sim_mode.h"
#include "sweep_merge.h"

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "support/temp_dir.h"

using namespace crunch;
using Json = nlohmann::ordered_json;

namespace {

const std::string kScene = std::string(CRUNCH_SOURCE_DIR) + "/test/scenes/two_tables.json";

std::string slurp(const std::string& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

app::SweepOptions tinyGrid(const std::string& out_dir) {
  app::SweepOptions o;
  o.grid.scenes = {kScene};
  o.grid.noise = "realistic";
  o.grid.schedule_steps = "4,8";
  o.grid.seeds = "2";
  o.jobs = "1";
  o.out_dir = out_dir;
  return o;
}

struct Run {
  int code;
  std::string out, err;
};

Run sweep(const app::SweepOptions& o) {
  std::ostringstream out, err;
  const int code = app::runSweep(o, out, err);
  return {code, out.str(), err.str()};
}

Run merge(const std::vector<std::string>& dirs, const std::string& out_dir) {
  std::ostringstream out, err;
  const int code = app::runSweepMerge(dirs, out_dir, out, err);
  return {code, out.str(), err.str()};
}

Json rows(const std::string& dir) { return Json::parse(slurp(dir + "/sweep.json")); }

// A row without what may differ between runs of the same point: timing, memory, shard.
Json stable(Json row) {
  row.erase("wall_s");
  row.erase("process_peak_rss_kib");
  row.erase("shard");
  return row;
}

Json stableRows(const Json& arr) {
  Json out = Json::array();
  for (const Json& r : arr) out.push_back(stable(r));
  return out;
}

std::vector<std::vector<std::string>> csvCells(const std::string& text) {
  std::vector<std::vector<std::string>> table;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream ls(line);
    while (std::getline(ls, cell, ',')) cells.push_back(cell);  // no quoted fields in this grid
    table.push_back(cells);
  }
  return table;
}

}  // namespace

TEST_CASE("sweep: one row per grid point in grid order, deterministic per seed", "[app][sweep]") {
  TempDir a, b;
  const Run ra = sweep(tinyGrid(a.path().string()));
  REQUIRE(ra.code == 0);
  const Run rb = sweep(tinyGrid(b.path().string()));
  REQUIRE(rb.code == 0);
  const Json ja = rows(a.path().string());
  const Json jb = rows(b.path().string());
  REQUIRE(ja.size() == 4);
  // Grid order: schedule_steps, then seed fastest.
  const int steps[] = {4, 4, 8, 8};
  const int seeds[] = {1, 2, 1, 2};
  for (size_t i = 0; i < 4; ++i) {
    CHECK(ja[i]["grid_index"] == i);
    CHECK(ja[i]["grid_size"] == 4);
    CHECK(ja[i]["shard"] == "0/1");
    CHECK(ja[i]["schedule_steps"] == steps[i]);
    CHECK(ja[i]["seed"] == seeds[i]);
    CHECK(ja[i]["noise"] == "realistic");
    CHECK(ja[i]["sigma_r"] == 0.005);
    CHECK(ja[i]["true_tables"] == 2);
    CHECK(ja[i]["poses"].get<int>() > 0);
    CHECK(ja[i]["proposals"].get<long long>() > 0);
    CHECK(ja[i]["peak_live_legs"].get<int>() > 0);
    CHECK(ja[i]["process_peak_rss_kib"].get<long>() > 0);
    CHECK(ja[i]["grid"] == ja[0]["grid"]);
  }
  // A longer schedule makes more proposals for the same seed (the sensed data is the same).
  CHECK(ja[2]["proposals"].get<long long>() > ja[0]["proposals"].get<long long>());
  CHECK(ja[0]["shapelets"] == ja[2]["shapelets"]);
  CHECK(stableRows(ja) == stableRows(jb));
  // Different seeds sense differently.
  CHECK(stable(ja[0]) != stable(ja[1]));
}

TEST_CASE("sweep: a row measures what crunchhost --sim reports for the same point", "[app][sweep]") {
  // The default arena (six tables, where the map is not empty) at a short schedule. Realistic
  // noise: at noisy with 4 temperatures the fused map is empty on seeds 2 and 3 since the global
  // chains have their own streams (issue 15), and an empty map would make the comparison vacuous.
  TempDir sw, sim;
  app::SweepOptions o;
  o.grid.scenes = {"default"};
  o.grid.noise = "realistic";
  o.grid.schedule_steps = "4";
  o.grid.seed_list = "2";
  o.out_dir = sw.path().string();
  REQUIRE(sweep(o).code == 0);
  const Json row = rows(sw.path().string()).at(0);
  app::SimOptions so;
  so.noise = "realistic";
  so.seed = 2;
  so.mapping.sampler.schedule_steps = 4;
  so.out_dir = sim.path().string();
  std::ostringstream out, err;
  REQUIRE(app::runSim(so, out, err) == 0);
  const Json report = Json::parse(slurp(sim.file("report.json")));
  CHECK(row["scene"] == "default");
  CHECK(row["true_tables"] == 6);
  CHECK(row["sigma_r"] == report["noise"]["sigma_r"]);
  CHECK(row["sigma_phi"] == report["noise"]["sigma_phi"]);
  CHECK(row["poses"] == report["counts"]["poses"]);
  CHECK(row["shapelets"] == report["counts"]["shapelets"]);
  CHECK(row["proposals"] == report["counts"]["proposals"]);
  for (const char* k : {"fused_tables", "matched", "precision", "recall", "f1"})
    CHECK(row[k] == report["accuracy"][k]);
  CHECK(row["mean_position_error_m"] == report["accuracy"]["mean_position_error_m"]);
  CHECK(row["per_pose_match_fraction"] == report["accuracy"]["per_pose_match_fraction"]);
  CHECK(row["phantoms_near_walls"] == report["accuracy"]["phantoms_near_walls"]);
  CHECK(row["matched"].get<int>() > 0);
}

TEST_CASE("sweep: --jobs 2 gives the serial rows", "[app][sweep]") {
  TempDir serial, parallel;
  REQUIRE(sweep(tinyGrid(serial.path().string())).code == 0);
  app::SweepOptions o = tinyGrid(parallel.path().string());
  o.jobs = "2";
  o.json_progress = true;
  const Run r = sweep(o);
  REQUIRE(r.code == 0);
  // --json: one progress line per finished run (done 1..4 whatever finished first), then done.
  std::istringstream lines(r.out);
  std::string line;
  std::vector<Json> events;
  while (std::getline(lines, line)) events.push_back(Json::parse(line));
  REQUIRE(events.size() == 5);
  for (size_t i = 0; i < 4; ++i) {
    CHECK(events[i]["event"] == "progress");
    CHECK(events[i]["done"] == i + 1);
    CHECK(events[i]["total"] == 4);
    CHECK(events[i].contains("eta_s"));
  }
  CHECK(events[4]["event"] == "done");
  CHECK(events[4]["runs"] == 4);
  CHECK(r.err.empty());
  CHECK(stableRows(rows(serial.path().string())) == stableRows(rows(parallel.path().string())));
}

TEST_CASE("sweep: CSV and JSON hold the same rows", "[app][sweep]") {
  TempDir d;
  REQUIRE(sweep(tinyGrid(d.path().string())).code == 0);
  const Json j = rows(d.path().string());
  const auto table = csvCells(slurp(d.file("sweep.csv")));
  REQUIRE(table.size() == j.size() + 1);
  REQUIRE(table[0] == kSweepColumns);
  for (size_t r = 0; r < j.size(); ++r) {
    REQUIRE(table[r + 1].size() == kSweepColumns.size());
    for (size_t c = 0; c < kSweepColumns.size(); ++c) {
      const Json& v = j[r][kSweepColumns[c]];
      const std::string& cell = table[r + 1][c];
      if (v.is_string()) CHECK(cell == v.get<std::string>());
      else CHECK(Json::parse(cell) == v);
    }
  }
}

TEST_CASE("sweep: shards 0/2 and 1/2 merged are the unsharded sweep", "[app][sweep]") {
  TempDir all, s0, s1, merged;
  REQUIRE(sweep(tinyGrid(all.path().string())).code == 0);
  app::SweepOptions o0 = tinyGrid(s0.path().string());
  o0.shard = "0/2";
  app::SweepOptions o1 = tinyGrid(s1.path().string());
  o1.shard = "1/2";
  REQUIRE(sweep(o0).code == 0);
  REQUIRE(sweep(o1).code == 0);
  const Json j0 = rows(s0.path().string());
  REQUIRE(j0.size() == 2);
  CHECK(j0[0]["grid_index"] == 0);
  CHECK(j0[1]["grid_index"] == 2);
  CHECK(j0[0]["shard"] == "0/2");
  // Order of the shard directories does not matter.
  const Run m = merge({s1.path().string(), s0.path().string()}, merged.path().string());
  REQUIRE(m.code == 0);
  CHECK(stableRows(rows(merged.path().string())) == stableRows(rows(all.path().string())));
  CHECK(rows(merged.path().string())[1]["shard"] == "1/2");
}

TEST_CASE("sweep-merge: refuses other grids, duplicates and missing points, writes nothing",
          "[app][sweep]") {
  TempDir s0, s1, other, out;
  app::SweepOptions o0 = tinyGrid(s0.path().string());
  o0.shard = "0/2";
  app::SweepOptions o1 = tinyGrid(other.path().string());
  o1.shard = "1/2";
  o1.grid.seeds = "";
  o1.grid.seed_list = "1,3";  // another grid of the same size
  REQUIRE(sweep(o0).code == 0);
  REQUIRE(sweep(o1).code == 0);
  CHECK(rows(s0.path().string())[0]["grid"] != rows(other.path().string())[0]["grid"]);
  const std::string out_dir = out.file("merged");

  Run m = merge({s0.path().string(), other.path().string()}, out_dir);
  CHECK(m.code == 2);
  CHECK(m.err.find("another grid") != std::string::npos);
  m = merge({s0.path().string()}, out_dir);
  CHECK(m.code == 2);
  CHECK(m.err.find("2 of 4 grid points missing (1, 3)") != std::string::npos);
  m = merge({s0.path().string(), s0.path().string()}, out_dir);
  CHECK(m.code == 2);
  CHECK(m.err.find("appears twice") != std::string::npos);
  m = merge({s1.path().string()}, out_dir);  // empty directory: no sweep.json
  CHECK(m.code == 2);
  CHECK(m.err.find("sweep.json") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(out_dir));
}

TEST_CASE("sweep: bad options exit 2 naming the option and write nothing", "[app][sweep]") {
  TempDir d;
  const std::string out_dir = d.file("out");
  using Field = std::string* (*)(app::SweepOptions&);
  struct Case {
    std::string option;  // what the message must name
    Field field;
    std::string value;
  };
  const std::string bad_key = std::string(CRUNCH_SOURCE_DIR) + "/test/scenes/bad_unknown_key.json";
  const std::vector<Case> cases = {
      {"--noise", +[](app::SweepOptions& o) { return &o.grid.noise; }, "realistic,loud"},
      {"--noise-scale", +[](app::SweepOptions& o) { return &o.grid.noise_scale; }, "1,x"},
      {"--noise-scale", +[](app::SweepOptions& o) { return &o.grid.noise_scale; }, "-1"},
      {"--schedule-steps", +[](app::SweepOptions& o) { return &o.grid.schedule_steps; }, "4,,8"},
      {"--schedule-steps", +[](app::SweepOptions& o) { return &o.grid.schedule_steps; }, "0"},
      {"--sweeps", +[](app::SweepOptions& o) { return &o.grid.sweeps; }, "1,1"},
      {"--working-memory", +[](app::SweepOptions& o) { return &o.grid.working_memory; }, "7,"},
      {"--seeds", +[](app::SweepOptions& o) { return &o.grid.seeds; }, "two"},
      {"--seeds and --seed-list", +[](app::SweepOptions& o) { return &o.grid.seed_list; }, "1"},
      {"--jobs", +[](app::SweepOptions& o) { return &o.jobs; }, "-1"},
      {"--shard", +[](app::SweepOptions& o) { return &o.shard; }, "2/2"},
      {"--shard", +[](app::SweepOptions& o) { return &o.shard; }, "1"},
      {"--scene", nullptr, "/nonexistent/scene.json"},
      {"--scene", nullptr, bad_key},
      {"--seed-list", nullptr, "1,-2"},
  };
  for (const Case& c : cases) {
    app::SweepOptions o = tinyGrid(out_dir);
    if (c.field) {
      *c.field(o) = c.value;
    } else if (c.option == "--scene") {
      o.grid.scenes = {c.value};
    } else {
      o.grid.seeds.clear();
      o.grid.seed_list = c.value;
    }
    const Run r = sweep(o);
    INFO(c.option << ": " << r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find(c.option + ":") != std::string::npos);
    CHECK_FALSE(std::filesystem::exists(out_dir));
  }
}

TEST_CASE("sweep --explore: an unknown policy or a bad budget exits 2 naming the option, writes "
          "nothing", "[app][sweep][explore]") {
  TempDir d;
  const std::string out_dir = d.file("out");
  struct Case {
    std::string option, explore, travel, whisks;
  };
  // Unknown names and negative budgets are the exploration library's checks
  // (explorePolicyByName, ExploreOptions::validate); a budget without a policy is the grid's.
  const std::vector<Case> cases = {{"--explore", "grid,teleport", "", ""},
                                   {"--travel-budget", "grid", "-1", ""},
                                   {"--travel-budget", "grid", "0", ""},
                                   {"--whisk-budget", "random", "", "-3"},
                                   {"--travel-budget", "", "10", ""},
                                   {"--travel-budget", "none", "10", ""}};
  for (const Case& c : cases) {
    app::SweepOptions o = tinyGrid(out_dir);
    o.grid.explore = c.explore;
    o.grid.travel_budget = c.travel;
    o.grid.whisk_budget = c.whisks;
    const Run r = sweep(o);
    INFO(c.option << " (explore '" << c.explore << "'): " << r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find(c.option) != std::string::npos);
    CHECK_FALSE(std::filesystem::exists(out_dir));
  }
}

TEST_CASE("sweep --explore: a row carries the run's travel and whisks, its curve goes to "
          "curves.csv, as --sim --explore reports them", "[app][sweep][explore]") {
  // One driven run on two_tables.json, stopped after 6 whisks, against the same --sim run.
  TempDir sw, sim;
  app::SweepOptions o = tinyGrid(sw.path().string());
  o.grid.schedule_steps = "4";
  o.grid.seeds = "1";
  o.grid.explore = "frontier";
  o.grid.whisk_budget = "6";
  const Run r = sweep(o);
  INFO(r.err);
  REQUIRE(r.code == 0);
  const Json row = rows(sw.path().string()).at(0);
  CHECK(row["explore"] == "frontier");
  const auto curves = csvCells(slurp(sw.file("curves.csv")));
  REQUIRE(curves.size() >= 2);
  CHECK(curves[0].back() == "run_f1");
  CHECK(std::stod(curves.back()[13]) == Approx(row["recall"].get<double>()));  // run_recall
  CHECK(std::stod(curves.back()[14]) == Approx(row["f1"].get<double>()));      // run_f1
  const int whisks = row["whisks"].get<int>();
  CHECK(whisks >= 1);
  CHECK(whisks <= 6);
  CHECK(std::stod(curves.back()[12]) == Approx(row["travel_m"].get<double>()));  // run_travel_m

  app::SimOptions so;
  so.scene_path = kScene;
  so.noise = "realistic";
  so.seed = 1;
  so.mapping.sampler.schedule_steps = 4;
  so.explore = "frontier";
  so.whisk_budget = 6;
  so.out_dir = sim.path().string();
  std::ostringstream out, err;
  REQUIRE(app::runSim(so, out, err) == 0);
  const Json ex = Json::parse(slurp(sim.file("report.json")))["exploration"];
  CHECK(row["travel_m"] == ex["travel_m"]);
  CHECK(row["whisks"] == ex["whisks"]);
  // One line per point of the run's curve (after the first whisk, every curve_step_m metres,
  // and the final map after the last whisk).
  REQUIRE(ex["curve"].size() >= 2);
  CHECK(curves.size() - 1 == ex["curve"].size());
  const Json& last = ex["curve"].back();
  CHECK(last["whisks"] == whisks);
  CHECK(last["recall"] == row["recall"]);
  CHECK(std::stod(curves.back()[7]) == Approx(last["travel_m"].get<double>()));
  CHECK(std::stod(curves.back()[9]) == Approx(last["recall"].get<double>()));
  CHECK(std::stod(curves.back()[11]) == Approx(last["f1"].get<double>()));
}
