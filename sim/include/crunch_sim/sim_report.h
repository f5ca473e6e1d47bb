// report.json of `crunchhost --sim` (ARCHITECTURE.md §4): schema "crunch.report/1", the scene,
// sensor model, noise regime and seed, accuracy against the scene (mapping/report_json.h), the
// run's counts and timings, and for the physics sensor its measured report errors beside the
// gaussian run on the same scene; then eq. 12's model sigmas and the sampler settings.
#pragma once

#include <string>

#include "crunch_sim/sim_run.h"

namespace crunch::sim {

// The report.json text (2-space indent, keys in a fixed order) of `run` on `scene`, run with
// `options`; total_s is the whole command's wall time.
std::string simReportJson(const Scene& scene, const SimRun& run, const SimRunOptions& options,
                          double total_s);

}  // namespace crunch::sim
