// The sweep charts (render/sweep_charts.h): which charts a sweep gets, and their content.
#include "crunch/render/sweep_charts.h"

#include <catch2/catch.hpp>
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
  CHECK(set.summary_csv.find("default,noisy,25,16,1,7,2,0.3000") != std::string::npos);
}

TEST_CASE("sweepCharts: one setting at one noise level draws nothing but still summarises",
          "[sweep_charts]") {
  const SweepChartSet set = sweepCharts({setting("realistic", 0.005, 16, 0.8, 0.9)});
  CHECK(set.charts.empty());
  CHECK(set.report.empty());
  CHECK(set.summary_csv.find("default,realistic,5,16,1,7,2,0.8000") != std::string::npos);
}
