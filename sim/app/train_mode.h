// `crunchhost train`: the paper's training protocols in the simulator (§2.4-2.5), the fitted
// models, their evaluation (Table 1, Figs. 9-10) and the figures (docs/TRAINING.md).
//
//   crunchhost train [--out DIR] [--seed N] [--models-out FILE] [--radial-f1 max|first] [--json]
//
// Wiring only: collects the radial and orientation contacts with sim::collectTrainingData
// (crunch_sim/training.h), fits and evaluates the models and draws the figures with
// crunch_sim/training_report.h (eq. 2 per whisker on the radial training set, scored on the
// held-out set; the orientation templates cross-validated leave-one-repeat-out and trained on
// every repeat), then writes
//   DIR/models.json            the signal models (models_io.h), also copied to --models-out
//   DIR/training_report.json   every number: options, per-contact data, both distance labels,
//                              every radial variant, per-angle errors, counts, timings
//   DIR/fig9_peak_deflection.{png,svg}, DIR/table1_radial_sigma.{png,svg},
//   DIR/fig10_orientation_error.{png,svg}
// Progress: a bar with the estimated time left on `err`, or with json_progress one JSON object
// per line on `out` ({"event":"progress",...}, then {"event":"done",...}).
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>

#include "crunch_sim/training.h"

namespace crunch::app {

struct TrainOptions {
  std::string out_dir = "out/train";
  std::uint64_t seed = 1;
  std::string models_out;         // empty: only DIR/models.json
  std::string radial_f1 = "first";  // which f1 the saved radial lines use: first | max
  bool json_progress = false;
  // The protocol; its seed and progress are set from the fields above. Tests shrink it.
  sim::TrainingOptions protocol;
};

// Exit codes: 0 success; 2 bad options or an output that cannot be written (checked before
// anything is collected: nothing is written then); 1 a failure after collection (a fit that
// cannot be made, a file that cannot be written: the files before it are complete, none is
// half-written).
int runTrain(const TrainOptions& options, std::ostream& out, std::ostream& err);

}  // namespace crunch::app
