// Fitting the ramp's slope-to-distance calibration (robot/ramp_fit.h) on synthetic contacts made
// by the beam theory itself with a known gain and compliance scale.
#include "crunch/robot/ramp_fit.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "crunch/core/rng.h"
#include "crunch/robot/whiskers.h"

using crunch::RampFitOptions;
using crunch::RampSample;
using crunch::WhiskerBeam;

namespace {

constexpr double kLever = crunch::kRobotRadius;  // the default radial array

// Contacts from `d_min` to `d_max` whose slopes a whisker with (gain, scale) would give, with
// relative slope noise `noise` (Gaussian, seeded).
std::vector<RampSample> contacts(const WhiskerBeam& beam, double gain, double scale, double d_min,
                                 double d_max, int n, double noise, std::uint64_t seed = 7) {
  crunch::Rng rng(seed);
  std::vector<RampSample> out;
  for (int i = 0; i < n; ++i) {
    const double d = d_min + (d_max - d_min) * i / (n - 1);
    const double s = crunch::rampSlope(beam, d, kLever, gain, scale);
    out.push_back({s * (1.0 + noise * rng.normal()), kLever, d});
  }
  return out;
}

}  // namespace

TEST_CASE("Ramp fit: recovers a known gain and compliance scale from full-length contacts",
          "[robot]") {
  const WhiskerBeam beam;
  for (const auto& [gain, scale] : {std::pair{1.0, 1.0}, {0.9, 1.6}, {1.15, 0.7}}) {
    INFO("gain " << gain << " scale " << scale);
    auto fit = crunch::fitRampCalibration(beam, contacts(beam, gain, scale, 0.02, 0.14, 40, 0.0));
    REQUIRE(fit.ok());
    CHECK(fit.value().gain == Approx(gain).epsilon(1e-4));
    CHECK(fit.value().compliance_scale == Approx(scale).epsilon(1e-4));
    CHECK(fit.value().rms < 1e-5);  // metres: the table's interpolation, far below a micrometre
    CHECK(fit.value().outliers == 0);
    if (gain != 1.0) CHECK(fit.value().rms_nominal > 1e-3);  // the nominal curve is mm off
  }
}

TEST_CASE("Ramp fit: with slope noise the distance error falls to the noise's own level",
          "[robot]") {
  const WhiskerBeam beam;
  // 2 % slope noise: ~1 mm of distance at the tip. A 1.5x softer shaft turns the base less per
  // radian of body turn, so the nominal curve reads its contacts several millimetres too far; the
  // fit's residual is the noise's.
  auto fit = crunch::fitRampCalibration(beam, contacts(beam, 1.0, 1.5, 0.02, 0.14, 200, 0.02));
  REQUIRE(fit.ok());
  const auto& f = fit.value();
  CHECK(f.compliance_scale == Approx(1.5).margin(4 * f.compliance_scale_se + 0.01));
  CHECK(f.gain == Approx(1.0).margin(4 * f.gain_se + 0.01));
  CHECK(f.compliance_scale_se > 0.0);
  CHECK(f.compliance_scale_se < 0.05);
  CHECK(f.mean_nominal > 2e-3);  // a softer shaft than nominal reads too far
  CHECK(std::abs(f.mean) < 2e-4);
  CHECK(f.rms < 0.5 * f.rms_nominal);
}

TEST_CASE("Ramp fit: a few gross outliers are dropped and do not move the fit", "[robot]") {
  const WhiskerBeam beam;
  std::vector<RampSample> xs = contacts(beam, 1.0, 1.3, 0.02, 0.14, 60, 0.005);
  // Two contacts on one whisker: the slope of neither distance.
  xs[10].slope *= 2.0;
  xs[40].slope *= 0.5;
  auto fit = crunch::fitRampCalibration(beam, xs);
  REQUIRE(fit.ok());
  CHECK(fit.value().outliers == 2);
  CHECK(fit.value().compliance_scale == Approx(1.3).epsilon(0.03));
  RampFitOptions keep_all;
  keep_all.outlier_sigmas = 0.0;
  auto all = crunch::fitRampCalibration(beam, xs, keep_all);
  REQUIRE(all.ok());
  CHECK(all.value().outliers == 0);
  CHECK(all.value().rms > fit.value().rms);
}

TEST_CASE("Ramp fit: contacts at one distance cannot separate gain from compliance", "[robot]") {
  const WhiskerBeam beam;
  auto fit = crunch::fitRampCalibration(beam, contacts(beam, 1.0, 1.2, 0.1, 0.1, 12, 0.0));
  REQUIRE_FALSE(fit.ok());
  CHECK(fit.error().message.find("cannot be told apart") != std::string::npos);
}

TEST_CASE("Ramp fit: too few contacts, bad options and a fit outside the physical range fail",
          "[robot]") {
  const WhiskerBeam beam;
  auto few = crunch::fitRampCalibration(beam, contacts(beam, 1.0, 1.0, 0.02, 0.14, 5, 0.0));
  REQUIRE_FALSE(few.ok());
  CHECK(few.error().message.find("usable contacts") != std::string::npos);

  RampFitOptions bad;
  bad.gain_max = 0.1;  // below gain_min
  auto b = crunch::fitRampCalibration(beam, contacts(beam, 1.0, 1.0, 0.02, 0.14, 20, 0.0), bad);
  REQUIRE_FALSE(b.ok());
  CHECK(b.error().message.find("gain_max") != std::string::npos);

  // A shaft 8x softer than nominal fits well, but is no longer this whisker.
  auto soft = crunch::fitRampCalibration(beam, contacts(beam, 1.0, 8.0, 0.02, 0.14, 30, 0.0));
  REQUIRE_FALSE(soft.ok());
  CHECK(soft.error().message.find("compliance_scale") != std::string::npos);
  CHECK(soft.error().message.find("physical range") != std::string::npos);

  // Non-finite slopes are not contacts.
  std::vector<RampSample> xs = contacts(beam, 1.0, 1.0, 0.02, 0.14, 20, 0.0);
  xs[3].slope = NAN;
  xs[4].r = -1.0;
  auto f = crunch::fitRampCalibration(beam, xs);
  REQUIRE(f.ok());
  CHECK(f.value().samples == 20);
  CHECK(f.value().used == 18);
}

TEST_CASE("Ramp fit: the table's distances agree with the host's distanceFromRampSlope",
          "[robot]") {
  // The fit reads distances as the host does; a fitted calibration applied with the host's own
  // function gives the fit's errors.
  const WhiskerBeam beam;
  const std::vector<RampSample> xs = contacts(beam, 1.05, 1.4, 0.02, 0.14, 30, 0.01);
  auto fit = crunch::fitRampCalibration(beam, xs);
  REQUIRE(fit.ok());
  double sum2 = 0.0;
  for (const RampSample& x : xs) {
    const double e = crunch::distanceFromRampSlope(beam, x.slope, x.lever_offset, fit.value().gain,
                                                   fit.value().compliance_scale) -
                     x.r;
    sum2 += e * e;
  }
  CHECK(std::sqrt(sum2 / xs.size()) == Approx(fit.value().rms).margin(1e-6));
}
