// A sweep's statistics (mapping/sweep_statistics.h): the Pareto front on hand-made points, the
// averaging over seeds of a small synthetic sweep.json, the fronts per noise regime, the noise
// levels of one setting and summary.csv.
#include "crunch/mapping/sweep_statistics.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>
#include <vector>

#include "support/synthetic_sweep.h"
#include "support/temp_dir.h"

using namespace crunch;
using Json = nlohmann::ordered_json;

namespace {

using synthetic_sweep::row;
Json synthetic() { return synthetic_sweep::sweep(); }

std::vector<SettingSummary> load(const Json& rows) {
  TempDir dir;
  std::ofstream(dir.file("sweep.json")) << rows.dump();
  auto s = loadSweepSummary(dir.file("sweep.json"));
  REQUIRE(s);
  return s.value();
}

}  // namespace

TEST_CASE("paretoFront: the settings no other beats on both cost and accuracy", "[sweep_statistics]") {
  //            0    1    2    3    4    5    6
  const std::vector<double> cost = {1.0, 2.0, 3.0, 2.5, 4.0, 0.5, 2.0};
  const std::vector<double> acc = {0.5, 0.7, 0.9, 0.6, 0.9, 0.2, 0.7};
  // 3 is beaten by 1 (cheaper, better); 4 by 2 (same accuracy, cheaper); 1 and 6 are identical:
  // neither beats the other. Sorted by cost.
  CHECK(paretoFront(cost, acc) == std::vector<size_t>{5, 0, 1, 6, 2});
  CHECK(paretoFront({}, {}).empty());
  CHECK(paretoFront({1.0}, {0.0}) == std::vector<size_t>{0});
  // Equal cost: only the more accurate one. Equal accuracy: only the cheaper one.
  CHECK(paretoFront({1.0, 1.0}, {0.3, 0.4}) == std::vector<size_t>{1});
  CHECK(paretoFront({2.0, 1.0}, {0.4, 0.4}) == std::vector<size_t>{1});
  // A NaN point is never on the front and beats nothing.
  const double nan = std::nan("");
  CHECK(paretoFront({nan, 2.0, 1.0}, {1.0, 0.5, 0.1}) == std::vector<size_t>{2, 1});
}

TEST_CASE("loadSweepSummary averages each setting over its seeds, in grid order",
          "[sweep_statistics]") {
  const std::vector<SettingSummary> s = load(synthetic());
  REQUIRE(s.size() == 8);
  const SettingSummary& first = s[0];
  CHECK(first.noise == "realistic");
  CHECK(first.schedule_steps == 4);
  CHECK(first.runs == 2);
  CHECK(first.f1_mean == Approx(0.5));
  CHECK(first.f1_sd == Approx(0.1 * std::sqrt(2.0)));
  CHECK(first.wall_s_mean == Approx(0.2));
  CHECK(s[3].isPaperSetting());
  CHECK(s[4].noise == "noisy");
  CHECK(s[4].f1_mean == Approx(0.125));
  CHECK(settingName(s[2]) == "8 T x 2 sweeps, WM 14");
}

TEST_CASE("loadSweepSummary names the file, row and column at fault", "[sweep_statistics]") {
  TempDir dir;
  const std::string path = dir.file("sweep.json");
  CHECK_THAT(loadSweepSummary(path).error().message, Catch::Contains(path));
  Json rows = synthetic();
  rows[3]["f1"] = "high";
  std::ofstream(path) << rows.dump();
  CHECK_THAT(loadSweepSummary(path).error().message,
             Catch::Contains("row 3") && Catch::Contains("'f1'"));
}

TEST_CASE("sweepFronts: per noise regime, the wall-time and proposals fronts", "[sweep_statistics]") {
  const std::vector<SettingSummary> all = load(synthetic());
  const std::vector<NoiseFronts> fronts = sweepFronts(all);
  REQUIRE(fronts.size() == 2);
  CHECK(fronts[0].noise == "realistic");
  CHECK(fronts[0].settings == std::vector<size_t>{0, 1, 2, 3});
  CHECK(fronts[0].wall_front == std::vector<size_t>{0, 1, 3});  // (8, 2, 14) is off
  CHECK(fronts[1].settings == std::vector<size_t>{4, 5, 6, 7});
  CHECK(fronts[1].proposals_front == std::vector<size_t>{4, 5, 7});
  const std::string csv = sweepSummaryCsv(all, fronts);
  CHECK(csv.find("default,paper,realistic,5,8,2,14,2,0.6000,0.1414") != std::string::npos);
  CHECK(csv.find(",0,0\n") != std::string::npos);  // (8, 2, 14): on no front
}

TEST_CASE("noiseLevels: the paper's setting across sigma_r, or none with one level",
          "[sweep_statistics]") {
  const std::vector<SettingSummary> levels = noiseLevels(load(synthetic()));
  REQUIRE(levels.size() == 2);
  CHECK(levels[0].isPaperSetting());
  CHECK(levels[0].sigma_r < levels[1].sigma_r);
  Json one = Json::array();
  one.push_back(row("realistic", 0.005, 16, 1, 7, 1, 0.8, 0.8, 1.0, 10.0));
  CHECK(noiseLevels(load(one)).empty());
}

TEST_CASE("loadSweepSummary: rows of two object models average apart, no model column is paper",
          "[sweep_statistics]") {
  Json rows = Json::array();
  for (const std::string model : {"paper", "rooms"}) {
    for (const double sigma : {0.005, 0.025}) {
      Json r = row(sigma < 0.01 ? "realistic" : "noisy", sigma, 16, 1, 7, 1, 0.8, 0.8, 1.0, 1.0);
      r["model"] = model;
      if (model == "rooms") r["recall"] = 0.9;
      rows.push_back(r);
    }
  }
  const std::vector<SettingSummary> s = load(rows);
  REQUIRE(s.size() == 4);
  CHECK(sweepModels(s) == std::vector<std::string>{"paper", "rooms"});
  CHECK(s[2].model == "rooms");
  CHECK(s[2].recall_mean == Approx(0.9));
  CHECK(settingName(s[2]) == "rooms: 16 T x 1 sweep, WM 7");
  CHECK(noiseLevels(s, "rooms").size() == 2);
  CHECK(noiseLevels(s, "rooms").front().model == "rooms");
  CHECK(noiseLevels(s, "chairs").empty());
  // Fronts are per (model, noise).
  CHECK(sweepFronts(s).size() == 4);
  // A model that is not a string names its row and column.
  rows[1]["model"] = 3;
  TempDir dir;
  std::ofstream(dir.file("sweep.json")) << rows.dump();
  const auto bad = loadSweepSummary(dir.file("sweep.json"));
  REQUIRE_FALSE(bad);
  CHECK_THAT(bad.error().message, Catch::Contains("row 1") && Catch::Contains("'model'"));
  // Rows without the column (sweeps from before the axis) are the paper's.
  CHECK(load(synthetic()).front().model == "paper");
}

// ---- Exploration curves (issue 14): hand-made curves.csv, two policies x two seeds.
namespace {
// grid:   seed 1 whisks at 1 m (recall .2, F1 .3) and 3 m (.6, .7);
//         seed 2 at 2 m (.4, .5) and 4 m (1.0, .9).
// random: seed 1 at 1 m (0, 0) and 6 m (.5, .6); seed 2 at 2 m (.25, .3).
const char* kCurves =
    "grid_index,scene,model,explore,noise,seed,whisk,travel_m,whisks,recall,precision,f1\n"
    "0,s.json,paper,grid,realistic,1,0,1,1,0.2,1.0,0.3\n"
    "0,s.json,paper,grid,realistic,1,1,3,2,0.6,0.8,0.7\n"
    "1,s.json,paper,grid,realistic,2,0,2,1,0.4,null,0.5\n"
    "1,s.json,paper,grid,realistic,2,1,4,2,1.0,0.8,0.9\n"
    "2,s.json,paper,random,realistic,1,0,1,1,0.0,,0.0\n"
    "2,s.json,paper,random,realistic,1,1,6,5,0.5,0.7,0.6\n"
    "3,s.json,paper,random,realistic,2,0,2,1,0.25,0.35,0.3\n";
}  // namespace

TEST_CASE("Explore curves: a step function of travel, 0 before the first whisk, held after the "
          "last", "[sweep][explore]") {
  const std::vector<double> travel = {1.0, 3.0, 3.0, 5.0}, value = {0.2, 0.4, 0.5, 0.9};
  CHECK(curveValueAt(travel, value, 0.0) == 0.0);
  CHECK(curveValueAt(travel, value, 0.999) == 0.0);
  CHECK(curveValueAt(travel, value, 1.0) == 0.2);
  CHECK(curveValueAt(travel, value, 2.9) == 0.2);
  CHECK(curveValueAt(travel, value, 3.0) == 0.5);  // two whisks at 3 m: the later one counts
  CHECK(curveValueAt(travel, value, 100.0) == 0.9);
}

TEST_CASE("Explore summaries: mean and sd over seeds on a common travel axis per scene",
          "[sweep][explore]") {
  const auto curves = parseExploreCurves(kCurves, "curves.csv");
  REQUIRE(curves);
  REQUIRE(curves.value().size() == 4);
  CHECK(std::isnan(curves.value()[1].precision[0]));  // null precision (nothing mapped) read
  CHECK(std::isnan(curves.value()[0].run_recall));     // no run_recall column: not known
  const auto all = exploreSummaries(curves.value(), 7, 0.9);  // axis 0, 1, ..., 6 m
  REQUIRE(all.size() == 2);
  const ExploreSummary& grid = all[0];
  const ExploreSummary& random = all[1];
  CHECK(grid.explore == "grid");
  CHECK(random.explore == "random");
  CHECK(grid.runs == 2);
  CHECK(grid.travel == std::vector<double>{0, 1, 2, 3, 4, 5, 6});
  CHECK(random.travel == grid.travel);  // one axis for the scene: to the longest run (6 m)
  const double s2 = std::sqrt(2.0);  // sd of two values d apart: d / sqrt(2)
  const std::vector<std::tuple<int, double, double>> grid_recall = {
      {0, 0.0, 0.0}, {1, 0.1, 0.2 / s2}, {2, 0.3, 0.2 / s2}, {3, 0.5, 0.2 / s2},
      {4, 0.8, 0.4 / s2}, {6, 0.8, 0.4 / s2}};
  for (const auto& [i, m, d] : grid_recall) {
    INFO("grid at " << i << " m");
    CHECK(grid.recall_mean[i] == Approx(m));
    CHECK(grid.recall_sd[i] == Approx(d));
  }
  CHECK(grid.f1_mean[4] == Approx(0.8));
  CHECK(grid.f1_sd[4] == Approx(0.2 / s2));
  CHECK(random.recall_mean[1] == Approx(0.0));
  CHECK(random.recall_mean[2] == Approx(0.125));
  CHECK(random.recall_sd[2] == Approx(0.25 / s2));
  CHECK(random.recall_mean[5] == Approx(0.125));  // seed 2 ended at 2 m: its 0.25 held
  CHECK(random.recall_mean[6] == Approx(0.375));
  CHECK(random.f1_mean[6] == Approx(0.45));
  CHECK(grid.final_travel_mean == Approx(3.5));
  CHECK(grid.final_whisks_mean == Approx(2.0));
  CHECK(grid.final_recall_mean == Approx(0.8));
  CHECK(grid.final_f1_mean == Approx(0.8));
  CHECK(random.final_travel_mean == Approx(4.0));
  CHECK(random.final_whisks_mean == Approx(3.0));
  // Target 0.9: only grid's seed 2 reaches it (at 4 m); neither mean curve does.
  CHECK(grid.reached == 1);
  CHECK(grid.travel_to_target_mean == Approx(4.0));
  CHECK(std::isnan(grid.mean_curve_travel_to_target));
  CHECK(random.reached == 0);
  CHECK(std::isnan(random.travel_to_target_mean));
  // Target 0.5: grid's seeds at 3 and 4 m, its mean curve at 3 m; random's seed 1 at 6 m.
  const auto half = exploreSummaries(curves.value(), 7, 0.5);
  CHECK(half[0].reached == 2);
  CHECK(half[0].travel_to_target_mean == Approx(3.5));
  CHECK(half[0].mean_curve_travel_to_target == Approx(3.0));
  CHECK(half[1].reached == 1);
  CHECK(std::isnan(half[1].mean_curve_travel_to_target));
  const std::string csv = exploreSummaryCsv(half);
  CHECK(csv.find("s.json,paper,realistic,grid,2,3.50,2.0,0.8000,") != std::string::npos);
  CHECK(csv.find(",0.5,2,3.50,3.00,,,,\n") != std::string::npos);  // final maps not given
  CHECK(csv.find("s.json,paper,realistic,random,2,4.00,3.0,0.3750,") != std::string::npos);
  CHECK(csv.find(",0.5,1,6.00,,,,,\n") != std::string::npos);  // mean curve never reached 0.5
}

TEST_CASE("Explore curves: bad lines are errors naming the file, line and column",
          "[sweep][explore]") {
  const std::string header =
      "grid_index,scene,model,explore,noise,seed,whisk,travel_m,whisks,recall,precision,f1\n";
  CHECK_THAT(parseExploreCurves("scene,seed\n", "c.csv").error().message,
             Catch::Contains("c.csv") && Catch::Contains("header") && Catch::Contains("model"));
  CHECK_THAT(parseExploreCurves(header + "0,s,paper,grid,realistic,1,0,1,1,1.5,1,0.5\n", "c.csv")
                 .error()
                 .message,
             Catch::Contains("line 2") && Catch::Contains("recall"));
  CHECK_THAT(parseExploreCurves(header + "0,s,paper,grid,realistic,1,0,1,1,0.5\n", "c.csv")
                 .error()
                 .message,
             Catch::Contains("line 2") && Catch::Contains("fields"));
  CHECK_THAT(parseExploreCurves(header + "0,s,paper,grid,realistic,1,0,2,1,0.5,1,0.5\n"
                                         "0,s,paper,grid,realistic,1,1,1,2,0.5,1,0.5\n",
                                "c.csv")
                 .error()
                 .message,
             Catch::Contains("line 3") && Catch::Contains("travel_m"));
  CHECK_THAT(parseExploreCurves(header + "0,s,paper,grid,realistic,1,0,x,1,0.5,1,0.5\n", "c.csv")
                 .error()
                 .message,
             Catch::Contains("travel_m") && Catch::Contains("'x'"));
  // A scene path with a comma is quoted by the writer and read back whole.
  const auto quoted =
      parseExploreCurves(header + "0,\"a,b.json\",paper,grid,realistic,1,0,1,1,0.5,1,0.5\n", "c");
  REQUIRE(quoted);
  CHECK(quoted.value()[0].scene == "a,b.json");
  TempDir dir;
  CHECK_THAT(loadExploreCurves(dir.file("curves.csv")).error().message,
             Catch::Contains("curves.csv") && Catch::Contains("cannot read"));
  std::ofstream(dir.file("empty.csv")) << header;
  CHECK_THAT(loadExploreCurves(dir.file("empty.csv")).error().message,
             Catch::Contains("no curve point"));
}

TEST_CASE("Explore curves: a run's travel after its last whisk extends the axis and its figures",
          "[sweep][explore]") {
  const std::string header = "scene,model,explore,noise,seed,travel_m,whisks,recall,precision,f1,"
                             "run_travel_m,run_recall,run_f1\n";
  // grid whisks at 1 m and stops at 2 m; random whisks at 1 m, then drives on to 8 m. Their
  // final maps (global inference) find more than the curves' snapshots.
  const auto curves = parseExploreCurves(header +
                                             "s,paper,grid,realistic,1,1,1,0.5,1,0.6,2,0.75,0.8\n"
                                             "s,paper,random,realistic,1,1,1,0.25,1,0.4,8,0.5,0.6\n",
                                         "c.csv");
  REQUIRE(curves);
  CHECK(curves.value()[1].run_travel_m == 8.0);
  const auto all = exploreSummaries(curves.value(), 9);
  REQUIRE(all.size() == 2);
  CHECK(all[0].travel.back() == 8.0);  // to the longest run, not its last whisk
  CHECK(all[0].recall_mean.back() == Approx(0.5));
  CHECK(all[0].final_travel_mean == Approx(2.0));
  CHECK(all[1].final_travel_mean == Approx(8.0));
  CHECK(all[0].map_recall_mean == Approx(0.75));
  CHECK(all[0].final_recall_mean == Approx(0.5));  // the curve's last, not the final map's
  CHECK(all[1].map_f1_mean == Approx(0.6));
  CHECK(all[1].map_recall_sd == 0.0);  // one seed
  CHECK_THAT(parseExploreCurves(header + "s,paper,grid,realistic,1,1,1,0.5,1,0.6,2,1.5,0.8\n",
                                "c.csv")
                 .error()
                 .message,
             Catch::Contains("run_recall"));
  CHECK_THAT(parseExploreCurves(header + "s,paper,grid,realistic,1,3,1,0.5,1,0.6,2,0.5,0.5\n", "c.csv")
                 .error()
                 .message,
             Catch::Contains("run_travel_m") && Catch::Contains("below"));
}
