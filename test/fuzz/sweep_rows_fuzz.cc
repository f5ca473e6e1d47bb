// libFuzzer target for sweep.json (crunch/mapping/sweep.h, docs/RESULTS.md): parseSweepRows over
// arbitrary bytes, the reader behind sweep-merge and sweep-chart. Checks, beyond "no crash, no
// sanitizer report":
//   - a refused file's error names it;
//   - every accepted row is inside the writer's ranges: its grid point in its grid and in its
//     shard, fractions in [0, 1] or NaN, counts and costs >= 0, matched <= fused and true tables;
//   - the rows write back (sweepRowsJson) to text that reads again to the same text.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "crunch/mapping/sweep.h"
#include "fuzz_check.h"

namespace {
using fuzz::check;
bool fraction(double v) { return std::isnan(v) || (v >= 0.0 && v <= 1.0); }
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const auto rows = crunch::parseSweepRows(text, "fuzz/sweep.json");
  if (!rows.ok()) {
    check(rows.error().message.rfind("fuzz/sweep.json", 0) == 0);
    return 0;
  }
  for (const crunch::SweepRow& r : rows.value()) {
    check(r.grid_index < r.grid_size);
    const auto shard = crunch::parseSweepShard(r.shard);
    check(shard.ok() && shard.value().holds(r.grid_index));
    const crunch::Evaluation& e = r.accuracy;
    check(fraction(e.precision) && fraction(e.recall) && fraction(e.f1) &&
          fraction(e.per_pose_match_fraction));
    check(r.wall_s >= 0.0 && r.poses >= 0 && r.shapelets >= 0 && r.proposals >= 0);
    check(e.matched >= 0 && e.matched <= e.fused_tables && e.matched <= e.true_tables);
  }
  const std::string once = crunch::sweepRowsJson(rows.value());
  const auto again = crunch::parseSweepRows(once, "again.json");
  check(again.ok() && crunch::sweepRowsJson(again.value()) == once);
  return 0;
}
