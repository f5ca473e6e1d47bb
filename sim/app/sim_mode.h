// `crunchhost --sim`: the simulated mapping run (ARCHITECTURE.md §4 command line). Wiring only:
// the options go to the simulator library's run (crunch_sim/sim_run.h: scene, ODE world, every
// reachable pose sensed, the blackboard, evaluation), which validates them; this writes
// OUT/map.json, OUT/map.png and OUT/report.json (crunch_sim/sim_report.h), and with --snapshot
// OUT/snapshot_K.{png,svg}.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>

#include "crunch/mapping/run_mapping.h"

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
  bool chain_fusion_given = false;  // --chain-fusion given (SimRunOptions::chain_fusion_given)
  // --snapshot K: also write OUT/snapshot_K.png and .svg, the blackboard (paper Figs. 3-4) after
  // the annealing of pose K, K the 0-based index in the run's order of reachable poses (the
  // scene's pose list without the unreachable ones; K < the "poses" count of report.json). A
  // pose that sensed nothing new does not anneal: its snapshot shows the blackboard as the last
  // annealing left it, with the robot at pose K. Out of range: exit 2, nothing written.
  std::optional<int> snapshot_pose;
  // --snapshot-temperature I: take the snapshot after the I-th temperature of pose K's
  // annealing (0 the hottest, beta = 1 ... schedule_steps - 1 the coldest; paper Fig. 4 is a
  // hot one) instead of at its end. Needs --snapshot; out of range: exit 2, nothing written.
  std::optional<int> snapshot_temperature;
  // --explore POLICY [--teleport] [--travel-budget M] [--whisk-budget N] [--start x,y,theta]
  // (docs/EXPLORATION.md): the robot chooses where to whisk. Unset: the scene's pose list,
  // teleported, as before. The budget and start flags need --explore; the library validates.
  std::optional<std::string> explore;
  bool teleport = false;
  std::optional<double> travel_budget;
  std::optional<int> whisk_budget;
  std::optional<std::string> start;
  // --serve ADDRESS (serve/serve_address.h, docs/LIVE_VIEW.md): a live view of the run over
  // HTTP while it runs. Checked before the run (a bad address: exit 2; one that cannot be
  // listened on: exit 3; nothing written either way). Never changes the map.
  std::optional<std::string> serve;
};

// Exit codes: 0 success; 2 bad input (scene, option) with nothing written; 1 failure to write;
// 3 the --serve address cannot be listened on (nothing run or written).
int runSim(const SimOptions& options, std::ostream& out, std::ostream& err);

}  // namespace crunch::app
