// crunchhost: the CrunchBot host program (ARCHITECTURE.md §4 command line).
#include <CLI/CLI.hpp>
#include <iostream>

#include "sim_mode.h"
#include "train_mode.h"

int main(int argc, char** argv) {
  CLI::App app{"crunchhost: map table-like objects by touch with a whiskered robot"};
  app.set_version_flag("--version", "crunchhost 0.1.0");
  bool sim = false, robot = false;
  crunch::app::SimOptions opt;
  std::string scene;
  auto* mode_sim = app.add_flag("--sim", sim, "run the ODE simulator and map its world");
  auto* mode_robot = app.add_flag("--robot", robot, "run the real robot (USB whisker bridge + Create)");
  mode_sim->excludes(mode_robot);
  app.add_option("--scene", scene, "scene file (JSON, ARCHITECTURE.md §4); default: built-in arena")
      ->check(CLI::ExistingFile);
  app.add_option("--sensor-model", opt.sensor_model, "physics | gaussian | ideal")
      ->check(CLI::IsMember({"physics", "gaussian", "ideal"}))
      ->capture_default_str();
  app.add_option("--models", opt.models_path,
                 "signal models for --sensor-model physics (default: the shipped "
                 "models/sim_models.json)")
      ->check(CLI::ExistingFile);
  app.add_option("--noise", opt.noise, "ideal | realistic | noisy")
      ->check(CLI::IsMember({"ideal", "realistic", "noisy"}))
      ->capture_default_str();
  app.add_option("--seed", opt.seed, "seed of every random choice")->capture_default_str();
  app.add_option("--out", opt.out_dir, "output directory")->capture_default_str();
  app.add_flag("--json", opt.json_progress, "machine-readable progress on stdout");
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
  app.add_option("--global-chains", opt.mapping.global_chains,
                 "independent chains of the global inference; a table needs half to agree")
      ->capture_default_str();
  // `crunchhost train`: the paper's training protocols in the simulator (docs/TRAINING.md).
  crunch::app::TrainOptions train_opt;
  auto* train = app.add_subcommand(
      "train", "collect the paper's training contacts in the simulator, fit and evaluate the "
               "signal models, write them and the paper's figures (docs/TRAINING.md)");
  train->add_option("--out", train_opt.out_dir, "output directory")->capture_default_str();
  train->add_option("--seed", train_opt.seed, "seed of every jitter and sensor noise")
      ->capture_default_str();
  train->add_option("--models-out", train_opt.models_out,
                    "also write the models here (e.g. models/sim_models.json)");
  train->add_option("--radial-f1", train_opt.radial_f1,
                    "f1 of the saved radial lines: max (over the whisk, as the mapper takes "
                    "it) | first (the first pass)")
      ->check(CLI::IsMember({"max", "first"}))
      ->capture_default_str();
  train->add_flag("--json", train_opt.json_progress, "machine-readable progress on stdout");
  CLI11_PARSE(app, argc, argv);
  if (*train) {
    if (sim || robot) {
      std::cerr << "crunchhost: train is a mode of its own: drop --sim/--robot\n";
      return 2;
    }
    return crunch::app::runTrain(train_opt, std::cout, std::cerr);
  }

  if (robot) {
    std::cerr << "crunchhost: --robot: the USB whisker bridge and Create drivers are not built yet "
                 "(issue 5); nothing was opened\n";
    return 2;
  }
  if (!sim) {
    std::cerr << "crunchhost: choose a mode: --sim or --robot (see --help)\n";
    return 2;
  }
  if (!scene.empty()) opt.scene_path = scene;
  return crunch::app::runSim(opt, std::cout, std::cerr);
}
