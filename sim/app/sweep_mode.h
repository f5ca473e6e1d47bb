// `crunchhost sweep` (issue 6, "Sweeps"; docs/RESULTS.md "Sweeps"): wiring only. The grid is
// the host library's (crunch/mapping/sweep.h: lists, validation, fingerprint, rows, files), its
// points run on worker threads in the simulator library (crunch_sim/sweep_run.h: each point one
// simulated run, crunch_sim/sim_run.h, as `--sim` runs it). `crunchhost sweep-merge` needs no
// simulator: host/app/sweep_merge.h.
//
// Output: OUT/sweep.csv and OUT/sweep.json (and OUT/curves.csv with --explore: every explore
// run's recall-against-travel curve, mapping/sweep.h), each written atomically after every run has
// finished, so an interrupted sweep leaves no partial file. Progress: a bar with the time left
// on `err`, or JSON lines on `out` with json_progress.
//
// Exit codes: 0 success; 2 bad input (an unknown scene file, a malformed list, a bad shard, an
// unknown --explore policy or a bad --travel-budget / --whisk-budget), with
// a message naming the option and nothing written; 1 a run or a write that failed.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "crunch/mapping/sweep.h"

namespace crunch::app {

struct SweepOptions {
  SweepGridSpec grid;          // the grid's lists as on the command line (mapping/sweep.h)
  std::string jobs;            // worker threads >= 1; empty or 0: hardware_concurrency()
  std::string shard;           // "i/n": only grid points with index % n == i; empty: all
  std::string out_dir = "out";
  bool json_progress = false;  // JSON progress lines on stdout instead of the bar on stderr
};

int runSweep(const SweepOptions& options, std::ostream& out, std::ostream& err);

}  // namespace crunch::app
