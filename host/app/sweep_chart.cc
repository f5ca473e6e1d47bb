#include "sweep_chart.h"

#include <filesystem>
#include <ostream>

#include "crunch/core/atomic_file.h"
#include "crunch/mapping/sweep_statistics.h"
#include "crunch/render/sweep_charts.h"

namespace crunch::app {

namespace {

// Every chart as PNG and SVG, then the summary; stops at the first failure.
Status writeCharts(const SweepChartSet& set, const std::string& dir,
                   const std::string& summary = "summary.csv") {
  if (Status s = ensureDirectory(dir); !s) return s;
  for (const auto& [name, chart] : set.charts) {
    if (Status s = renderChartPng(chart, dir + name + ".png"); !s) return s;
    if (Status s = renderChartSvg(chart, dir + name + ".svg"); !s) return s;
  }
  return writeFileAtomic(dir + summary, set.summary_csv);
}

// An explore sweep (DIR/curves.csv): recall and F1 against travel, per scene.
int runExploreCharts(const SweepChartOptions& options, std::ostream& out, std::ostream& err) {
  auto curves = loadExploreCurves(options.in_dir + "/curves.csv");
  if (!curves) {
    err << "crunchhost sweep-chart: " << curves.error().message << "\n";
    return 2;
  }
  const SweepChartSet set = exploreCharts(exploreSummaries(curves.value()));
  const std::string dir = (options.out_dir.empty() ? options.in_dir : options.out_dir) + "/";
  if (Status s = writeCharts(set, dir, "explore_summary.csv"); !s) {
    err << "crunchhost sweep-chart: " << s.error().message << "\n";
    return 1;
  }
  out << set.report << "wrote " << dir << "{";
  for (const auto& [name, chart] : set.charts) out << name << ",";
  out << "explore_summary} (.png and .svg; explore_summary.csv)\n";
  return 0;
}

}  // namespace

int runSweepChart(const SweepChartOptions& options, std::ostream& out, std::ostream& err) {
  if (std::filesystem::exists(options.in_dir + "/curves.csv"))
    return runExploreCharts(options, out, err);
  auto loaded = loadSweepSummary(options.in_dir + "/sweep.json");
  if (!loaded) {
    err << "crunchhost sweep-chart: " << loaded.error().message << "\n";
    return 2;
  }
  const SweepChartSet set = sweepCharts(loaded.value());
  const std::string dir = (options.out_dir.empty() ? options.in_dir : options.out_dir) + "/";
  if (Status s = writeCharts(set, dir); !s) {
    err << "crunchhost sweep-chart: " << s.error().message << "\n";
    return 1;
  }
  out << set.report << "wrote " << dir << "{";
  for (const auto& [name, chart] : set.charts) out << name << ",";
  out << "summary}" << (set.charts.empty() ? " (no chart: one setting and one noise level)" : "")
      << " (.png and .svg; summary.csv)\n";
  return 0;
}

}  // namespace crunch::app
