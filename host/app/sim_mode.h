// `crunchhost --sim`: the simulated mapping run (ARCHITECTURE.md §4 command line).
// Loads the scene (or the built-in default arena), builds the ODE world, senses every reachable
// pose, runs the blackboard, and writes OUT/map.json, OUT/map.png and OUT/report.json.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>

#include "crunch/mapping/pipeline.h"

namespace crunch::app {

struct SimOptions {
  std::optional<std::string> scene_path;  // empty: the built-in default arena
  std::string sensor_model = "gaussian";  // gaussian | ideal | physics
  std::string noise = "realistic";        // ideal | realistic | noisy
  uint64_t seed = 1;
  std::string out_dir = "out";
  // --sensor-model physics: the trained signal models (crunchhost train); empty: the shipped
  // models/sim_models.json of the source tree.
  std::string models_path;
  bool json_progress = false;  // one JSON object per line on stdout instead of a progress bar
  MappingOptions mapping;
};

// Exit codes: 0 success; 2 bad input (scene, option) with nothing written; 1 failure to write.
int runSim(const SimOptions& options, std::ostream& out, std::ostream& err);

}  // namespace crunch::app
