// crunchhost: the CrunchBot host program (ARCHITECTURE.md §4 command line). Parsing and wiring
// only: each mode's options are set up by one function below and handed to the mode, which
// calls the library. The simulator modes (--sim, sweep, train) live in sim/app/ (crunch_sim_app)
// and are included by plain name; nothing here includes the simulator's headers.
#include <CLI/CLI.hpp>
#include <iostream>

#include "crunch/core/atomic_file.h"
#include "crunch/exploration/policy.h"
#include "crunch/session/export.h"
#include "robot_mode.h"
#include "sim_mode.h"
#include "sweep_chart.h"
#include "sweep_merge.h"
#include "sweep_mode.h"
#include "train_mode.h"

namespace {

using namespace crunch::app;

// The mode flags and the options --sim and --robot share.
struct TopLevel {
  bool sim = false, robot = false;
  std::string replay;
  std::string scene;
  SimOptions sim_opt;  // --sim's options; --robot takes the shared ones from it
};

void addModes(CLI::App& app, TopLevel& t) {
  auto* mode_sim = app.add_flag("--sim", t.sim, "run the ODE simulator and map its world");
  auto* mode_robot =
      app.add_flag("--robot", t.robot, "run the real robot (USB whisker bridge + Create)");
  mode_sim->excludes(mode_robot);
  auto* mode_replay = app.add_option("--replay", t.replay,
                                     "re-run a recording of --robot offline (same map)")
                          ->check(CLI::ExistingFile);
  mode_replay->excludes(mode_sim)->excludes(mode_robot);
}

// --robot (robot_mode.h, docs/ROBOT.md).
void addRobotOptions(CLI::App& app, RobotOptions& ropt) {
  auto* robot_opts = app.add_option_group("robot", "options of --robot");
  robot_opts->add_option("--usb", ropt.usb, "USB id VID:PID of the whisker bridge")
      ->capture_default_str();
  robot_opts->add_option("--create", ropt.create, "serial port of the iRobot Create")
      ->capture_default_str();
  robot_opts->add_option("--duration", ropt.duration_s, "seconds to run (0: until Ctrl-C)")
      ->capture_default_str();
  robot_opts->add_option("--record", ropt.record_path,
                         "recording file (default OUT/recording.crec)");
  robot_opts->add_flag("!--no-record", ropt.record, "do not record the raw input");
  robot_opts->add_option("--map-every", ropt.map_every_s, "seconds between map writes")
      ->capture_default_str();
  robot_opts->add_option("--area-width", ropt.area_width, "width of the mapped area, m")
      ->capture_default_str();
  robot_opts->add_option("--area-depth", ropt.area_depth, "depth of the mapped area, m")
      ->capture_default_str();
  robot_opts->add_option("--start-x", ropt.start_x, "start x in the map, m (default: centre)");
  robot_opts->add_option("--start-y", ropt.start_y, "start y in the map, m (default: centre)");
  robot_opts->add_option("--start-theta", ropt.start_theta, "start heading in the map, rad")
      ->capture_default_str();
  robot_opts->add_flag("--full-mode", ropt.create_full_mode,
                       "OI Full mode (no cliff/wheel-drop stop by the Create itself)");
  robot_opts->add_flag("!--checksum-per-manual", ropt.checksum_includes_header,
                       "the Create's checksum excludes the header byte, as its manual says "
                       "(default: includes it, as the Create 1 does)");
}

// --sim's own options (sim_mode.h).
void addSimOptions(CLI::App& app, TopLevel& t) {
  SimOptions& opt = t.sim_opt;
  app.add_option("--scene", t.scene, "scene file (JSON, ARCHITECTURE.md §4); default: built-in arena")
      ->check(CLI::ExistingFile);
  app.add_option("--sensor-model", opt.sensor_model, "physics | gaussian | ideal")
      ->check(CLI::IsMember({"physics", "gaussian", "ideal"}))
      ->capture_default_str();
  app.add_option("--noise", opt.noise, "ideal | realistic | noisy")
      ->check(CLI::IsMember({"ideal", "realistic", "noisy"}))
      ->capture_default_str();
  app.add_option("--snapshot", opt.snapshot_pose,
                 "also write OUT/snapshot_K.{png,svg}: the blackboard after the annealing of "
                 "pose K (0-based, in the run's order of reachable poses), like the paper's "
                 "Figs. 3-4");
  app.add_option("--snapshot-temperature", opt.snapshot_temperature,
                 "with --snapshot: after the I-th temperature of pose K's annealing (0 the "
                 "hottest ... schedule-steps - 1 the coldest) instead of at its end (Fig. 4)");
  app.add_option("--explore", opt.explore,
                 "the robot chooses where to whisk: grid | random | frontier | entropy | "
                 "infogain (default: the scene's pose list, teleported; docs/EXPLORATION.md)");
  app.add_flag("--teleport", opt.teleport,
               "with --explore: jump between whisk poses (the paper's idealisation) instead of "
               "driving");
  app.add_option("--travel-budget", opt.travel_budget, "with --explore: stop after M metres");
  app.add_option("--whisk-budget", opt.whisk_budget, "with --explore: stop after N whisks");
  app.add_option("--start", opt.start,
                 "with --explore: start pose x,y,theta (default: the first reachable pose of "
                 "the scene's list)");
}

// The options --sim and --robot share: models, seed, output, progress and the mapping settings.
void addSharedOptions(CLI::App& app, SimOptions& opt) {
  app.add_option("--models", opt.models_path,
                 "signal models for --sensor-model physics (default: the shipped "
                 "models/sim_models.json)")
      ->check(CLI::ExistingFile);
  // A negative seed would wrap to 2^64 - 1 in the conversion: refused as the contract's exit 2.
  app.add_option("--seed", opt.seed, "seed of every random choice")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--out", opt.out_dir, "output directory")->capture_default_str();
  app.add_flag("--json", opt.json_progress, "machine-readable progress on stdout");
  app.add_option("--serve", opt.serve,
                 "serve a live view of the run (map, pose, path, contacts, counters) at "
                 "ADDRESS: PORT or HOST:PORT or [IPV6]:PORT; PORT alone listens on loopback "
                 "127.0.0.1 (this machine only); read-only: GET /, /state.json, /events "
                 "(docs/LIVE_VIEW.md)")
      ->type_name("ADDRESS");
  auto& s = opt.mapping.sampler;
  app.add_option("--schedule-steps", s.schedule_steps, "annealing temperatures")
      ->capture_default_str();
  app.add_option("--sweeps", s.sweeps_per_temperature, "sweeps per temperature")
      ->capture_default_str();
  app.add_option("--working-memory", opt.mapping.working_memory, "shapelets in working memory")
      ->capture_default_str();
  app.add_flag("!--no-smart-proposals", s.smart_parent,
               "use the paper's blind proposals (uniform table placements, no corner fit)");
  app.add_option("--smart-gain", s.smart_parent_gain,
                 "weight added per leg already at a placement's other corners")
      ->capture_default_str();
  app.add_option("--min-support", opt.mapping.fuse.min_support,
                 "per-pose MAPs that must agree for a fused table")
      ->capture_default_str();
  app.add_option("--global-sweeps", opt.mapping.global_sweeps,
                 "fused map by one annealing over all shapelets (sweeps per temperature; 0: "
                 "cluster the per-pose MAPs)")
      ->capture_default_str();
  app.add_option_function<std::string>(
         "--model",
         [&opt](const std::string& name) {
           const auto model = crunch::objectModelByName(name);
           if (!model) throw CLI::ValidationError("--model", model.error().message);
           opt.mapping.model.objects = model.value();
         },
         "objects the map may hold: paper (one table size, no walls; the paper's figures) | "
         "walls (the paper's table and walls) | rooms (walls, four-legged objects of any size)")
      ->default_str(crunch::objectModelName(crunch::defaultMappingModel().objects));
  app.add_option_function<std::string>(
         "--chain-fusion",
         [&opt](const std::string& name) {
           const auto f = crunch::chainFusionByName(name);
           if (!f) throw CLI::ValidationError("--chain-fusion", f.error().message);
           opt.mapping.chain_fusion = f.value();
           opt.chain_fusion_given = true;
         },
         "how the global chains become the map (default: pool for the physics sensor and --robot --explore, "
         "else vote): vote (a table half the chains end with) | "
         "pool (one more chain over their tables) | marginal (posterior probability from the "
         "samples of every chain's coldest --marginal-steps temperatures, kept above 0.5)")
      ->default_str("vote");
  app.add_option("--marginal-steps", opt.mapping.marginal_steps,
                 "--chain-fusion marginal: coldest temperatures whose sweeps are samples")
      ->capture_default_str();
  app.add_option_function<std::string>(
         "--acceptance",
         [&opt](const std::string& name) {
           const auto a = crunch::acceptanceByName(name);
           if (!a) throw CLI::ValidationError("--acceptance", a.error().message);
           opt.mapping.sampler.acceptance = a.value();
         },
         "move acceptance: paper (the annealed Gibbs conditional of eq. 29, no proposal "
         "ratio) | rj (reversible-jump Metropolis-Hastings with every move's proposal ratio, "
         "any --model; docs/BLACKBOARD.md)")
      ->default_str("paper");
  app.add_option_function<int>(
         "--global-chains",
         [&opt](int n) {
           opt.mapping.global_chains = n;
           opt.global_chains_given = true;
         },
         "independent chains of the global inference (default: 32 for the physics sensor and --robot "
         "--explore, else 8); a table needs half to agree (vote)")
      ->default_str("8");
  app.add_option("--threads", opt.mapping.threads,
                 "threads the global inference's chains run on (0: one per core); the map is "
                 "the same for every count")
      ->capture_default_str();
}

// `crunchhost train`: the paper's training protocols in the simulator (docs/TRAINING.md).
CLI::App* addTrain(CLI::App& app, TrainOptions& o) {
  auto* train = app.add_subcommand(
      "train", "collect the paper's training contacts in the simulator, fit and evaluate the "
               "signal models, write them and the paper's figures (docs/TRAINING.md)");
  train->add_option("--out", o.out_dir, "output directory")->capture_default_str();
  train->add_option("--seed", o.seed, "seed of every jitter and sensor noise")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  train->add_option("--models-out", o.models_out,
                    "also write the models here (e.g. models/sim_models.json)");
  train->add_option("--radial-f1", o.radial_f1,
                    "f1 of the saved radial lines: max (over the whisk, as the mapper takes "
                    "it) | first (the first pass)")
      ->check(CLI::IsMember({"max", "first"}))
      ->capture_default_str();
  train->add_flag("--json", o.json_progress, "machine-readable progress on stdout");
  return train;
}

// `crunchhost sweep` (sweep_mode.h, docs/RESULTS.md "Sweeps").
CLI::App* addSweep(CLI::App& app, SweepOptions& o) {
  auto* sweep = app.add_subcommand(
      "sweep", "map a grid of scenes x noise x sampler budgets x seeds with the gaussian (fast, "
               "ray-cast) sensor model, one row per run in OUT/sweep.csv and OUT/sweep.json "
               "(docs/RESULTS.md)");
  sweep->add_option("--scene", o.grid.scenes,
                    "scene file, repeatable; the word 'default' is the built-in arena "
                    "(default: default)");
  sweep->add_option("--model", o.grid.models,
                    "object models, e.g. paper,rooms (default: paper; see --sim --model)");
  sweep->add_option("--noise", o.grid.noise, "noise regimes, e.g. ideal,realistic,noisy");
  sweep->add_option("--noise-scale", o.grid.noise_scale,
                    "noise as multiples of realistic (sigma_r 5 mm, sigma_phi pi/32), e.g. "
                    "0.5,1,2,5,10 (neither: realistic)");
  sweep->add_option("--schedule-steps", o.grid.schedule_steps,
                    "annealing temperatures, e.g. 4,8,16 (default 16)");
  sweep->add_option("--sweeps", o.grid.sweeps, "sweeps per temperature, e.g. 1,2,4 (default 1)");
  sweep->add_option("--working-memory", o.grid.working_memory,
                    "shapelets in working memory, e.g. 7,14 (default 7)");
  sweep->add_option("--seeds", o.grid.seeds, "N: seeds 1..N (default 1)");
  sweep->add_option("--seed-list", o.grid.seed_list, "explicit seeds, e.g. 3,7,11");
  sweep->add_option("--chain-fusion", o.grid.chain_fusion,
                    "vote | pool | marginal, for every point (default vote)");
  sweep->add_option("--acceptance", o.grid.acceptance,
                    "paper | literal | rj, for every point (default paper)");
  sweep->add_option("--explore", o.grid.explore,
                    "exploration policies, e.g. grid,random,frontier,entropy,infogain: each "
                    "point is the driven run of --sim --explore NAME; 'none' is the pose list "
                    "teleported (default: none); curves in OUT/curves.csv");
  sweep->add_option("--travel-budget", o.grid.travel_budget,
                    "metres each explore run may drive (default: no limit)");
  sweep->add_option("--whisk-budget", o.grid.whisk_budget,
                    "whisks each explore run may make (default: no limit)");
  sweep->add_option("--jobs", o.jobs, "worker threads (default: one per core)");
  sweep->add_option("--shard", o.shard,
                    "i/n: run only grid points with index % n == i (e.g. a Slurm array task)");
  sweep->add_option("--out", o.out_dir, "output directory")->capture_default_str();
  sweep->add_flag("--json", o.json_progress, "JSON progress lines on stdout");
  return sweep;
}

struct MergeOptions {
  std::vector<std::string> dirs;
  std::string out = "out";
};

// `crunchhost sweep-merge` (sweep_merge.h).
CLI::App* addSweepMerge(CLI::App& app, MergeOptions& o) {
  auto* merge = app.add_subcommand(
      "sweep-merge", "join the sweep.csv/json of `sweep --shard` runs into one, in grid order");
  merge->add_option("dirs", o.dirs, "output directories of the shards")->required();
  merge->add_option("--out", o.out, "output directory")->capture_default_str();
  return merge;
}

// `crunchhost sweep-chart` (sweep_chart.h, docs/RESULTS.md "Charts").
CLI::App* addSweepChart(CLI::App& app, SweepChartOptions& o) {
  auto* chart = app.add_subcommand(
      "sweep-chart", "draw a sweep's accuracy-against-cost (Pareto) and accuracy-against-noise "
                     "charts, PNG and SVG, from DIR/sweep.json");
  chart->add_option("--in", o.in_dir, "directory holding sweep.json")->required();
  chart->add_option("--out", o.out_dir, "output directory (default: --in)");
  return chart;
}

// `crunchhost export` (session/export.h, docs/EXPORT.md): the library validates every setting.
CLI::App* addExport(CLI::App& app, crunch::session::ExportOptions& o) {
  auto* exp = app.add_subcommand(
      "export", "write a map or a recording in formats other tools read: ros-map (map.json -> "
                "map.pgm + map.yaml for ROS map_server / nav2_map_server) | csv (a recording -> "
                "samples.csv, contacts.csv, odometry.csv) (docs/EXPORT.md)");
  exp->add_option("--format", o.format, "ros-map | csv")->required();
  exp->add_option("--in", o.in, "input: OUT/map.json (ros-map) or a recording .crec (csv)")
      ->required();
  exp->add_option("--out", o.out_dir, "output directory (created if missing)")->required();
  exp->add_option("--resolution", o.ros.resolution,
                  "ros-map: metres per cell, 0.001 to 1")
      ->capture_default_str();
  exp->add_flag("--tops-occupied", o.ros.tops_occupied,
                "ros-map: table tops occupied too (default: only legs and walls; the Create "
                "drives under table tops)");
  return exp;
}

int runExportMode(crunch::session::ExportOptions& o, const CLI::App& exp) {
  o.resolution_given = exp.count("--resolution") > 0;
  o.tops_given = exp.count("--tops-occupied") > 0;
  const auto r = crunch::session::runExport(o);
  (r.exit_status == 0 ? std::cout : std::cerr) << "crunchhost export: " << r.summary << "\n";
  return r.exit_status;
}

// --replay, --robot or --sim, with the options they share.
int runTopLevel(TopLevel& t, RobotOptions& ropt) {
  SimOptions& opt = t.sim_opt;
  if (!t.replay.empty()) {
    ReplayOptions rp;
    rp.recording = t.replay;
    rp.out_dir = opt.out_dir;
    rp.json_progress = opt.json_progress;
    rp.threads = opt.mapping.threads;  // the machine's, not the recording's
    return runReplay(rp, std::cout, std::cerr);
  }
  if (t.robot) {
    // --explore on the robot: the same policies and budgets as --sim (the library validates
    // them, planRobot); a real robot cannot teleport, and its start is --start-x/-y/-theta.
    if (opt.teleport || opt.start) {
      std::cerr << "crunchhost: " << (opt.teleport ? "--teleport" : "--start")
                << ": not with --robot (a real robot drives; its start pose in the map is "
                   "--start-x, --start-y, --start-theta)\n";
      return 2;
    }
    auto explore = crunch::exploration::exploreOptionsFromFlags(opt.explore, opt.travel_budget,
                                                                opt.whisk_budget);
    if (!explore) {
      std::cerr << "crunchhost: " << explore.error().message << "\n";
      return 2;
    }
    ropt.explore = explore.value();
    ropt.out_dir = opt.out_dir;
    ropt.seed = opt.seed;
    ropt.models_path = opt.models_path;
    ropt.json_progress = opt.json_progress;
    ropt.mapping = opt.mapping;
    ropt.chain_fusion_given = opt.chain_fusion_given;
    ropt.global_chains_given = opt.global_chains_given;
    ropt.serve = opt.serve;
    return runRobot(ropt, std::cout, std::cerr);
  }
  if (!t.sim) {
    std::cerr << "crunchhost: choose a mode: --sim, --robot or --replay FILE (see --help)\n";
    return 2;
  }
  if (!t.scene.empty()) opt.scene_path = t.scene;
  return runSim(opt, std::cout, std::cerr);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"crunchhost: map table-like objects by touch with a whiskered robot"};
  app.set_version_flag("--version", "crunchhost 0.1.0");
  app.footer(
      "Exit status (ARCHITECTURE.md §4):\n"
      "  0  success\n"
      "  1  an output could not be written (e.g. disk full): no output is left half-written\n"
      "  2  bad input or setting: the file, field or option is named; nothing is written\n"
      "  3  a device missing or a recording damaged: what was replayed is written, and said so;\n"
      "     or the --serve address cannot be listened on (in use): nothing run or written\n"
      "A SIGINT or SIGTERM before the end leaves no output (--robot: ends the run and writes it).");
  TopLevel top;
  RobotOptions ropt;
  TrainOptions train_opt;
  SweepOptions sweep_opt;
  MergeOptions merge_opt;
  SweepChartOptions chart_opt;
  crunch::session::ExportOptions export_opt;
  addModes(app, top);
  addRobotOptions(app, ropt);
  addSimOptions(app, top);
  addSharedOptions(app, top.sim_opt);
  CLI::App* train = addTrain(app, train_opt);
  CLI::App* sweep = addSweep(app, sweep_opt);
  CLI::App* sweep_merge = addSweepMerge(app, merge_opt);
  CLI::App* sweep_chart = addSweepChart(app, chart_opt);
  CLI::App* export_cmd = addExport(app, export_opt);
  // The contract's exit codes (ARCHITECTURE.md §4): a command line CLI11 cannot parse is bad
  // input, exit 2 (CLI11's own codes are 100 and up); --help and --version exit 0.
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  // From here on a signal that ends the process removes every output's temporary first.
  crunch::removeTempsOnSignals();
  const bool top_mode = top.sim || top.robot || !top.replay.empty();
  if (top.sim_opt.serve && !top.sim && !top.robot) {
    std::cerr << "crunchhost: --serve: only with --sim or --robot (the live view of a run)\n";
    return 2;
  }
  if (*export_cmd) {
    if (top_mode) {
      std::cerr << "crunchhost: export is a mode of its own: drop --sim/--robot/--replay\n";
      return 2;
    }
    return runExportMode(export_opt, *export_cmd);
  }
  if (*sweep || *sweep_merge || *sweep_chart) {
    if (top_mode) {
      std::cerr << "crunchhost: sweep is a mode of its own: drop --sim/--robot/--replay\n";
      return 2;
    }
    if (*sweep_chart) return runSweepChart(chart_opt, std::cout, std::cerr);
    if (*sweep_merge) return runSweepMerge(merge_opt.dirs, merge_opt.out, std::cout, std::cerr);
    return runSweep(sweep_opt, std::cout, std::cerr);
  }
  if (*train) {
    if (top.sim || top.robot) {
      std::cerr << "crunchhost: train is a mode of its own: drop --sim/--robot\n";
      return 2;
    }
    return runTrain(train_opt, std::cout, std::cerr);
  }
  return runTopLevel(top, ropt);
}
