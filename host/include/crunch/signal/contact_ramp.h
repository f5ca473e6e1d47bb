// Contact localisation from the deflection's time course against the body's motion (issue 12;
// docs/SIGNAL.md, "Locating a contact from the ramp").
//
// While the body turns in place by dpsi past the heading psi0 at which a straight whisker first
// touched a fixed point, the whisker must bend aside by the lateral push delta = lever * dpsi at
// the contact, and its base turns by theta = delta * d / (k_base C(d)) (whisker_beam.h). For the
// first few hundredths of a radian this is a straight line through (psi0, 0):
//
//   theta(psi) = s * |psi - psi0|,    s = slope, a function of the contact distance d only
//
// RampFitter fits that line by least squares to the (heading, theta) pairs of one contact while
// theta is in [theta_low, theta_high] ("the ramp"): below theta_low the onset's smoothing
// transient and static friction bend it, above theta_high the whisker's large-deflection geometry
// does. The fit gives
//   slope        s = |d theta / d psi|: the contact distance (robot/whisker_beam.h inverts it);
//   touch_heading psi0, where the fitted line reaches theta = 0: the heading at which the
//                straight rest whisker passes through the contact point. Right by construction
//                whatever the whisker was doing before the ramp (a push while driving, a pause):
//                the deflection is a static equilibrium, so turning back by theta / s puts the
//                rest ray through the point;
//   first_sample where the ramp began (its pose gives the position the heading belongs to).
//
// Only samples turning in place count: a sample whose position moved since the previous one (by
// more than 1 um: driving), or lies more than max_translation from the ramp's first sample,
// restarts the fit (a translation bends the whisker without turning it).
// A heading reversal, theta leaving the band, or close() ends the ramp; an ended ramp with fewer
// than min_points samples or less than min_span of heading is discarded and the fitter looks for
// the next one (noise at the band's edge, a brush). The fit is the first good ramp of a contact.
// Mirrored for both turn directions (and for a ramp that falls as the body turns away).
//
// Plain value; allocation-free; not thread-safe.
#pragma once

#include <cstdint>

#include "crunch/core/geometry.h"
#include "crunch/core/result.h"

namespace crunch::signal {

struct RampOptions {
  double theta_low = 0.012;   // radians of base deflection
  double theta_high = 0.06;   // radians
  int min_points = 40;        // samples (20 ms)
  double min_span = 0.002;    // radians of heading covered by the ramp's samples
  double max_translation = 5e-4;  // metres the base may move during a ramp
  // okStatus(), or an Error naming the bad field.
  Status validate() const;
};

// What turns a ramp's slope into a contact distance besides the whisker's nominal mechanics
// (robot/whisker_beam.h, rampSlope): the sensor's reading per radian of base turn and the shaft's
// compliance relative to the nominal beam. `crunchhost train` fits both (docs/TRAINING.md); the
// nominal values are exact for the simulated whisker.
struct RampCalibration {
  double gain = 1.0;
  double compliance_scale = 1.0;
  // okStatus(), or an Error naming the bad field (each in (0, 100]).
  Status validate() const;
};

struct ContactRamp {
  bool valid = false;
  double slope = 0.0;          // |d theta / d psi|, radians per radian
  double touch_heading = 0.0;  // psi0, radians (in the unwrapped range of the poses given)
  int direction = 0;           // +1: theta grew with the heading (the object on the left)
  std::uint64_t first_sample = 0;  // pipeline sample of the ramp's first point
  int points = 0;
  double span = 0.0;           // heading covered, radians
  double residual_rms = 0.0;   // radians of theta
};

class RampFitter {
 public:
  RampFitter() = default;
  explicit RampFitter(const RampOptions& options) : options_(options) {}

  // A new contact: forgets the fit.
  void reset();
  // One sample: theta (smoothed base deflection, radians) and the pose it belongs to (aligned
  // for the smoothing's delay by the caller), at pipeline sample `sample`.
  void push(double theta, const Pose2& pose, std::uint64_t sample);
  // The contact ended: keeps the ramp in progress if it is good enough.
  void close();

  bool done() const { return done_; }
  const ContactRamp& result() const { return result_; }

 private:
  void endRamp();  // keeps the ramp (done_) if good, else starts looking again
  void restart();

  RampOptions options_;
  bool done_ = false;
  ContactRamp result_;
  // The ramp in progress, x = heading - the first point's heading.
  int n_ = 0;
  Pose2 first_;
  Pose2 last_pose_;  // the previous sample's (driving is told from turning by it)
  std::uint64_t first_sample_ = 0;
  double last_x_ = 0.0, min_x_ = 0.0, max_x_ = 0.0;
  int dir_ = 0;
  double sx_ = 0.0, sy_ = 0.0, sxx_ = 0.0, sxy_ = 0.0, syy_ = 0.0;
};

}  // namespace crunch::signal
