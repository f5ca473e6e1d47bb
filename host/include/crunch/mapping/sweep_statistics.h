// Statistics of a sweep (issue 6, "Charts"; docs/RESULTS.md "Charts"): a sweep.json's rows
// averaged over the seeds of each grid point (model x noise x schedule_steps x sweeps x
// working_memory),
// the Pareto front of accuracy against cost, the noise levels of one setting, and summary.csv.
// The charts drawn from them are render/sweep_charts.h.
//
// Accuracy is the F1 of the fused map (Evaluation); cost is the mean wall_s per run or the mean
// Metropolis-Hastings proposals per run. Spreads are sample standard deviations (n - 1; 0 for a
// single seed).
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "crunch/core/result.h"

namespace crunch {

// The paper's sampler setting (docs/BLACKBOARD.md; SamplerOptions / MappingOptions defaults).
inline constexpr int kPaperScheduleSteps = 16;
inline constexpr int kPaperSweeps = 1;
inline constexpr int kPaperWorkingMemory = 7;
// The paper's noise levels as ARCHITECTURE.md maps them: realistic and "very noisy" sigma_r, m.
inline constexpr double kPaperRealisticSigmaR = 0.005;
inline constexpr double kPaperNoisySigmaR = 0.025;

// The sweep.json columns the statistics read.
extern const std::vector<std::string> kSweepChartColumns;

// One grid point's rows averaged over its seeds.
struct SettingSummary {
  std::string scene;
  std::string model = "paper";  // the object model (--model); sweeps from before the axis: paper
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
    return model == "paper" && schedule_steps == kPaperScheduleSteps && sweeps == kPaperSweeps &&
           working_memory == kPaperWorkingMemory;
  }
};

// "16 T x 1 sweep, WM 7": the setting's name in charts and reports; a model other than the
// paper's leads: "rooms: 16 T x 1 sweep, WM 7".
std::string settingName(const SettingSummary& s);

// Reads and checks `path` (a sweep.json) and averages its rows per (model, noise,
// schedule_steps, sweeps, working_memory), in grid order (order of first appearance). Checks: the
// file exists and parses, is a non-empty JSON array of objects, every object has the
// kSweepChartColumns with the right types (and "model", if present, a string: rows without it
// are the paper's model), and all rows are of one scene. Errors name the path, and the row index and column
// where one is at fault.
Result<std::vector<SettingSummary>> loadSweepSummary(const std::string& path);

// The Pareto front of points (cost[i], accuracy[i]): the indices of the points no other point
// beats on both, i.e. no j with cost[j] <= cost[i] and accuracy[j] >= accuracy[i], one of them
// strictly. Identical points are all on the front. Sorted by cost, then by accuracy. Points with
// a non-finite coordinate are never on it and never beat another. Requires equal lengths.
std::vector<size_t> paretoFront(const std::vector<double>& cost,
                                const std::vector<double>& accuracy);

// One (model, noise regime)'s settings and their Pareto fronts (F1 against wall time, against
// proposals). All indices are into the summary list the fronts were computed from.
struct NoiseFronts {
  std::string model;
  std::string noise;
  std::vector<size_t> settings;        // in grid order
  std::vector<size_t> wall_front;      // sorted by cost (paretoFront)
  std::vector<size_t> proposals_front;
};
// Per (model, noise regime), in order of first appearance.
std::vector<NoiseFronts> sweepFronts(const std::vector<SettingSummary>& all);

// One setting of `model` across the noise levels, by sigma_r: the paper's sampler setting if the
// sweep has it at two levels or more, otherwise the model's first setting in grid order. Empty
// when the model's rows have fewer than two distinct sigma_r (or the chosen setting fewer than
// two levels).
std::vector<SettingSummary> noiseLevels(const std::vector<SettingSummary>& all,
                                        const std::string& model = "paper");
// The models of `all`, in order of first appearance.
std::vector<std::string> sweepModels(const std::vector<SettingSummary>& all);

// summary.csv: one row per (model, noise, setting): the means and spreads, and whether the setting is
// on the wall-time and on the proposals Pareto front of its noise regime.
std::string sweepSummaryCsv(const std::vector<SettingSummary>& all,
                            const std::vector<NoiseFronts>& fronts);

// ---- Exploration (issue 14): recall and F1 against metres driven, from a `sweep --explore`
// run's curves.csv (mapping/sweep.h kCurveColumns; one line per whisk of every explore run).

// One explore run's curve: its points in whisk order (travel non-decreasing).
struct ExploreCurve {
  std::string scene, model, explore, noise;
  std::uint64_t seed = 0;
  std::vector<double> travel_m, recall, precision, f1;
  std::vector<int> whisks;
  // Metres the run drove in all (curves.csv run_travel_m; without the column, the last whisk's).
  double run_travel_m = 0.0;
  // The run's final fused map (curves.csv run_recall, run_f1; NaN without the columns).
  double run_recall = std::numeric_limits<double>::quiet_NaN();
  double run_f1 = std::numeric_limits<double>::quiet_NaN();
};

// curves.csv's text into its runs, grouped by (scene, model, explore, noise, seed) in order of
// first appearance. Checks: a header holding every kCurveColumns name, each line as many fields
// as the header, numbers where numbers belong (recall, precision, f1 in [0, 1] or empty/null for
// precision; travel_m finite and >= 0 and non-decreasing within a run). Errors name `source`,
// the line (1-based) and the column.
Result<std::vector<ExploreCurve>> parseExploreCurves(const std::string& text,
                                                     const std::string& source);
// The file at `path` through parseExploreCurves; an Error naming it when it cannot be read or
// holds no curve point.
Result<std::vector<ExploreCurve>> loadExploreCurves(const std::string& path);

// A run's value at `travel` metres: a step function of travel, the value after the last whisk
// made at or before `travel`; 0 before the first whisk (nothing is mapped yet); the last value
// held after the run ended. Requires equal lengths, travel non-decreasing.
double curveValueAt(const std::vector<double>& travel, const std::vector<double>& value,
                    double at);

// One policy on one (scene, model, noise), over its seeds: recall and F1 on a common travel
// axis (shared by every policy of the same scene, model and noise: 0 to the longest run's
// run_travel_m, evenly spaced), mean and sample sd (n - 1; 0 for one seed) over the seeds at each
// travel; the runs' final figures; and how far each seed drove before its fused map first
// reached recall >= recall_target.
struct ExploreSummary {
  std::string scene, model, noise, explore;
  int runs = 0;
  std::vector<double> travel;  // the common axis, metres
  std::vector<double> recall_mean, recall_sd, f1_mean, f1_sd;
  double final_travel_mean = 0.0;  // run_travel_m
  double final_whisks_mean = 0.0;
  double final_recall_mean = 0.0, final_recall_sd = 0.0, final_f1_mean = 0.0, final_f1_sd = 0.0;
  // The runs' final fused maps (run_recall, run_f1), mean and sd over seeds; NaN if not given.
  double map_recall_mean = 0.0, map_recall_sd = 0.0, map_f1_mean = 0.0, map_f1_sd = 0.0;
  double recall_target = 0.9;
  int reached = 0;  // seeds whose recall reached the target
  // Mean over the seeds that reached it of the travel at which each first did (NaN: none did).
  double travel_to_target_mean = 0.0;
  // The travel at which the MEAN recall curve first reaches the target (NaN: never).
  double mean_curve_travel_to_target = 0.0;
};

// Per (scene, model, noise), then per explore value, in order of first appearance. `samples`
// >= 2 points on each travel axis.
std::vector<ExploreSummary> exploreSummaries(const std::vector<ExploreCurve>& curves,
                                             int samples = 201, double recall_target = 0.9);

// explore_summary.csv: one row per summary with its final and travel-to-target figures.
std::string exploreSummaryCsv(const std::vector<ExploreSummary>& all);

}  // namespace crunch
