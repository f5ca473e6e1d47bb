// The sweep charts (render/sweep_charts.h): which charts a sweep gets, and their content.
#include "crunch/render/sweep_charts.h"

#include <catch2/catch.hpp>
#include <limits>
#include <string>
#include <vector>

using namespace crunch;

namespace {
SettingSummary setting(const std::string& noise, double sigma_r, int ss, double f1, double wall) {
  SettingSummary s;
  s.scene = "default";
  s.noise = noise;
  s.sigma_r = sigma_r;
  s.schedule_steps = ss;
  s.sweeps = 1;
  s.working_memory = 7;
  s.runs = 2;
  s.f1_mean = f1;
  s.recall_mean = f1;
  s.wall_s_mean = wall;
  s.proposals_mean = wall * 1e5;
  return s;
}
std::vector<std::string> names(const SweepChartSet& set) {
  std::vector<std::string> n;
  for (const auto& [name, chart] : set.charts) n.push_back(name);
  return n;
}
}  // namespace

TEST_CASE("sweepCharts: Pareto charts per regime with two settings, a noise chart with two levels",
          "[sweep_charts]") {
  const std::vector<SettingSummary> all = {
      setting("realistic", 0.005, 8, 0.7, 0.4), setting("realistic", 0.005, 16, 0.8, 0.9),
      setting("noisy", 0.025, 16, 0.3, 0.9)};
  const SweepChartSet set = sweepCharts(all);
  CHECK(names(set) ==
        std::vector<std::string>{"pareto_realistic", "pareto_realistic_proposals", "noise"});
  const Chart& pareto = set.charts[0].second;
  CHECK_THAT(pareto.options.title, Catch::Contains("noise 'realistic'"));
  REQUIRE_FALSE(pareto.series.empty());
  CHECK(pareto.series[0].x.size() == 2);  // both settings on the front
  CHECK_THAT(set.report, Catch::Contains("realistic: Pareto front (wall time):") &&
                             Catch::Contains("mean recall below 0.5 from sigma_r = 25 mm"));
  CHECK(set.summary_csv.find("default,paper,noisy,25,16,1,7,2,0.3000") != std::string::npos);
}

TEST_CASE("sweepCharts: one setting at one noise level draws nothing but still summarises",
          "[sweep_charts]") {
  const SweepChartSet set = sweepCharts({setting("realistic", 0.005, 16, 0.8, 0.9)});
  CHECK(set.charts.empty());
  CHECK(set.report.empty());
  CHECK(set.summary_csv.find("default,paper,realistic,5,16,1,7,2,0.8000") != std::string::npos);
}

TEST_CASE("sweepCharts: two object models get their own fronts, a comparison and noise lines",
          "[sweep_charts]") {
  std::vector<SettingSummary> all;
  for (const std::string model : {"paper", "rooms"}) {
    const double gain = model == "paper" ? 0.0 : 0.1;
    for (const int ss : {8, 16}) {
      SettingSummary s = setting("realistic", 0.005, ss, 0.7 + gain + ss / 160.0, 0.05 * ss);
      s.model = model;
      all.push_back(s);
    }
    SettingSummary noisy = setting("noisy", 0.025, 16, 0.3 + gain, 0.9);
    noisy.model = model;
    all.push_back(noisy);
  }
  const SweepChartSet set = sweepCharts(all);
  CHECK(names(set) == std::vector<std::string>{"pareto_realistic", "pareto_realistic_proposals",
                                               "pareto_realistic_rooms",
                                               "pareto_realistic_rooms_proposals",
                                               "pareto_realistic_models", "pareto_noisy_models",
                                               "noise"});
  CHECK_THAT(set.charts[2].second.options.title, Catch::Contains("model rooms"));
  // The comparison: per model its settings (2 points) and its front (both settings).
  const Chart& models = set.charts[4].second;
  REQUIRE(models.series.size() == 4);
  CHECK(models.series[1].label.find("--model paper") == 0);
  CHECK(models.series[3].label.find("--model rooms") == 0);
  REQUIRE(models.series[3].y.size() == 2);
  CHECK(models.series[3].y[0] == Approx(0.85));
  CHECK(models.series[3].y[1] == Approx(0.9));
  // One setting per model still compares the models (a point each).
  REQUIRE(set.charts[5].second.series[3].y.size() == 1);
  CHECK(set.charts[5].second.series[3].y[0] == Approx(0.4));
  // The noise chart: two reference lines, then recall, F1, precision per model.
  const Chart& noise = set.charts[6].second;
  REQUIRE(noise.series.size() == 2 + 2 * 3);
  CHECK(noise.series[5].label.find("--model rooms: recall") == 0);
  REQUIRE(noise.series[5].y.size() == 2);
  CHECK(noise.series[5].y[0] == Approx(0.9));
  CHECK(noise.series[5].y[1] == Approx(0.4));
  // Several models' legend is tall: the x axis runs on past the noisiest point (25 mm) so the
  // legend, top right, stands clear of the data.
  REQUIRE(noise.options.x_max.has_value());
  CHECK(*noise.options.x_max >= 1.5 * 25.0);
  CHECK_THAT(set.report, Catch::Contains("rooms, realistic: Pareto front") &&
                             Catch::Contains("noise (rooms: 16 T x 1 sweep, WM 7): recall"));
  CHECK(set.summary_csv.find("default,rooms,noisy,25,16,1,7,2,0.4000") != std::string::npos);
  // isPaperSetting is the paper's model at the paper's budget only.
  CHECK(all[1].isPaperSetting());
  CHECK_FALSE(all[4].isPaperSetting());
}

TEST_CASE("exploreCharts: recall and F1 against travel per scene, one line per policy with its "
          "sd band", "[sweep_charts][explore]") {
  auto summary = [](const std::string& scene, const std::string& explore, int runs) {
    ExploreSummary s;
    s.scene = scene;
    s.model = "paper";
    s.noise = "realistic";
    s.explore = explore;
    s.runs = runs;
    s.travel = {0.0, 1.0, 2.0};
    s.recall_mean = {0.0, 0.5, 0.9};
    s.recall_sd = {0.0, 0.2, 0.2};
    s.f1_mean = {0.0, 0.4, 0.8};
    s.f1_sd = {0.0, 0.1, 0.1};
    s.final_travel_mean = 2.0;
    s.final_recall_mean = 0.9;
    s.final_f1_mean = 0.8;
    s.mean_curve_travel_to_target = 2.0;
    s.map_recall_mean = s.map_f1_mean = std::numeric_limits<double>::quiet_NaN();
    return s;
  };
  const std::vector<ExploreSummary> all = {summary("test/scenes/large_room.json", "grid", 2),
                                           summary("test/scenes/large_room.json", "infogain", 1),
                                           summary("default", "grid", 2)};
  const SweepChartSet set = exploreCharts(all);
  CHECK(names(set) == std::vector<std::string>{"explore_large_room_recall", "explore_large_room_f1",
                                               "explore_default_recall", "explore_default_f1"});
  const Chart& recall = set.charts[0].second;
  REQUIRE(recall.validate());
  // The 0.9 target line, grid's mean and its two sd lines, infogain's mean (one seed: no band).
  REQUIRE(recall.series.size() == 5);
  CHECK(recall.series[0].y == std::vector<double>{0.9, 0.9});
  CHECK(recall.series[1].y == std::vector<double>{0.0, 0.5, 0.9});
  CHECK(recall.series[2].y[1] == Approx(0.3));
  CHECK(recall.series[3].y[2] == Approx(1.0));  // mean + sd clipped at 1
  CHECK(recall.series[3].label.empty());        // the band stays out of the legend
  CHECK(recall.series[1].label.rfind("grid", 0) == 0);
  CHECK(recall.series[4].label.rfind("infogain", 0) == 0);
  const Chart& f1 = set.charts[1].second;
  REQUIRE(f1.series.size() == 4);  // no target line on the F1 chart
  CHECK(f1.series[0].y == std::vector<double>{0.0, 0.4, 0.8});
  CHECK(set.report.find("explore large_room:") != std::string::npos);
  CHECK(set.summary_csv.find("test/scenes/large_room.json,paper,realistic,infogain,1,") !=
        std::string::npos);
  // With the final maps known: a square per policy at its mean travel, sd as its bar.
  std::vector<ExploreSummary> mapped = {all[0]};
  mapped[0].map_recall_mean = 0.95;
  mapped[0].map_recall_sd = 0.05;
  mapped[0].map_f1_mean = 0.9;
  const Chart with_map = exploreCharts(mapped).charts[0].second;
  REQUIRE(with_map.series.size() == 5);
  CHECK(with_map.series[4].x == std::vector<double>{2.0});
  CHECK(with_map.series[4].y == std::vector<double>{0.95});
  CHECK(with_map.series[4].y_error == std::vector<double>{0.05});
  CHECK(with_map.series[1].label.find("final map 0.95") != std::string::npos);
  ExploreSummary rooms = all[0];
  rooms.model = "rooms";
  rooms.noise = "noisy";
  CHECK(exploreChartStem(rooms) == "large_room_rooms_noisy");
}
