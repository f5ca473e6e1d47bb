// `crunchhost train`'s fitting, evaluation and outputs (paper §2.4-2.5; docs/TRAINING.md): from
// the data of collectTrainingData (training.h), fit eq. 2 per whisker on the radial training set
// and score it on the held-out set (every RadialVariant), cross-validate the orientation
// templates leave-one-repeat-out and train the final templates on every repeat; then draw the
// paper's figures against its numbers and write training_report.json.
//
// Figures (chart.h, PNG and SVG): fig9_peak_deflection (Fig. 9: peak deflection f1 against the
// true radial distance, with the eq. 2 lines), table1_radial_sigma (Table 1: held-out sigma of r
// per whisker and all together, beside the paper's), fig10_orientation_error (Fig. 10: the
// orientation error per class angle, beside the paper's mean and sd, and the faces located from
// two whiskers' ramps beside them), and with the ramp protocol (issue 12) ramp_distance (the
// ramp's distance against the true distance over the whole whisker, eq. 2 beside it) and
// table1_ramp_sigma (Table 1 re-measured: the ramp nominal and fitted, eq. 2, the paper).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "crunch/render/chart.h"
#include "crunch/signal/models_io.h"
#include "crunch/signal/orientation_templates.h"
#include "crunch_sim/training.h"

namespace crunch::sim {

// The paper's numbers: Table 1 (mm, per whisker and "Combo") and Fig. 10 (degrees).
inline constexpr double kPaperSigmaMm[4] = {2.78, 1.82, 4.37, 5.68};
inline constexpr double kPaperComboMm = 4.98;
inline constexpr double kPaperMeanDeg = -2.2;
inline constexpr double kPaperSdDeg = 21.2;

// `--radial-f1`: "max" (over the whisk, as the mapper takes it) or "first" (the first pass). An
// Error naming --radial-f1 and the choices otherwise.
Result<F1Source> f1SourceByName(const std::string& name);

struct TrainingFit {
  std::vector<RadialEvaluation> variants;  // allRadialVariants() order; [0]: max, f1, truth
  F1Source saved_source = F1Source::kFirstEpisode;
  std::size_t saved = 0;       // the variant whose lines are saved: f1 of saved_source, truth
  std::size_t first_pass = 0;  // f1 of the first pass, truth (Table 1's third bars)
  signal::CrossValidation cv;  // leave one repeat out (Fig. 10)
  // The ramp calibration and its evaluation (when the data has ramp contacts; otherwise the
  // saved calibration is nominal), and Fig. 10 with faces located by the saved models.
  bool has_ramp = false;
  RampEvaluation ramp;
  FaceEvaluation faces;
  // The saved lines, the final templates, the rig's pipeline, the ramp calibration.
  signal::SignalModels models;
};

// Fits and evaluates everything. Errors: a radial fit that cannot be made, an orientation
// cross-validation or training that fails ("orientation cross-validation: ...",
// "orientation templates: ..."), or fitted models that do not validate.
Result<TrainingFit> fitTrainingModels(const TrainingData& data, const TrainingOptions& protocol,
                                      F1Source saved);

Chart fig9Chart(const std::vector<RadialContact>& contacts, const RadialEvaluation& saved);
Chart table1Chart(const RadialEvaluation& protocol, const RadialEvaluation& first_pass);
Chart fig10Chart(const signal::CrossValidation& cv, const FaceEvaluation* faces = nullptr);
Chart rampDistanceChart(const TrainingData& data, const TrainingFit& fit);
Chart table1RampChart(const TrainingFit& fit);

// Writes the figures into `dir` (PNG, then SVG, each atomically), stopping at the first
// failure, whose Error names the file.
Status writeTrainingFigures(const std::string& dir, const TrainingData& data,
                            const TrainingFit& fit);

// training_report.json (1-space indent): the command, seed and timing, the rig's pipeline, the
// detector threshold's evidence, and for radial distance and orientation the protocol, counts,
// every variant or cross-validation result, the paper's numbers and every contact.
std::string trainingReportJson(const TrainingOptions& protocol, const TrainingData& data,
                               const TrainingFit& fit, double wall_s);

}  // namespace crunch::sim
