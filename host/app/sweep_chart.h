// `crunchhost sweep-chart --in DIR [--out DIR]` (issue 6, "Charts"; docs/RESULTS.md "Charts").
//
// Reads DIR/sweep.json (written by `crunchhost sweep`, sweep_mode.h), averages its rows over the
// seeds of each grid point (noise x schedule_steps x sweeps x working_memory) and draws, as PNG
// and SVG with the Cairo chart renderer (crunch/render/chart.h):
//
//  - pareto_<noise>.{png,svg} and pareto_<noise>_proposals.{png,svg}, for every noise regime
//    with at least two sampler settings: accuracy (F1 of the fused map, mean over seeds, error
//    bars +-1 sample standard deviation over seeds) against cost (mean wall_s per run; then mean
//    Metropolis-Hastings proposals per run). One point per setting, colour = schedule_steps,
//    marker = (sweeps, working_memory); the Pareto front (paretoFront below) drawn as a line
//    through its points; the paper's setting (16 temperatures, 1 sweep per temperature, working
//    memory 7: docs/BLACKBOARD.md "Defaults are the paper's", beta_i = exp(7.5 - 0.5 i) for
//    i = 15 ... 0, and "the 7-slot working memory") marked as its own series.
//  - noise.{png,svg} when the sweep has at least two noise levels (distinct sigma_r): recall, F1
//    (mean, +-1 sd over seeds) and precision (mean) against sigma_r in mm, at one sampler
//    setting (the paper's if the sweep has it at two noise levels or more, otherwise the first
//    in grid order), with the paper's "realistic" (5 mm, pi/32) and "very noisy" (25 mm, pi/8)
//    levels marked as vertical lines.
//  - summary.csv: one row per (noise, setting): the means and spreads the charts show, and
//    whether the setting is on the wall-time and on the proposals Pareto front.
//
// Input checks, all before anything is written: DIR/sweep.json must exist and parse, be a
// non-empty JSON array of objects, every object must have the columns the charts need
// (kSweepChartColumns) with the right types, and all rows must be of one scene. Otherwise: a
// message naming the file (and the row and column), exit 2, nothing written.
// Exit codes: 0 success; 2 bad input; 1 a file could not be written.
#pragma once

#include <cstddef>
#include <iosfwd>
#include <string>
#include <vector>

#include "crunch/core/result.h"

namespace crunch::app {

// The paper's sampler setting (docs/BLACKBOARD.md; SamplerOptions / MappingOptions defaults).
inline constexpr int kPaperScheduleSteps = 16;
inline constexpr int kPaperSweeps = 1;
inline constexpr int kPaperWorkingMemory = 7;
// The paper's noise levels as ARCHITECTURE.md maps them: realistic and "very noisy" sigma_r, m.
inline constexpr double kPaperRealisticSigmaR = 0.005;
inline constexpr double kPaperNoisySigmaR = 0.025;

// The sweep.json columns sweep-chart reads.
extern const std::vector<std::string> kSweepChartColumns;

struct SweepChartOptions {
  std::string in_dir;   // holds sweep.json
  std::string out_dir;  // empty: in_dir; created if missing
};

// One grid point's rows averaged over its seeds. Spreads are sample standard deviations
// (n - 1; 0 for a single seed).
struct SettingSummary {
  std::string scene;
  std::string noise;     // regime name as in sweep.json ("realistic", "x2", ...)
  double sigma_r = 0.0;  // m
  int schedule_steps = 0, sweeps = 0, working_memory = 0;
  int runs = 0;  // seeds averaged
  double f1_mean = 0.0, f1_sd = 0.0;
  double recall_mean = 0.0, recall_sd = 0.0;
  double precision_mean = 0.0, precision_sd = 0.0;
  double wall_s_mean = 0.0;
  double proposals_mean = 0.0;
  bool isPaperSetting() const {
    return schedule_steps == kPaperScheduleSteps && sweeps == kPaperSweeps &&
           working_memory == kPaperWorkingMemory;
  }
};

// Reads and checks `path` (a sweep.json) and averages its rows per (noise, schedule_steps,
// sweeps, working_memory), in grid order (order of first appearance). Errors name the path,
// and the row index and column where one is at fault.
Result<std::vector<SettingSummary>> loadSweepSummary(const std::string& path);

// The Pareto front of points (cost[i], accuracy[i]): the indices of the points no other point
// beats on both, i.e. no j with cost[j] <= cost[i] and accuracy[j] >= accuracy[i], one of them
// strictly. Identical points are all on the front. Sorted by cost, then by accuracy. Points with
// a non-finite coordinate are never on it and never beat another. Requires equal lengths.
std::vector<size_t> paretoFront(const std::vector<double>& cost,
                                const std::vector<double>& accuracy);

int runSweepChart(const SweepChartOptions& options, std::ostream& out, std::ostream& err);

}  // namespace crunch::app
