// `crunchhost sweep` (issue 6, "Sweeps"; docs/RESULTS.md "Sweeps"): wiring only. The grid is
// the host library's (crunch/mapping/sweep.h: lists, validation, fingerprint, rows, files), its
// points run on worker threads in the simulator library (crunch_sim/sweep_run.h: each point one
// simulated run, crunch_sim/sim_run.h, as `--sim` runs it). `crunchhost sweep-merge` needs no
// simulator: host/app/sweep_merge.h.
//
// Output: OUT/sweep.csv and OUT/sweep.json, each written atomically after every run has
// finished, so an interrupted sweep leaves no partial file. Progress: a bar with the time left
// on `err`, or JSON lines on `out` with json_progress.
//
// Exit codes: 0 success; 2 bad input (an unknown scene file, a malformed list, a bad shard), with
// a message naming the option and nothing written; 1 a run or a write that failed.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace crunch::app {

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

}  // namespace crunch::app
