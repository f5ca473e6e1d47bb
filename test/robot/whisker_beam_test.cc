// The whisker's mechanics (robot/whisker_beam.h): the tapered beam theory and the ramp slope
// that locates a contact.
#include "crunch/robot/whisker_beam.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "crunch/core/geometry.h"
#include "crunch/robot/whiskers.h"

using crunch::kPi;
using crunch::kRobotRadius;
using crunch::WhiskerBeam;

namespace {

// Closed form of integral_0^d (d - s)^2 / (E I(s)) ds for the linear taper.
double taperClosedForm(const WhiskerBeam& beam, double d) {
  const double a = beam.diameter(0.0);
  const double b = (beam.base_diameter - beam.tip_diameter) / beam.total_length;
  const double c = beam.diameter(d);
  const double bracket = 1.0 / (3.0 * c) - 1.0 / a + c / (a * a) - c * c / (3.0 * a * a * a);
  return 64.0 / (beam.youngs_modulus * kPi * b * b * b) * bracket;
}

}  // namespace

TEST_CASE("WhiskerBeam: geometry follows the paper's 160 mm taper, 140 mm outside", "[robot]") {
  const WhiskerBeam beam;
  CHECK(beam.diameter(-0.02) == Approx(1.45e-3));
  CHECK(beam.diameter(0.14) == Approx(0.30e-3));
  CHECK(beam.diameter(0.0) == Approx(1.45e-3 - 1.15e-3 * 0.02 / 0.16));
  CHECK(beam.secondMoment(0.0) == Approx(kPi * std::pow(beam.diameter(0.0), 4) / 64.0));
  CHECK(beam.bendingStiffness(0.07) == Approx(2.5e9 * beam.secondMoment(0.07)));
  // A frustum's mass: the whole external shaft weighs about 0.09 g.
  CHECK(beam.mass(0.0, 0.14) == Approx(9.22e-5).epsilon(0.01));
  CHECK(beam.mass(0.0, 0.07) + beam.mass(0.07, 0.14) == Approx(beam.mass(0.0, 0.14)));
}

TEST_CASE("WhiskerBeam: shaft compliance matches the closed form of a linear taper", "[robot]") {
  const WhiskerBeam beam;
  for (const double d : {0.01, 0.05, 0.09, 0.12, 0.14}) {
    INFO("d = " << d);
    CHECK(beam.shaftCompliance(d) == Approx(taperClosedForm(beam, d)).epsilon(1e-8));
    CHECK(beam.compliance(d) ==
          Approx(d * d / beam.follicle_stiffness + taperClosedForm(beam, d)).epsilon(1e-8));
  }
  CHECK(beam.shaftCompliance(0.0) == 0.0);
}

TEST_CASE("WhiskerBeam: a uniform beam gives d^3 / 3EI", "[robot]") {
  WhiskerBeam beam;
  beam.tip_diameter = beam.base_diameter;
  REQUIRE(beam.validate().ok());
  const double ei = beam.bendingStiffness(0.0);
  for (const double d : {0.03, 0.1, 0.14}) {
    CHECK(beam.shaftCompliance(d) == Approx(d * d * d / (3.0 * ei)).epsilon(1e-10));
  }
  // A uniform element's lumped spring is EI / length at its middle.
  CHECK(beam.elementStiffness(0.02, 0.05) == Approx(ei / 0.03).epsilon(1e-10));
  CHECK(beam.complianceCentroid(0.02, 0.05) == Approx(0.035).epsilon(1e-10));
}

TEST_CASE("WhiskerBeam: a taper moves an element's compliance centroid toward the tip", "[robot]") {
  const WhiskerBeam beam;
  const double c = beam.complianceCentroid(0.1, 0.14);
  CHECK(c > 0.12);
  CHECK(c < 0.14);
  // The lumped spring is softer than the element's base and stiffer than its tip would say.
  const double k = beam.elementStiffness(0.1, 0.14);
  CHECK(k < beam.bendingStiffness(0.1) / 0.04);
  CHECK(k > beam.bendingStiffness(0.14) / 0.04);
}

TEST_CASE("WhiskerBeam: base angle is linear in the push and falls with distance", "[robot]") {
  const WhiskerBeam beam;
  CHECK(beam.baseAngle(0.010, 0.12) == Approx(2.0 * beam.baseAngle(0.005, 0.12)));
  CHECK(beam.baseMoment(0.005, 0.12) ==
        Approx(beam.baseAngle(0.005, 0.12) * beam.follicle_stiffness));
  double previous = beam.baseAngle(0.005, 0.01);
  for (double d = 0.02; d <= 0.14 + 1e-12; d += 0.01) {
    const double now = beam.baseAngle(0.005, d);
    CHECK(now < previous);
    previous = now;
  }
  // Near the base the shaft is stiff: the angle tends to the rigid-whisker delta / d.
  CHECK(beam.baseAngle(0.0005, 0.005) == Approx(0.1).epsilon(0.02));
  CHECK(beam.baseAngle(0.0005, 0.005) / 0.1 > beam.baseAngle(0.001, 0.01) / 0.1);
  CHECK(beam.baseAngle(0.005, 0.0) == 0.0);
}

TEST_CASE("rampSlope: a rigid shaft turns the base by the lever ratio", "[robot]") {
  WhiskerBeam beam;
  // A very stiff shaft: only the follicle bends, theta = dpsi (b + d) / d.
  beam.youngs_modulus = 1e15;
  for (const double d : {0.02, 0.07, 0.14}) {
    CHECK(crunch::rampSlope(beam, d, kRobotRadius) == Approx((kRobotRadius + d) / d).epsilon(1e-5));
  }
}

TEST_CASE("rampSlope: the nominal whisker's slope is the push-to-angle theory's", "[robot]") {
  const WhiskerBeam beam;
  // slope = baseAngle(delta, d) / dpsi with delta = (b + d) dpsi.
  for (const double d : {0.03, 0.09, 0.14}) {
    const double dpsi = 1e-3;
    CHECK(crunch::rampSlope(beam, d, kRobotRadius) ==
          Approx(beam.baseAngle((kRobotRadius + d) * dpsi, d) / dpsi).epsilon(1e-9));
  }
  // Monotone: every distance has its own slope, ~0.8 at the tip.
  double previous = crunch::rampSlope(beam, 0.005, kRobotRadius);
  for (double d = 0.01; d <= 0.14 + 1e-12; d += 0.005) {
    const double now = crunch::rampSlope(beam, d, kRobotRadius);
    CHECK(now < previous);
    previous = now;
  }
  CHECK(previous == Approx(0.805).epsilon(0.01));
}

TEST_CASE("distanceFromRampSlope inverts rampSlope, calibration included, and clamps",
          "[robot]") {
  const WhiskerBeam beam;
  for (const double gain : {1.0, 0.9}) {
    for (const double scale : {1.0, 1.3}) {
      for (double d = 0.01; d <= 0.14 + 1e-12; d += 0.01) {
        const double s = crunch::rampSlope(beam, d, kRobotRadius, gain, scale);
        CHECK(crunch::distanceFromRampSlope(beam, s, kRobotRadius, gain, scale) ==
              Approx(d).margin(1e-7));
      }
    }
  }
  // Flatter than the tip's: a tip contact; steeper than at 5 mm: at the follicle.
  CHECK(crunch::distanceFromRampSlope(beam, 0.1, kRobotRadius) == beam.external_length);
  CHECK(crunch::distanceFromRampSlope(beam, 1e3, kRobotRadius) == Approx(0.005));
  CHECK(crunch::distanceFromRampSlope(beam, std::nan(""), kRobotRadius) == Approx(0.005));
}
