#include "crunch/robot/whisker_beam.h"

#include <cmath>
#include <string>

#include "crunch/core/geometry.h"

namespace crunch {

namespace {

// Composite Simpson's rule over [a, b] with n (even) intervals.
template <typename F>
double simpson(F f, double a, double b, int n) {
  if (!(b > a)) return 0.0;
  const double h = (b - a) / n;
  double sum = f(a) + f(b);
  for (int i = 1; i < n; ++i) sum += (i % 2 == 1 ? 4.0 : 2.0) * f(a + i * h);
  return sum * h / 3.0;
}

Error beamError(const std::string& field, const std::string& what) {
  return Error{"WhiskerBeam::" + field + " " + what};
}
bool positive(double x) { return std::isfinite(x) && x > 0.0; }
bool nonNegative(double x) { return std::isfinite(x) && x >= 0.0; }

constexpr double kMinContactDistance = kMinRampContactDistance;

}  // namespace

Status WhiskerBeam::validate() const {
  if (!positive(total_length)) return beamError("total_length", "must be finite and > 0");
  if (!positive(external_length) || external_length > total_length) {
    return beamError("external_length", "must be in (0, total_length]");
  }
  if (!positive(base_diameter)) return beamError("base_diameter", "must be finite and > 0");
  if (!positive(tip_diameter) || tip_diameter > base_diameter) {
    return beamError("tip_diameter", "must be in (0, base_diameter]");
  }
  if (!positive(youngs_modulus)) return beamError("youngs_modulus", "must be finite and > 0");
  if (!positive(density)) return beamError("density", "must be finite and > 0");
  if (!positive(follicle_stiffness)) {
    return beamError("follicle_stiffness", "must be finite and > 0");
  }
  if (!nonNegative(follicle_damping)) {
    return beamError("follicle_damping", "must be finite and >= 0");
  }
  if (!nonNegative(material_damping_time)) {
    return beamError("material_damping_time", "must be finite and >= 0");
  }
  return okStatus();
}

double WhiskerBeam::diameter(double s) const {
  const double along = s + innerLength();  // from the magnet end
  return base_diameter - (base_diameter - tip_diameter) * along / total_length;
}

double WhiskerBeam::secondMoment(double s) const {
  const double d = diameter(s);
  return kPi * d * d * d * d / 64.0;
}

double WhiskerBeam::bendingStiffness(double s) const {
  return youngs_modulus * secondMoment(s);
}

double WhiskerBeam::shaftCompliance(double d) const {
  return simpson([&](double s) { return (d - s) * (d - s) / bendingStiffness(s); }, 0.0, d, 2000);
}

double WhiskerBeam::compliance(double d) const {
  return d * d / follicle_stiffness + shaftCompliance(d);
}

double WhiskerBeam::baseMoment(double delta, double d) const {
  if (!(d > 0.0)) return 0.0;
  return delta * d / compliance(d);
}

double WhiskerBeam::baseAngle(double delta, double d) const {
  return baseMoment(delta, d) / follicle_stiffness;
}

double WhiskerBeam::elementStiffness(double a, double b) const {
  return 1.0 / simpson([&](double s) { return 1.0 / bendingStiffness(s); }, a, b, 200);
}

double WhiskerBeam::complianceCentroid(double a, double b) const {
  const double c = simpson([&](double s) { return 1.0 / bendingStiffness(s); }, a, b, 200);
  return simpson([&](double s) { return s / bendingStiffness(s); }, a, b, 200) / c;
}

double WhiskerBeam::mass(double a, double b) const {
  const double d1 = diameter(a), d2 = diameter(b);
  return density * kPi / 12.0 * (b - a) * (d1 * d1 + d1 * d2 + d2 * d2);
}

double rampSlope(const WhiskerBeam& beam, double d, double lever_offset, double gain,
                 double compliance_scale) {
  const double shaft = compliance_scale * beam.follicle_stiffness * beam.shaftCompliance(d);
  return gain * (lever_offset + d) * d / (d * d + shaft);
}

double distanceFromRampSlope(const WhiskerBeam& beam, double slope, double lever_offset,
                             double gain, double compliance_scale) {
  double lo = kMinContactDistance, hi = beam.external_length;
  if (!(slope < rampSlope(beam, lo, lever_offset, gain, compliance_scale))) return lo;
  if (!(slope > rampSlope(beam, hi, lever_offset, gain, compliance_scale))) return hi;
  for (int i = 0; i < 40; ++i) {  // 135 mm / 2^40: far below a micrometre
    const double mid = 0.5 * (lo + hi);
    if (rampSlope(beam, mid, lever_offset, gain, compliance_scale) > slope) lo = mid;
    else hi = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace crunch
