// Radial distance to contact from peak deflection (paper §2.4, eqs. 1-2), and the tip/shaft
// decision of the paper's framework (Fig. 1, §1).
//
//   f1 = max_t theta(t)              (eq. 1; theta from ContactDetector, radians)
//   r  = a1 f1 + a0                  (eq. 2; one least-squares line per whisker)
//
// r is measured from the whisker's base along the whisker, metres, as ContactReport's r.
//
// Tip or shaft (docs/SIGNAL.md, "Tip or shaft"). A contact whose predicted r lies within
// tip_zone of the external length, r >= external_length - tip_zone, is a tip contact: its
// surface orientation can be read (§2.5). Anything nearer the base is a shaft contact: the
// robot should move and try again. The default zone is the 50 mm nearest the tip, the range the
// paper's training data covers (§2.4: 10 mm steps over 50 mm from the tip of the 140 mm external
// length), so a "tip" answer is always one the model was trained for.
//
// Fit statistics follow Table 1: sigma per whisker is the residual standard error
// sqrt(sum e^2 / (n - 2)); "pooled" combines the per-whisker lines' residuals
// sqrt(sum e^2 / (N - 2 W)); "combined" fits one line to all whiskers' data together, which is
// what Table 1's "Combo" 4.98 mm appears to be (it exceeds the RMS of the per-whisker sigmas).
//
// Plain values; thread-safe for concurrent const use.
#pragma once

#include <array>
#include <vector>

#include "crunch/core/result.h"
#include "crunch/signal/sample.h"

namespace crunch::signal {

// One training contact: whisker index, its peak deflection f1 (rad) and the true r (m).
struct RadialTrainingSample {
  int whisker = 0;
  double f1 = 0.0;
  double r = 0.0;
};

// r = a1 f1 + a0 for one whisker, with what it was fitted on.
struct RadialLine {
  double a1 = 0.0;     // metres per radian
  double a0 = 0.0;     // metres
  double sigma = 0.0;  // residual standard error, metres
  int samples = 0;
  double f1_min = 0.0, f1_max = 0.0;  // training range of f1
  double r_min = 0.0, r_max = 0.0;    // training range of r

  double predict(double f1) const { return a1 * f1 + a0; }
};

struct RadialOptions {
  double external_length = 0.14;  // metres outside the follicle (§2.4)
  double tip_zone = 0.05;         // metres nearest the tip that count as "tip"
  // okStatus(), or an Error naming the field (positive, finite, tip_zone <= external_length).
  Status validate() const;
};

struct RadialEstimate {
  double r = 0.0;             // metres from the base
  bool tip = false;           // r >= external_length - tip_zone
  bool extrapolated = false;  // f1 outside the whisker's training range
};

struct RadialModel {
  std::array<RadialLine, kWhiskers> whiskers;
  RadialOptions options;

  // Asserts 0 <= whisker < kWhiskers.
  RadialEstimate estimate(int whisker, double f1) const;
  bool isTip(double r) const { return r >= options.external_length - options.tip_zone; }
};

struct RadialFitSummary {
  std::array<double, kWhiskers> sigma{};  // per whisker, metres (Table 1, W1..W4)
  std::array<int, kWhiskers> samples{};
  double pooled_sigma = 0.0;  // the per-whisker lines' residuals together
  RadialLine combined;        // one line through every whisker's data (Table 1 "Combo")
};

struct RadialFit {
  RadialModel model;
  RadialFitSummary summary;
};

// Least-squares fit of eq. 2 per whisker (Eigen's column-pivoting QR on [f1 1]). Errors, each
// naming the sample or whisker: a whisker index outside 0..3, a non-finite f1 or r, a whisker
// with fewer than 3 samples (sigma needs n - 2 > 0), or one whose f1 values are all equal.
Result<RadialFit> fitRadialModel(const std::vector<RadialTrainingSample>& data,
                                 const RadialOptions& options = {});

}  // namespace crunch::signal
