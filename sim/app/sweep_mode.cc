#include "sweep_mode.h"

#include <chrono>
#include <nlohmann/json.hpp>
#include <ostream>

#include "crunch/mapping/sweep.h"
#include "crunch_sim/sweep_run.h"
#include "progress.h"

namespace crunch::app {

namespace {

void printDone(const SweepOptions& opt, const SweepGrid& g, const SweepShard& shard,
               const sim::SweepRunResult& r, double total_s, std::ostream& out) {
  if (opt.json_progress) {
    nlohmann::ordered_json j;
    j["event"] = "done";
    j["runs"] = r.rows.size();
    j["grid_size"] = g.size();
    j["grid"] = g.fingerprint;
    j["shard"] = shard.name();
    j["wall_s"] = total_s;
    j["out"] = opt.out_dir;
    out << j.dump() << "\n";
    return;
  }
  out << "sweep " << g.fingerprint << ": " << r.rows.size() << " of " << g.size()
      << " grid points (shard " << shard.name() << ") on " << r.jobs << " threads in "
      << formatDuration(total_s) << "; wrote " << opt.out_dir << "/{sweep.csv,sweep.json"
      << (g.explores == std::vector<std::string>{"none"} ? "" : ",curves.csv") << "}\n";
}

}  // namespace

int runSweep(const SweepOptions& opt, std::ostream& out, std::ostream& err) {
  const auto t0 = std::chrono::steady_clock::now();
  auto grid = buildSweepGrid(opt.grid);
  if (!grid) {
    err << "crunchhost sweep: " << grid.error().message << "\n";
    return 2;
  }
  if (Status s = sim::validateSweepExplore(grid.value()); !s) {
    err << "crunchhost sweep: " << s.error().message << "\n";
    return 2;
  }
  auto shard = parseSweepShard(opt.shard);
  auto jobs = parseSweepJobs(opt.jobs);
  if (!shard || !jobs) {
    err << "crunchhost sweep: " << (shard ? jobs.error() : shard.error()).message << "\n";
    return 2;
  }
  size_t points = 0;
  for (size_t i = 0; i < grid.value().size(); ++i) points += shard.value().holds(i) ? 1 : 0;
  RunProgress progress(opt.json_progress ? out : err, opt.json_progress, points);
  auto run = sim::runSweepPoints(grid.value(), shard.value(), jobs.value(),
                                 [&progress](size_t done, size_t) { progress(done); });
  if (!run) {
    err << "crunchhost sweep: " << run.error().message << "\n";
    return 1;
  }
  if (Status s = writeSweepFiles(run.value().rows, opt.out_dir); !s) {
    err << "crunchhost: " << s.error().message << "\n";
    return 1;
  }
  const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  printDone(opt, grid.value(), shard.value(), run.value(), total_s, out);
  return 0;
}

}  // namespace crunch::app
