// The MLX90333 model under a whisker (issue 4): gain, quantisation, clamping, noise, inverse.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/core/rng.h"
#include "crunch_sim/hall_model.h"

using crunch::kPi;
using crunch::Rng;
using crunch::sim::HallCodes;
using crunch::sim::HallSensorModel;

namespace {
constexpr double kDeg = kPi / 180.0;
constexpr double kCodesPerRadian = 65536.0 / (2.0 * kPi);  // 360 degrees over 16 bits
}  // namespace

TEST_CASE("Hall: rest reads mid-scale and the gain is 360 degrees per 16 bits", "[sim]") {
  const HallSensorModel hall;
  const HallCodes rest = hall.ideal(0.0, 0.0);
  CHECK(rest.alpha == 32768);
  CHECK(rest.beta == 32768);
  CHECK_FALSE(rest.alpha_clamped);
  // One degree is 182.04 codes.
  CHECK(hall.ideal(1.0 * kDeg, 0.0).alpha == 32768 + 182);
  CHECK(hall.ideal(0.0, -1.0 * kDeg).beta == 32768 - 182);
  CHECK(hall.ideal(-10.0 * kDeg, 0.0).alpha == 32768 - 1820);
  // Alpha carries the horizontal angle, Beta the vertical one, independently.
  const HallCodes both = hall.ideal(2.0 * kDeg, -3.0 * kDeg);
  CHECK(both.alpha == hall.ideal(2.0 * kDeg, 0.0).alpha);
  CHECK(both.beta == hall.ideal(0.0, -3.0 * kDeg).beta);
}

TEST_CASE("Hall: outputs are quantised to the nearest code", "[sim]") {
  const HallSensorModel hall;
  // 0.4 and 0.6 of a code either side of rest.
  CHECK(hall.ideal(0.4 / kCodesPerRadian, 0.0).alpha == 32768);
  CHECK(hall.ideal(0.6 / kCodesPerRadian, 0.0).alpha == 32769);
  CHECK(hall.ideal(-0.6 / kCodesPerRadian, 0.0).alpha == 32767);
  // A sweep of angles moves the code one step at a time, never skipping.
  std::uint16_t last = hall.ideal(0.0, 0.0).alpha;
  for (int i = 1; i <= 2000; ++i) {
    const std::uint16_t code = hall.ideal(i * 0.1 / kCodesPerRadian, 0.0).alpha;
    CHECK(code - last <= 1);
    last = code;
  }
  CHECK(last == 32768 + 200);
}

TEST_CASE("Hall: outputs saturate at the clamping levels", "[sim]") {
  const HallSensorModel hall;
  CHECK(hall.clampLow() == 32768 - 5461);  // -30 degrees
  CHECK(hall.clampHigh() == 32768 + 5461);
  const HallCodes far = hall.ideal(45.0 * kDeg, -80.0 * kDeg);
  CHECK(far.alpha == hall.clampHigh());
  CHECK(far.beta == hall.clampLow());
  CHECK(far.alpha_clamped);
  CHECK(far.beta_clamped);
  const HallCodes inside = hall.ideal(29.0 * kDeg, -29.0 * kDeg);
  CHECK_FALSE(inside.alpha_clamped);
  CHECK_FALSE(inside.beta_clamped);
  CHECK(inside.alpha < hall.clampHigh());
  // Non-finite angles read as saturated instead of wrapping.
  CHECK(hall.ideal(INFINITY, -INFINITY).alpha == hall.clampHigh());
  CHECK(hall.ideal(INFINITY, -INFINITY).beta == hall.clampLow());
  CHECK(hall.ideal(std::nan(""), 0.0).alpha == hall.clampLow());
  CHECK(hall.ideal(std::nan(""), 0.0).alpha_clamped);
  // Noise cannot carry a reading past a clamp either.
  Rng rng(3);
  for (int i = 0; i < 1000; ++i) {
    const HallCodes s = hall.sample(30.0 * kDeg, 0.0, rng);
    CHECK(s.alpha <= hall.clampHigh());
  }
}

TEST_CASE("Hall: noise is Gaussian with the configured sigma and zero mean", "[sim]") {
  const HallSensorModel hall;  // sigma 4 codes
  Rng rng(42);
  const int n = 20000;
  const double angle = 5.0 * kDeg;
  const double expected = 32768.0 + kCodesPerRadian * angle;
  double sum = 0.0, sum2 = 0.0;
  int within_one_sigma = 0;
  for (int i = 0; i < n; ++i) {
    const double e = hall.sample(angle, 0.0, rng).alpha - expected;
    sum += e;
    sum2 += e * e;
    if (std::abs(e) <= 4.0) ++within_one_sigma;
  }
  const double mean = sum / n;
  const double sd = std::sqrt(sum2 / n - mean * mean);
  // Quantisation adds 1/12 code^2 of variance: sqrt(16 + 1/12) = 4.01. The standard error of
  // the mean is 4 / sqrt(20000) = 0.03 codes.
  CHECK(mean == Approx(0.0).margin(0.12));
  CHECK(sd == Approx(4.01).epsilon(0.03));
  // About 68 % within one sigma (rounding to whole codes nudges it up a little).
  CHECK(within_one_sigma > 0.66 * n);
  CHECK(within_one_sigma < 0.74 * n);

  HallSensorModel::Options quiet;
  quiet.noise_codes = 0.0;
  const HallSensorModel noiseless(quiet);
  CHECK(noiseless.sample(angle, 0.0, rng).alpha == noiseless.ideal(angle, 0.0).alpha);
}

TEST_CASE("Hall: a seed gives the same readings, whatever is clamped", "[sim]") {
  const HallSensorModel hall;
  Rng a(9), b(9);
  for (int i = 0; i < 100; ++i) {
    const double angle = (i % 2 == 0) ? 1.0 : 0.01;  // every other sample saturated
    const HallCodes x = hall.sample(angle, -angle, a);
    const HallCodes y = hall.sample(angle, -angle, b);
    CHECK(x.alpha == y.alpha);
    CHECK(x.beta == y.beta);
  }
  // Exactly two normals per sample: the streams stay aligned with a fresh generator.
  Rng c(9), d(9);
  hall.sample(1.0, 1.0, c);
  d.normal();
  d.normal();
  CHECK(c.next() == d.next());
}

TEST_CASE("Hall: codes map back to angles within half a code", "[sim]") {
  const HallSensorModel hall;
  for (double deg = -29.5; deg <= 29.5; deg += 0.37) {
    const double angle = deg * kDeg;
    const HallCodes c = hall.ideal(angle, -angle);
    CHECK(std::abs(hall.toAngle(c.alpha) - angle) <= 0.5 / kCodesPerRadian + 1e-12);
    CHECK(std::abs(hall.toAngle(c.beta) + angle) <= 0.5 / kCodesPerRadian + 1e-12);
  }
  CHECK(hall.toAngle(32768) == 0.0);
}

TEST_CASE("Hall: options validate and name the bad field", "[sim]") {
  HallSensorModel::Options o;
  REQUIRE(o.validate().ok());
  o.gain = 0.0;
  CHECK_THAT(o.validate().error().message, Catch::Contains("gain"));
  o = {};
  o.noise_codes = -1.0;
  CHECK_THAT(o.validate().error().message, Catch::Contains("noise_codes"));
  o = {};
  o.clamp_angle = kPi;  // +-180 degrees does not fit around mid-scale at this gain
  CHECK_THAT(o.validate().error().message, Catch::Contains("clamp_angle"));
  o = {};
  o.rest_code = 70000.0;
  CHECK_THAT(o.validate().error().message, Catch::Contains("rest_code"));
}
