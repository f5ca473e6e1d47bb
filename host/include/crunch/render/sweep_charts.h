// The charts of `crunchhost sweep-chart` (issue 6, "Charts"; docs/RESULTS.md "Charts"), drawn
// from a sweep's statistics (mapping/sweep_statistics.h) with the chart renderer (chart.h):
//
//  - pareto_<noise> and pareto_<noise>_proposals (pareto_<noise>_<model>... for an object model
//    other than the paper's), for every (model, noise regime) with at least two sampler settings: accuracy (F1 of the fused map, mean over seeds, error bars +-1 sample
//    standard deviation over seeds) against cost (mean wall_s per run; then mean
//    Metropolis-Hastings proposals per run). One point per setting, colour = schedule_steps,
//    marker = (sweeps, working_memory); the Pareto front drawn as a line through its points; the
//    paper's setting (16 temperatures, 1 sweep per temperature, working memory 7:
//    docs/BLACKBOARD.md "Defaults are the paper's", beta_i = exp(7.5 - 0.5 i) for i = 15 ... 0,
//    and "the 7-slot working memory") marked as its own series.
//  - pareto_<noise>_models, when the sweep has two object models or more: each model's settings
//    and Pareto front (F1 against wall time), one colour per model.
//  - noise, when the sweep has at least two noise levels (distinct sigma_r): recall, F1 (mean,
//    +-1 sd over seeds) and precision (mean) against sigma_r in mm, at one sampler setting
//    (noiseLevels), one set of lines per object model, with the paper's "realistic" (5 mm, pi/32) and "very noisy" (25 mm, pi/8)
//    levels marked as vertical lines.
//  - explore_<scene>_recall and explore_<scene>_f1 (issue 14; from a `sweep --explore` run's
//    curves.csv, exploreSummaries): the fused map's recall (F1) against metres driven, one line
//    per exploration policy (mean over seeds, dashed lines at mean +-1 sample sd), one chart per
//    scene (and model / noise regime other than paper / realistic: their names are appended).
//    The recall chart marks the target recall 0.9; a square (+-1 sd) at each policy's
//    mean travel marks its runs' final fused map (global inference at the end), when curves.csv
//    has run_recall / run_f1.
// Pure functions: nothing is written here.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "crunch/mapping/sweep_statistics.h"
#include "crunch/render/chart.h"

namespace crunch {

// One noise regime's settings `set` against one cost (proposals: MH proposals, otherwise wall
// time); `front` indexes `set` (paretoFront order).
Chart sweepParetoChart(const std::vector<SettingSummary>& set, bool proposals,
                       const std::string& noise, const std::vector<size_t>& front);

// Each model's fronts of one noise regime (`fronts`: that regime's NoiseFronts, one per model;
// their indices are into `all`).
Chart sweepModelsChart(const std::vector<SettingSummary>& all,
                       const std::vector<NoiseFronts>& fronts);

// One setting across noise levels per object model (noiseLevels; at least one model, each
// with at least one entry).
Chart sweepNoiseChart(const std::vector<std::vector<SettingSummary>>& models);

// Every chart of a sweep, named as the files' stems ("pareto_realistic", "noise", ...), the
// summary.csv text and a short text report (the Pareto fronts by wall time, the recall at each
// noise level and where it falls below 0.5), one line per chart family.
struct SweepChartSet {
  std::vector<std::pair<std::string, Chart>> charts;
  std::string summary_csv;
  std::string report;
};
SweepChartSet sweepCharts(const std::vector<SettingSummary>& all);

// One (scene, model, noise) group's policies (ExploreSummary entries sharing their travel
// axis), recall (f1 false) or F1 against travel.
Chart exploreChart(const std::vector<ExploreSummary>& group, bool f1);

// The stem of a group's chart files: the scene file's stem ("default" for the built-in arena),
// then "_<model>" unless paper, "_<noise>" unless realistic.
std::string exploreChartStem(const ExploreSummary& s);

// Every exploration chart (explore_<stem>_recall, explore_<stem>_f1), explore_summary.csv's text
// and a report: per scene, each policy's final recall and the travel at which its mean recall
// first reaches the target.
SweepChartSet exploreCharts(const std::vector<ExploreSummary>& all);

}  // namespace crunch
