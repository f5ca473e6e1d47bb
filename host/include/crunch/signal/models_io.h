// The signal models file: the radial-distance lines (eq. 2), the orientation templates (eq. 3)
// and the signal-pipeline settings they were trained with, in one JSON document (docs/SIGNAL.md,
// "Models file").
//
//   {"format": "crunchbot-signal-models", "version": 2,
//    "radial": {"external_length": 0.14, "tip_zone": 0.05,
//               "whiskers": [{"a1": .., "a0": .., "sigma": .., "samples": n,
//                             "f1_min": .., "f1_max": .., "r_min": .., "r_max": ..} x 4]},
//    "orientation": {"channels": 8, "decimation": 20, "columns": 200,
//                    "templates": [{"angle": rad, "windows": n, "data": [[columns] x 8]} ...]},
//    "pipeline": {"detector": {"radians_per_code": .., "smoothing": {"order": n, "cutoff_hz": ..,
//                              "sample_rate_hz": .., "moving_average": n}, "settle_samples": n,
//                              "calibration_samples": n, "max_noise_sigma": .., "onset_sigmas": ..,
//                              "release_sigmas": .., "min_onset_threshold": ..,
//                              "release_samples": n, "baseline_time_constant_s": ..,
//                              "max_held_samples": n, "accept_dropped": bool},
//                 "window": {"samples": n, "decimation": n},
//                 "max_episode_samples": n, "max_held_fraction": ..,
//                 "ramp": {"theta_low": .., "theta_high": .., "min_points": n, "min_span": ..,
//                          "max_translation": ..}},
//    "ramp": {"gain": .., "compliance_scale": ..}}
//
// Version 1 files (no "pipeline") are still read: every one was written by `crunchhost train`
// with the pipeline's defaults and an onset threshold of kVersion1OnsetThreshold, which is what
// reading one gives. Version 2 files (no ramp settings, no "ramp" calibration) read with the
// default RampOptions and the nominal RampCalibration (contact_ramp.h). Files are written as
// version 3.
//
// Reading is strict: every field required, unknown keys refused, numbers finite, counts
// non-negative integers, sizes as declared. Every failure is an Error "<file>: <field path>:
// <what is wrong>". Writing is atomic (temporary file, fsync, rename): a reader sees the old
// file or the new one, never half of one.
#pragma once

#include <string>

#include "crunch/core/result.h"
#include "crunch/signal/orientation_templates.h"
#include "crunch/signal/pipeline_options.h"
#include "crunch/signal/radial_distance.h"

namespace crunch::signal {

inline constexpr const char* kModelsFormat = "crunchbot-signal-models";
inline constexpr int kModelsVersion = 3;
// The detector's onset threshold of every version-1 file's training rig (radians).
inline constexpr double kVersion1OnsetThreshold = 0.008;

struct SignalModels {
  RadialModel radial;
  OrientationModel orientation;
  // The settings the models were trained with: whoever runs the models runs the pipeline so.
  PipelineOptions pipeline;
  // Ramp slope -> contact distance (contact_ramp.h); nominal in files before version 3.
  RampCalibration ramp;
};

// okStatus(), or an Error naming the field (as in the file) that could not be written or read
// back: non-finite numbers, radial options out of range, an empty or ragged orientation model,
// pipeline settings that PipelineOptions::validate() refuses. (Whether the templates fit a
// pipeline's window is SignalPipeline::setModels' check.)
Status validateModels(const SignalModels& models);

// The document's text. Asserts validateModels(models).
std::string modelsToJson(const SignalModels& models);
// Parses and checks a document; `source` names it in errors.
Result<SignalModels> parseModelsJson(const std::string& text, const std::string& source);

// Validates, then writes atomically. The Error names `path`.
Status saveModels(const SignalModels& models, const std::string& path);
// Reads and parses `path`. A missing or unreadable file is an Error naming `path`.
Result<SignalModels> loadModels(const std::string& path);

// Where the shipped models (models/sim_models.json) are for the running program: an installed
// crunchhost (cmake --install, the .deb; issue 17) finds them at
// <its bin directory>/../share/crunchbot/models/sim_models.json, and when that file exists it
// is the answer; a crunchhost in its build tree has none there and gets `source_tree_path`.
std::string shippedModelsPath(const std::string& source_tree_path);

}  // namespace crunch::signal
