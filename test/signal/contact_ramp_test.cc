// The ramp of a contact's deflection against the body's heading (signal/contact_ramp.h).
#include "crunch/signal/contact_ramp.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "crunch/core/rng.h"

using namespace crunch;
using namespace crunch::signal;

namespace {

// The body turns in place at `rate` rad/sample from `psi_start`; a contact touched at psi0 bends
// the base by slope * |psi - psi0| (zero before), plus Gaussian noise of `noise` rad. Feeds
// `samples` samples from sample index `first`.
void turn(RampFitter& f, double psi_start, double rate, double psi0, double slope, int samples,
          double noise = 0.0, Pose2 at = {}, std::uint64_t first = 0) {
  Rng rng(7);
  for (int k = 0; k < samples; ++k) {
    const double psi = psi_start + rate * k;
    const double ahead = rate > 0 ? psi - psi0 : psi0 - psi;
    const double theta = std::max(0.0, slope * ahead) + (noise > 0 ? rng.normal(0, noise) : 0.0);
    f.push(std::abs(theta), {at.x, at.y, psi}, first + static_cast<std::uint64_t>(k));
  }
}

}  // namespace

TEST_CASE("RampFitter: slope and touch heading of a clean ramp, both turn directions",
          "[signal]") {
  for (const double rate : {6.5e-5, -6.5e-5}) {
    for (const double slope : {0.8, 3.0}) {
      INFO("rate " << rate << " slope " << slope);
      RampFitter f;
      f.reset();
      turn(f, 1.0, rate, 1.0 + 200 * rate, slope, 4000, 0.0, {}, 1000);
      REQUIRE(f.done());
      const ContactRamp& r = f.result();
      CHECK(r.valid);
      CHECK(r.slope == Approx(slope).epsilon(1e-9));
      CHECK(r.touch_heading == Approx(1.0 + 200 * rate).margin(1e-9));
      CHECK(r.direction == (rate > 0 ? 1 : -1));
      // The first point is the first sample in the band: theta >= theta_low.
      const int first = static_cast<int>(std::ceil(RampOptions{}.theta_low / (slope * std::abs(rate)))) + 200;
      CHECK(std::abs(static_cast<long>(r.first_sample) - (1000 + first)) <= 1);
      CHECK(r.residual_rms < 1e-8);  // exact data; the sums' rounding leaves ~1e-9
    }
  }
}

TEST_CASE("RampFitter: Hall noise leaves the slope within a percent", "[signal]") {
  RampFitter f;
  f.reset();
  // 4 LSB of an MLX90333 after smoothing is ~1e-4 rad; 1e-3 rad here is ten times worse.
  turn(f, 0.0, 6.5e-5, 0.01, 0.8, 6000, 1e-3);
  REQUIRE(f.done());
  CHECK(f.result().slope == Approx(0.8).epsilon(0.01));
  CHECK(f.result().touch_heading == Approx(0.01).margin(2e-4));
}

TEST_CASE("RampFitter: a translation restarts the ramp, the turn that follows is fitted",
          "[signal]") {
  RampFitter f;
  f.reset();
  // Driving into the object at a constant heading: theta climbs into the band, heading fixed.
  for (int k = 0; k < 400; ++k) {
    const double x = 1e-5 * k;  // 4 mm over the drive
    f.push(0.005 + 0.02 * k / 400.0, {x, 0.0, 0.5}, static_cast<std::uint64_t>(k));
  }
  CHECK_FALSE(f.done());
  // Pressed at 0.025 rad, the body turns in place: theta = 0.025 + 1.2 (psi - 0.5).
  for (int k = 0; k < 2000; ++k) {
    const double psi = 0.5 + 6.5e-5 * k;
    f.push(0.025 + 1.2 * (psi - 0.5), {4e-3, 0.0, psi}, 400 + static_cast<std::uint64_t>(k));
  }
  REQUIRE(f.done());
  CHECK(f.result().slope == Approx(1.2).epsilon(1e-6));
  // The rest ray passes the point where the pressed deflection is turned back out.
  CHECK(f.result().touch_heading == Approx(0.5 - 0.025 / 1.2).margin(1e-6));
  CHECK(f.result().first_sample >= 400);
}

TEST_CASE("RampFitter: a reversal ends the ramp of the first pass", "[signal]") {
  RampFitter f;
  f.reset();
  turn(f, 0.0, 6.5e-5, 0.001, 2.0, 300);  // through the band's lower part
  const double psi_turn = 6.5e-5 * 299;
  // Back the other way with a friction step: theta lower on the way back.
  for (int k = 1; k < 300; ++k) {
    const double psi = psi_turn - 6.5e-5 * k;
    f.push(std::max(0.0, 1.5 * (psi - 0.001)), {0, 0, psi}, 300 + static_cast<std::uint64_t>(k));
  }
  REQUIRE(f.done());
  CHECK(f.result().slope == Approx(2.0).epsilon(1e-6));
  CHECK(f.result().direction == 1);
}

TEST_CASE("RampFitter: a brush that never reaches the band, or too short a ramp, gives none",
          "[signal]") {
  RampFitter f;
  f.reset();
  turn(f, 0.0, 6.5e-5, 0.001, 0.1, 1000);  // peaks at 0.0064 rad
  f.close();
  CHECK_FALSE(f.done());
  CHECK_FALSE(f.result().valid);
  f.reset();
  // Through the band in 20 samples (fewer than min_points), then out of it above.
  turn(f, 0.0, 6.5e-5, 0.0, 40.0, 60);
  f.close();
  CHECK_FALSE(f.result().valid);
}

TEST_CASE("RampOptions and RampCalibration: validate names the field", "[signal]") {
  RampOptions o;
  CHECK(o.validate().ok());
  o.theta_high = o.theta_low;
  CHECK_THAT(o.validate().error().message, Catch::Contains("theta_high"));
  o = {};
  o.min_points = 1;
  CHECK_THAT(o.validate().error().message, Catch::Contains("min_points"));
  o = {};
  o.max_translation = std::nan("");
  CHECK_THAT(o.validate().error().message, Catch::Contains("max_translation"));
  RampCalibration c;
  CHECK(c.validate().ok());
  c.gain = 0.0;
  CHECK_THAT(c.validate().error().message, Catch::Contains("gain"));
  c = {};
  c.compliance_scale = -1.0;
  CHECK_THAT(c.validate().error().message, Catch::Contains("compliance_scale"));
}
