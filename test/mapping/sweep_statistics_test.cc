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

TEST_CASE("loadSweepSummary: rows of two object models average apart; no model column is paper",
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
