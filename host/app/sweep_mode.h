// `crunchhost sweep` and `crunchhost sweep-merge` (issue 6, "Sweeps"; docs/RESULTS.md "Sweeps").
//
// A sweep is the grid scenes x noise x schedule_steps x sweeps x working_memory x seeds; each grid
// point is one `--sim` run with the gaussian (ray-cast) sensor model — the fast one; the physics
// sensor is not swept — built exactly as sim_mode.cc builds it (scene, World, reachable poses,
// RaySensorModel at the noise regime, eq. 12's shapelet sigmas never below the regime's, default
// MappingOptions otherwise, runMapping, evaluate). Grid order, the order of the rows: scene
// (slowest), noise (the named regimes, then the scales), schedule_steps, sweeps, working_memory,
// seed (fastest); a point's grid_index is its position in that order.
//
// Output: OUT/sweep.csv and OUT/sweep.json (a JSON array of objects with the same columns, in
// the same order, with the same values: CSV numbers are the JSON numbers' text), each written
// atomically after every run has finished, so an interrupted sweep leaves no partial file.
// Columns (kSweepColumns): the grid fingerprint (a 64-bit FNV-1a hash, hex, of the grid
// description: every scene's argument and file content, the noise sigmas, the budget lists, the
// seeds and the fixed mapping options), grid_index, grid_size, shard ("i/n", "0/1" unsharded),
// the point's settings, accuracy (Evaluation), cost (proposals, the mapping's high-water marks
// MapStats::peak_live_tables / peak_live_legs, wall_s of the run's sensing + inference +
// evaluation) and process_peak_rss_kib: getrusage(RUSAGE_SELF).ru_maxrss when the row finished.
// That last column is the PROCESS's peak resident set so far, shared by every run of the process
// (and by the other --jobs threads): it is not a per-run figure and only grows down the rows.
//
// Determinism: a run draws only from its own seed (runMapping's sensor and sampler streams), so
// the same grid point gives the same row whatever --jobs, --shard or the completion order;
// only wall_s, process_peak_rss_kib and shard differ.
//
// Threads: --jobs worker threads take grid points in order. The ODE collision scratch of this
// build is global (crunch_sim/world.h), so every World query (sensing) holds one process-wide
// mutex; inference, the bulk of a run, runs in parallel.
//
// Exit codes: 0 success; 2 bad input (an unknown scene file, a malformed list, a bad shard, a
// merge of shards of different grids or with duplicate or missing points), with a message naming
// the option or directory and nothing written; 1 a failure to write.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace crunch::app {

// The columns of sweep.csv / keys of every sweep.json object, in order.
extern const std::vector<std::string> kSweepColumns;

struct SweepOptions {
  // Scene files; the word "default" is the built-in arena. Empty: {"default"}.
  std::vector<std::string> scenes;
  // The lists exactly as on the command line, comma-separated; empty text = the default.
  std::string noise;           // ideal,realistic,noisy names (default: realistic, if no scale)
  std::string noise_scale;     // multiples of realistic's sigma_r = 5 mm and sigma_phi = pi/32
  std::string schedule_steps;  // SamplerOptions::schedule_steps values (default 16)
  std::string sweeps;          // SamplerOptions::sweeps_per_temperature values (default 1)
  std::string working_memory;  // MappingOptions::working_memory values (default 7)
  std::string seeds;           // N >= 1: seeds 1..N
  std::string seed_list;       // explicit seeds (excludes seeds); neither: seed 1
  std::string jobs;            // worker threads >= 1; empty or 0: hardware_concurrency()
  std::string shard;           // "i/n": only grid points with index % n == i; empty: all
  std::string out_dir = "out";
  bool json_progress = false;  // JSON progress lines on stdout instead of the bar on stderr
};

int runSweep(const SweepOptions& options, std::ostream& out, std::ostream& err);

// Joins the sweep.json of each of `shard_dirs` into out_dir/sweep.{csv,json} in grid order.
// Refuses (exit 2, nothing written) directories without a sweep.json, rows of different grid
// fingerprints or sizes, a grid point twice or a grid point missing.
int runSweepMerge(const std::vector<std::string>& shard_dirs, const std::string& out_dir,
                  std::ostream& out, std::ostream& err);

}  // namespace crunch::app
