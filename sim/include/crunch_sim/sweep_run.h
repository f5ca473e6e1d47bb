// Running a sweep's grid points (`crunchhost sweep`; the grid, rows and files are
// mapping/sweep.h): each point is one simulated run (sim_run.h) with the gaussian sensor at the
// point's noise and settings, evaluated against its scene, on worker threads. A point of the
// explore axis is the driven run of `crunchhost --sim --explore NAME` with the grid's budgets
// (SimRunOptions::explore); its row carries the run's travel and whisks, and its
// recall-against-travel curve (SimRun::exploration->curve) for curves.csv.
//
// Determinism: a run draws only from its own seed, so the same grid point gives the same row
// whatever the job count, the shard or the completion order; only wall_s, process_peak_rss_kib
// (getrusage(RUSAGE_SELF).ru_maxrss when the row finished: the process's peak, shared by every
// run) and shard differ.
//
// Threads: `jobs` workers (0: one per core; never more than the points) take the shard's points
// in grid order. Each run's global chains get the cores the workers leave (MappingOptions::threads
// = max(1, cores / workers): 1 when the points fill the cores, all of them for a single point);
// that never changes a row. Each scene's World is built once and shared; the ODE collision scratch of this
// build is global (world.h), so every World query holds one mutex; inference, the bulk of a run,
// runs in parallel. `progress` is called under a lock after every point with (done, total).
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "crunch/exploration/exploration.h"
#include "crunch/mapping/sweep.h"

namespace crunch::sim {

struct SweepRunResult {
  std::vector<SweepRow> rows;  // the shard's points, in grid order
  int jobs = 1;                // worker threads used
};

// The settings of the grid's explore value `explore`: nullopt for "none" (the pose list,
// teleported); otherwise the policy named (exploration::explorePolicyByName) with the grid's
// travel and whisk budgets, checked by ExploreOptions::validate. Errors name --explore,
// --travel-budget or --whisk-budget.
Result<std::optional<exploration::ExploreOptions>> sweepExploreOptions(const SweepGrid& grid,
                                                                       const std::string& explore);
// Every explore value of the grid through sweepExploreOptions: `crunchhost sweep` checks this
// before it runs anything (mapping/sweep.h cannot: it does not link the exploration library).
Status validateSweepExplore(const SweepGrid& grid);

// Runs every point of `grid` that `shard` holds (after validateSweepExplore). An Error names the first grid point whose run
// failed ("grid point N: ...").
Result<SweepRunResult> runSweepPoints(const SweepGrid& grid, const SweepShard& shard, int jobs,
                                      const std::function<void(size_t, size_t)>& progress);

}  // namespace crunch::sim
