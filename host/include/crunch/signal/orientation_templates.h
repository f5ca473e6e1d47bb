// Surface orientation by template matching (paper §2.5, eq. 3; results §3.2, Fig. 10).
//
// Classes: the wall angles of the training runs, 20..160 degrees in 10 degree steps (15
// classes), stored in radians. A template is the element-wise mean of the training windows
// (window.h: 8 channels, aligned to the first contact, smoothed, possibly decimated) of one
// class. A window I is classified as the class whose template T_i has the lowest
//
//   e(T_i) = 1/N sum_t sum_c (I_c(t) - T_i,c(t))^2          (eq. 3)
//
// over all channels c and samples t (N = channels x columns). The paper's evaluation trains on
// three of four repeats and tests on the fourth, four times (leaveOneRepeatOut).
//
// The angle's meaning is the training label's: the angle between the robot's heading and the
// wall it drove into, as the training runs define it (docs/SIGNAL.md).
//
// Plain values; classify() is const and thread-safe; it allocates nothing when given an
// estimate whose `errors` already has one entry per template.
#pragma once

#include <vector>

#include "crunch/core/result.h"
#include "crunch/signal/window.h"

namespace crunch::signal {

// 20, 30, ..., 160 degrees, in radians.
std::vector<double> defaultOrientationAngles();

struct OrientationOptions {
  std::vector<double> angles = defaultOrientationAngles();  // class angles, radians, distinct
  double label_tolerance =
      0.5 * 3.141592653589793 / 180.0;  // a label must be this close to a class
  Status validate() const;
};

// One training window with its wall angle (radians) and the repeat it came from (0..3 in the
// paper; any non-negative integers).
struct LabelledWindow {
  double angle = 0.0;
  int repeat = 0;
  ContactWindow window;
};

struct OrientationTemplate {
  double angle = 0.0;  // radians
  int windows = 0;     // training windows averaged
  WindowMatrix mean;   // kChannels x columns
};

struct OrientationEstimate {
  int class_index = -1;        // index into the model's templates
  double angle = 0.0;          // radians
  std::vector<double> errors;  // e(T_i) per template, rad^2
};

struct OrientationModel {
  int decimation = 1;  // of the windows it was trained on
  int columns = 0;     // window columns
  std::vector<OrientationTemplate> templates;

  // True if `w` has this model's shape (decimation and columns).
  bool accepts(const ContactWindow& w) const {
    return w.decimation == decimation && w.data.cols() == columns;
  }
  // Eq. 3 against every template; asserts accepts(w) and a non-empty model. Resizes
  // out.errors to the number of templates (no allocation if it already has that size). Ties go
  // to the lower index.
  void classify(const ContactWindow& w, OrientationEstimate& out) const;
  OrientationEstimate classify(const ContactWindow& w) const;
};

// Templates from labelled windows. Errors, naming the window or class: windows of different
// shapes, a non-finite value, a label no class is within label_tolerance of, a class with no
// window.
Result<OrientationModel> trainOrientationTemplates(const std::vector<LabelledWindow>& data,
                                                   const OrientationOptions& options = {});

// One test window of the cross-validation.
struct OrientationTrial {
  int repeat = 0;
  double true_angle = 0.0;       // radians (the class the label belongs to)
  double estimated_angle = 0.0;  // radians
  double error = 0.0;            // estimated - true, radians
};

struct AngleErrors {
  double angle = 0.0;          // class angle, radians
  std::vector<double> errors;  // estimated - true, one per test window of this class
  double mean = 0.0;
  double sd = 0.0;  // sample standard deviation (0 for fewer than 2 errors)
};

struct CrossValidation {
  std::vector<OrientationTrial> trials;
  std::vector<AngleErrors> per_angle;  // in class order
  double mean_error = 0.0;             // over all trials (Fig. 10: -2.2 degrees)
  double sd_error = 0.0;               // over all trials (Fig. 10's "standard error", 21.2 degrees)
  double accuracy = 0.0;               // fraction of trials with the right class
};

// The paper's protocol: for each repeat, templates from every other repeat, tested on this
// repeat's windows. Errors: those of trainOrientationTemplates for any fold (a fold missing a
// class names the repeat left out), or fewer than 2 repeats.
Result<CrossValidation> leaveOneRepeatOut(const std::vector<LabelledWindow>& data,
                                          const OrientationOptions& options = {});

}  // namespace crunch::signal
