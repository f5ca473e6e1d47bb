// `crunchhost sweep-chart --in DIR [--out DIR]` (issue 6, "Charts"; docs/RESULTS.md "Charts"):
// wiring only. Reads DIR/sweep.json (written by `crunchhost sweep`) into the library's
// statistics (crunch/mapping/sweep_statistics.h: rows averaged over the seeds of each setting,
// Pareto fronts, noise levels), draws the charts (crunch/render/sweep_charts.h) and writes
//   OUT/pareto_<noise>.{png,svg}, OUT/pareto_<noise>_proposals.{png,svg} (per noise regime with
//   at least two sampler settings), OUT/noise.{png,svg} (with two noise levels or more) and
//   OUT/summary.csv (one row per noise and setting: means, spreads, whether on a front);
// then prints the fronts and the recall at each noise level.
// An explore sweep (DIR/curves.csv present, `sweep --explore`): instead, the curves
// (loadExploreCurves, exploreSummaries) drawn as OUT/explore_<scene>_{recall,f1}.{png,svg}
// (recall and F1 against metres driven, one line per policy, mean +-1 sd over seeds) and
// OUT/explore_summary.csv; the Pareto and noise charts, which average over the policies, are
// not drawn then.
//
// Input checks, all before anything is written: those of loadSweepSummary (loadExploreCurves). Otherwise: a message
// naming the file (and the row and column), exit 2, nothing written.
// Exit codes: 0 success; 2 bad input; 1 a file could not be written.
#pragma once

#include <iosfwd>
#include <string>

namespace crunch::app {

struct SweepChartOptions {
  std::string in_dir;   // holds sweep.json
  std::string out_dir;  // empty: in_dir; created if missing
};

int runSweepChart(const SweepChartOptions& options, std::ostream& out, std::ostream& err);

}  // namespace crunch::app
