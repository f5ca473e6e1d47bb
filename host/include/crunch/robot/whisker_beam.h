// One whisker's mechanics (paper §2.1): the printed whisker's taper and material, its follicle
// spring, and the tapered Euler-Bernoulli beam theory of what a lateral push does to the base
// angle the Hall sensor reads. Part of the robot's description: the simulator builds its ODE
// whiskers from it (sim/whisker_physics.h) and the host locates contacts with it
// (rampSlope: the deflection's ramp against the body's turn, signal/contact_ramp.h).
//
// The ramp (issue 12; docs/SIGNAL.md, "Locating a contact from the ramp"). A whisker mounted
// with its base at distance b along its own direction from the robot's turning centre
// (b = base . direction: the body radius for the radially mounted default array) touches a fixed
// point at distance d along the straight whisker. Turning the body by dpsi moves the point, in
// the robot's frame, by (b + d) dpsi across the whisker and (to first order, for a radial mount)
// not along it, so the whisker is pushed aside by delta = (b + d) dpsi at d, and its base turns
//   theta = delta d / (k_base C(d)),   C(d) = d^2 / k_base + S(d)   (S: shaftCompliance)
//   slope(d) = d theta / d psi = (b + d) d / (d^2 + k_base S(d))
// which falls monotonically from (b + d) / d for a rigid shaft near the base to ~0.8 at the
// tip of the default whisker. Two numbers a real robot calibrates (`crunchhost train`):
// `gain`, the sensor's reading per radian of base turn, and `compliance_scale`, the shaft's
// compliance relative to this nominal beam (an unknown modulus or follicle stiffness):
//   slope(d) = gain (b + d) d / (d^2 + compliance_scale k_base S(d)).
//
// Plain value; thread-safe for concurrent const use.
#pragma once

#include "crunch/core/result.h"

namespace crunch {

// One whisker: geometry, material and follicle (paper §2.1). All lengths in metres.
struct WhiskerBeam {
  double total_length = 0.160;     // whole printed whisker, §2.1
  double external_length = 0.140;  // outside the follicle, §2.4; s runs over [0, this]
  double base_diameter = 1.45e-3;  // at the magnet end of the whisker, §2.1
  double tip_diameter = 0.30e-3;   // §2.1
  // NanoCure RCP25 photopolymer (§2.1). No published modulus for it was found; 2.5 GPa is the
  // middle of the 2-3 GPa of stiff acrylate SLA photopolymers (docs/WHISKERS.md). Pa.
  double youngs_modulus = 2.5e9;
  double density = 1150.0;  // kg/m^3, cured acrylate photopolymer
  // The polyurethane plug as a rotational spring, N m/rad. Chosen (docs/WHISKERS.md) so that
  // near-tip contacts in a body whisk turn the base a few degrees, and the plug takes about
  // half of the compliance at the tip (C(0.14 m): 6.5 of 17.6 m/N).
  double follicle_stiffness = 3.0e-3;
  // N m s/rad: damping ratio 0.3 of the first mode (about 16 Hz with the default beam);
  // polyurethane is lossy.
  double follicle_damping = 1.75e-5;
  // Stiffness-proportional material damping of the shaft joints, kd_i = this * k_i, seconds.
  // Damps the fast segment modes (zeta ~ 0.2 at the tip) while leaving the slow ones to the plug.
  double material_damping_time = 5.0e-4;

  // okStatus(), or an Error naming the bad field.
  Status validate() const;

  double innerLength() const { return total_length - external_length; }
  // Diameter at distance s from the follicle exit (s may run past [0, external_length]; the
  // linear taper is extrapolated).
  double diameter(double s) const;
  // Second moment of area I(s) = pi D(s)^4 / 64, m^4.
  double secondMoment(double s) const;
  // Bending stiffness E I(s), N m^2.
  double bendingStiffness(double s) const;
  // integral_0^d (d - s)^2 / (E I(s)) ds: lateral compliance at d of the shaft on a rigid base,
  // m/N (composite Simpson, relative error below 1e-9). d in [0, external_length].
  double shaftCompliance(double d) const;
  // C(d) = d^2 / k_base + shaftCompliance(d), m/N.
  double compliance(double d) const;
  // Base moment M = delta d / C(d) for a lateral push delta (m) at distance d (m), N m.
  double baseMoment(double delta, double d) const;
  // Base angle theta = M / k_base for the same push, radians.
  double baseAngle(double delta, double d) const;
  // Rotational stiffness of the shaft between a and b under a uniform moment,
  // 1 / integral_a^b ds / (E I(s)), N m/rad. 0 <= a < b.
  double elementStiffness(double a, double b) const;
  // The compliance centroid of [a, b]: integral s / EI ds over integral 1 / EI ds. A rotational
  // spring of elementStiffness(a, b) placed there matches the element's lateral compliance
  // (d - s)^2 / EI at any d >= b to within the element's second moment about that point.
  double complianceCentroid(double a, double b) const;
  // Mass of the shaft between a and b (a frustum of the taper), kg.
  double mass(double a, double b) const;
};

// The ramp's slope for a contact at d (header comment), radians of base turn per radian of body
// turn. d in (0, beam.external_length].
double rampSlope(const WhiskerBeam& beam, double d, double lever_offset, double gain = 1.0,
                 double compliance_scale = 1.0);
// The contact distance whose rampSlope is `slope` (bisection; rampSlope falls with d), clamped to
// [min_d, beam.external_length]: a slope below the tip's is a tip contact, one above min_d's a
// contact at the follicle. min_d = kMinRampContactDistance.
inline constexpr double kMinRampContactDistance = 0.005;  // metres
double distanceFromRampSlope(const WhiskerBeam& beam, double slope, double lever_offset,
                             double gain = 1.0, double compliance_scale = 1.0);

}  // namespace crunch
