// The sweep grid of `crunchhost sweep` (issue 6, "Sweeps"; docs/RESULTS.md "Sweeps"): the lists
// of settings to map, their parsing and validation, the grid's fingerprint, one row per grid
// point and the sweep.csv / sweep.json files, and the merge of sharded sweeps. Running the
// points needs the simulator (crunch_sim/sweep_run.h); nothing here does.
//
// A sweep is the grid scenes x models x explore x noise x schedule_steps x sweeps x
// working_memory x seeds; each grid
// point is one mapping run with the gaussian (ray-cast) sensor model — the fast one; the physics
// sensor is not swept — at the point's noise regime and object model (`--model`, ModelParams::
// objects), with default MappingOptions otherwise. Grid order, the order of the rows: scene
// (slowest), model, explore, noise (the named regimes, then the scales),
// schedule_steps, sweeps, working_memory, seed (fastest); a point's grid_index is its position in
// that order.
//
// The explore axis (issue 14, `--explore grid,random,...`; docs/EXPLORATION.md): each value is an
// exploration policy's name (the driven run of `crunchhost --sim --explore NAME`, with the grid's
// `--travel-budget` / `--whisk-budget`), or "none": the scene's pose list teleported in order,
// the paper's §2.8 run and every sweep before the axis. Without `--explore` every point is
// "none". The names and budgets are checked by the exploration library
// (crunch_sim/sweep_run.h validateSweepExplore; mapping cannot link it), not here. A "none" row
// has travel_m null (no travel is measured) and whisks = poses. Each explore run's
// recall-against-travel curve (report.json exploration.curve) goes to curves.csv.
//
// Files: sweep.csv and sweep.json (a JSON array of objects with the same columns, in the same
// order, with the same values: CSV numbers are the JSON numbers' text). Columns (kSweepColumns):
// the grid fingerprint (a 64-bit FNV-1a hash, hex, of the grid description: every scene's
// argument and file content, the noise sigmas, the budget lists, the seeds and the fixed mapping
// options), grid_index, grid_size, shard ("i/n", "0/1" unsharded), the point's settings, accuracy
// (Evaluation), cost (proposals, the mapping's high-water marks MapStats::peak_live_tables /
// peak_live_legs, wall_s of the run's sensing + inference + evaluation) and
// process_peak_rss_kib: the PROCESS's peak resident set when the row finished, shared by every
// run of the process (not a per-run figure; it only grows down the rows).
//
// Errors: every parse and check returns an Error naming the option ("--noise", "--seeds", ...),
// or for a merge the directory or file at fault.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "crunch/core/result.h"
#include "crunch/mapping/evaluation.h"
#include "crunch/mapping/map.h"
#include "crunch/mapping/mapping_options.h"
#include "crunch/mapping/sensor_model.h"
#include "crunch/scene/scene.h"

namespace crunch {

// The columns of sweep.csv / keys of every sweep.json object, in order.
extern const std::vector<std::string> kSweepColumns;

// The grid's lists exactly as on the command line, comma-separated; empty text = the default.
struct SweepGridSpec {
  // Scene files; the word "default" is the built-in arena. Empty: {"default"}.
  std::vector<std::string> scenes;
  std::string models;          // paper,rooms (default: --sim's, walls)
  std::string noise;           // ideal,realistic,noisy names (default: realistic, if no scale)
  std::string noise_scale;     // multiples of realistic's sigma_r = 5 mm and sigma_phi = pi/32
  std::string schedule_steps;  // SamplerOptions::schedule_steps values (default 16)
  std::string sweeps;          // SamplerOptions::sweeps_per_temperature values (default 1)
  std::string working_memory;  // MappingOptions::working_memory values (default 7)
  std::string seeds;           // N >= 1: seeds 1..N
  std::string seed_list;       // explicit seeds (excludes seeds); neither: seed 1
  std::string chain_fusion;    // every point's MappingOptions::chain_fusion by name (default vote)
  std::string acceptance;      // every point's SamplerOptions::acceptance by name (default paper)
  std::string explore;         // exploration policies, e.g. grid,random,infogain (default none)
  std::string travel_budget;   // every explore point's --travel-budget, metres (default none)
  std::string whisk_budget;    // every explore point's --whisk-budget (default none)
};

struct SweepScene {
  std::string arg;  // as given: a path or "default"
  Scene scene;
};

// One grid point: indices into SweepGrid::scenes / noises, and the point's values.
struct SweepPoint {
  std::size_t scene = 0, noise = 0;
  ObjectModel model = ObjectModel::kPaper;
  std::string explore = "none";  // a policy name, or "none" (the pose list, teleported)
  int schedule_steps = 0, sweeps = 0, working_memory = 0;
  std::uint64_t seed = 0;
};

struct SweepGrid {
  std::vector<SweepScene> scenes;
  std::vector<ObjectModel> models;
  std::vector<std::string> explores;  // {"none"} without --explore
  std::vector<NoiseRegime> noises;
  std::vector<int> schedule_steps, sweeps, working_memory;
  std::vector<std::uint64_t> seeds;
  ChainFusion chain_fusion = ChainFusion::kVote;  // the same for every point
  Acceptance acceptance = Acceptance::kTempered;  // the same for every point
  // Every explore point's budgets (ExploreOptions::travel_budget_m, whisk_budget; their ranges
  // are ExploreOptions::validate's): infinity and 0 when not given. Given without --explore
  // (or with only "none"), an Error.
  double travel_budget_m = std::numeric_limits<double>::infinity();
  int whisk_budget = 0;
  std::string fingerprint;  // 16 hex digits

  std::size_t size() const;
  // Index -> point, seed fastest, scene slowest. Requires index < size().
  SweepPoint pointAt(std::size_t index) const;
  // The point's mapping settings: defaults, with the point's seed, object model, schedule_steps,
  // sweeps and working_memory, and the grid's chain_fusion and acceptance. Valid:
  // buildSweepGrid validated every point. (The run raises eq. 12's
  // shapelet sigmas to the point's noise, withSensorNoise, as every simulated run does.)
  MappingOptions mappingOptions(const SweepPoint& point) const;
};

// Parses and checks every list, loads every scene (an Error names the option; nothing is
// written) and validates every point's MappingOptions and NoiseRegime. At most 10^7 points.
Result<SweepGrid> buildSweepGrid(const SweepGridSpec& spec);

// `--shard i/n`: only grid points with index % n == i. Empty text: 0/1 (every point).
struct SweepShard {
  int index = 0, count = 1;
  std::string name() const;  // "i/n"
  bool holds(std::size_t grid_index) const;
};
Result<SweepShard> parseSweepShard(const std::string& text);

// `--jobs N`: a count >= 0 (0: one worker per core). Empty text: 0.
Result<int> parseSweepJobs(const std::string& text);

// One point of an explore run's recall-against-travel curve (exploration::CurvePoint, which
// this layer cannot include): after each whisk.
struct SweepCurvePoint {
  double travel_m = 0.0;
  int whisks = 0;
  double recall = 0.0, precision = 0.0, f1 = 0.0;
};

// The columns of curves.csv, in order: one line per curve point of every explore row, rows in
// grid order, points in whisk order; run_travel_m is the row's travel_m (the run may drive on
// after its last whisk), run_recall and run_f1 the row's recall and f1: the run's final fused map
// (global inference at the end), which the curve's running snapshot does not include.
extern const std::vector<std::string> kCurveColumns;

// One row of sweep.csv / sweep.json (kSweepColumns, in order).
struct SweepRow {
  std::string grid;
  std::size_t grid_index = 0, grid_size = 0;
  std::string shard;
  std::string scene, model, explore = "none", noise;
  double sigma_r = 0.0, sigma_phi = 0.0;
  int schedule_steps = 0, sweeps = 0, working_memory = 0;
  std::uint64_t seed = 0;
  int poses = 0, shapelets = 0;
  double travel_m = std::numeric_limits<double>::quiet_NaN();  // NaN ("none"): not measured
  int whisks = 0;
  Evaluation accuracy;  // only the fields of kSweepColumns travel through the files
  long long proposals = 0;
  int peak_live_tables = 0, peak_live_legs = 0;
  double wall_s = 0.0;
  long process_peak_rss_kib = 0;
  // The explore run's curve (empty for "none"); not a column: it goes to curves.csv.
  std::vector<SweepCurvePoint> curve;
};

// The row of grid point `index` of `grid`, mapped into `stats` and evaluated as `accuracy`
// (travel_m NaN, whisks = stats.poses, no curve: the caller sets them for an explore point).
SweepRow sweepRow(const SweepGrid& grid, std::size_t index, const SweepShard& shard,
                  const MapStats& stats, const Evaluation& accuracy, double wall_s,
                  long process_peak_rss_kib);

// The files' text: a header line and one line per row; a JSON array, one-space indent.
std::string sweepRowsCsv(const std::vector<SweepRow>& rows);
std::string sweepRowsJson(const std::vector<SweepRow>& rows);
// sweep.json text back into rows. Errors name `source`: not a JSON array, or a row whose columns
// are not kSweepColumns with their types.
Result<std::vector<SweepRow>> parseSweepRows(const std::string& text, const std::string& source);

// Joins the sweep.json of each of `shard_dirs` into one list of rows in grid order, with the
// explore rows' curves read back from each shard's curves.csv. Errors (naming the directory or
// file): a directory without a sweep.json, rows of different grid fingerprints or sizes, a grid
// point twice or a grid point missing; a shard with explore rows without its curves.csv, or a
// curves.csv line that does not read or names a grid point its sweep.json lacks.
Result<std::vector<SweepRow>> mergeSweepShards(const std::vector<std::string>& shard_dirs);

// curves.csv's text (kCurveColumns): a header line and every explore row's curve points.
std::string sweepCurvesCsv(const std::vector<SweepRow>& rows);

// Writes out_dir/sweep.csv and out_dir/sweep.json (created if missing), each atomically, and
// out_dir/curves.csv when a row is an explore run (explore != "none").
Status writeSweepFiles(const std::vector<SweepRow>& rows, const std::string& out_dir);

}  // namespace crunch
