// `crunchhost sweep-merge DIR... [--out DIR]` (issue 6, "Sweeps"; docs/RESULTS.md "Sweeps"):
// joins the sweep.json of `sweep --shard` runs into out_dir/sweep.{csv,json} in grid order
// (crunch/mapping/sweep.h mergeSweepShards: no simulator needed).
// Exit codes: 0 success; 2 (nothing written) a directory without a sweep.json, rows of
// different grid fingerprints or sizes, a grid point twice or a grid point missing; 1 a failure
// to write.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

namespace crunch::app {

int runSweepMerge(const std::vector<std::string>& shard_dirs, const std::string& out_dir,
                  std::ostream& out, std::ostream& err);

}  // namespace crunch::app
