// Fitting the two numbers of the ramp's slope-to-distance curve (whisker_beam.h, rampSlope:
// slope(d) = gain (b + d) d / (d^2 + compliance_scale k_base S(d))) to contacts whose true
// distance along the whisker is known: what `crunchhost train` calibrates (docs/TRAINING.md,
// "Ramp calibration"); the host stores the result as the models file's `ramp`
// (signal::RampCalibration).
//
// The objective is the distance error itself: least squares of d_hat_i - r_i, where d_hat_i is
// what the host reads from sample i's measured slope (distanceFromRampSlope with the candidate
// gain and compliance_scale, clamped to [kMinRampContactDistance, external_length] as the host
// clamps it) and r_i the true distance. Why not the slope residual: the map uses d, and a slope
// error costs very different distances along the whisker (near the base the curve is steep,
// (b + d) / d, and 1 % of slope is a fraction of a millimetre; at the tip 1 % of slope is
// ~0.4 mm); unweighted slope least squares would let the few steep near-base slopes decide. A tip
// contact whose slope is below the tip's reads as the tip, exactly as the host reads it, so a
// contact hooked on the very tip costs nothing rather than pulling the fit.
//
// The two parameters are told apart by where the contacts are: near the follicle the shaft's
// compliance is negligible (slope ~ gain (b + d) / d) and fixes the gain; toward the tip the
// shaft dominates and fixes compliance_scale. Contacts at one distance cannot separate them: the
// fit refuses when the normal matrix is that close to singular.
//
// Method: Levenberg-Marquardt on (ln gain, ln compliance_scale) (both stay positive), numeric
// Jacobian; the host's bisection runs on a table of S(d) at 0.05 mm (linear interpolation,
// relative error < 1e-6), so a fit over hundreds of contacts takes milliseconds. Outliers (a
// second contact on the shaft, a slip: the slope then belongs to no single distance) are
// dropped once, after a first fit, beyond outlier_sigmas robust standard deviations
// (1.4826 x the median absolute deviation), and the fit is repeated on the rest.
//
// Plain functions; thread-safe.
#pragma once

#include <vector>

#include "crunch/core/result.h"
#include "crunch/robot/whisker_beam.h"

namespace crunch {

// One contact: its measured ramp slope, the whisker mount's lever offset b (metres:
// WhiskerMount::base . direction(), as the host uses it) and the true contact distance r
// (metres along the whisker from the follicle exit).
struct RampSample {
  double slope = 0.0;
  double lever_offset = 0.0;
  double r = 0.0;
};

struct RampFitOptions {
  // The physical range of the fitted values; a fit outside it is an Error naming the value.
  // gain: the sensor's reading per radian of base turn; a Hall chain off by more than 2x is a
  // wrong radians_per_code, not a calibration. compliance_scale: the shaft's compliance against
  // the nominal beam (1 / the modulus ratio); photopolymers' moduli span ~1-4 GPa against the
  // nominal 2.5, and a follicle plug or a shaft 5x off the nominal is a different whisker.
  double gain_min = 0.5, gain_max = 2.0;
  double scale_min = 0.2, scale_max = 5.0;
  int min_samples = 8;        // usable samples (finite, r in (0, external_length], slope > 0)
  double outlier_sigmas = 4.0;  // robust sigmas; 0 keeps every sample
  // Smallest robust sigma used for the outlier cut, metres: on noise-free (synthetic) data the
  // MAD is ~0 and would call every sample an outlier.
  double min_outlier_sigma = 1e-4;
  // okStatus(), or an Error naming the bad field.
  Status validate() const;
};

struct RampFitSummary {
  double gain = 1.0;
  double compliance_scale = 1.0;
  // 1-sigma standard errors of the two values from the fit's covariance (residual variance times
  // the inverse normal matrix, in the log parameters, mapped back).
  double gain_se = 0.0;
  double compliance_scale_se = 0.0;
  int samples = 0;   // given
  int used = 0;      // in the final fit
  int outliers = 0;  // dropped by the outlier cut
  int iterations = 0;
  // d_hat - r over the used samples, metres: with the nominal calibration (1, 1) and fitted.
  double rms_nominal = 0.0, mean_nominal = 0.0;
  double rms = 0.0, mean = 0.0;
};

// Errors: bad options or beam; fewer than min_samples usable samples; contacts that cannot
// separate the two values; a fit outside the physical range (the Error names "gain" or
// "compliance_scale" and the value).
Result<RampFitSummary> fitRampCalibration(const WhiskerBeam& beam,
                                          const std::vector<RampSample>& samples,
                                          const RampFitOptions& options = {});

}  // namespace crunch
