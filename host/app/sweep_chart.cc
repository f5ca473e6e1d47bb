#include "sweep_chart.h"

#include <ostream>

#include "crunch/core/atomic_file.h"
#include "crunch/mapping/sweep_statistics.h"
#include "crunch/render/sweep_charts.h"

namespace crunch::app {

namespace {

// Every chart as PNG and SVG, then summary.csv; stops at the first failure.
Status writeCharts(const SweepChartSet& set, const std::string& dir) {
  if (Status s = ensureDirectory(dir); !s) return s;
  for (const auto& [name, chart] : set.charts) {
    if (Status s = renderChartPng(chart, dir + name + ".png"); !s) return s;
    if (Status s = renderChartSvg(chart, dir + name + ".svg"); !s) return s;
  }
  return writeFileAtomic(dir + "summary.csv", set.summary_csv);
}

}  // namespace

int runSweepChart(const SweepChartOptions& options, std::ostream& out, std::ostream& err) {
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
