// Frequency and step responses of the paper's smoothing (§2.5): 17 Hz low-pass and 5-point
// moving average at 2 kHz.
#include "crunch/signal/filters.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <vector>

using namespace crunch;
using namespace crunch::signal;

namespace {

constexpr double kFs = 2000.0;
constexpr double kPi = std::numbers::pi;

double dB(double gain) { return 20.0 * std::log10(gain); }

ButterworthLowPass lowPass(int order) {
  ButterworthLowPass::Options o;
  o.order = order;
  return ButterworthLowPass(o);
}

// Steady-state amplitude of a filter's output for a unit sine at f: runs 3 s, then fits
// a sin + b cos over the last second (an integer number of periods for the frequencies used).
template <typename Filter>
double measuredGain(Filter& filter, double f) {
  filter.reset(0.0);
  const int settle = 4000, measure = 2000;
  double s = 0.0, c = 0.0;
  for (int n = 0; n < settle + measure; ++n) {
    const double phase = 2.0 * kPi * f * n / kFs;
    const double y = filter.step(std::sin(phase));
    if (n >= settle) {
      s += y * std::sin(phase);
      c += y * std::cos(phase);
    }
  }
  return 2.0 * std::hypot(s, c) / measure;
}

}  // namespace

TEST_CASE("Butterworth: unit gain at DC, -3.01 dB at 17 Hz, 100 Hz strongly attenuated",
          "[signal]") {
  for (int order : {2, 4}) {
    CAPTURE(order);
    const ButterworthLowPass lp = lowPass(order);
    CHECK(lp.sections() == order / 2);
    CHECK(lp.gain(0.0) == Approx(1.0).epsilon(1e-12));
    // Pre-warping puts the analogue -3 dB point exactly on 17 Hz.
    CHECK(dB(lp.gain(17.0)) == Approx(-10.0 * std::log10(2.0)).margin(1e-9));
    // The bilinear transform compresses frequencies towards fs/2, so the digital filter is at
    // least as steep as the analogue 1 / sqrt(1 + (f/fc)^2n).
    const double analogue_100 = -10.0 * std::log10(1.0 + std::pow(100.0 / 17.0, 2 * order));
    CHECK(dB(lp.gain(100.0)) <= analogue_100 + 1e-9);
    CHECK(dB(lp.gain(100.0)) < (order == 2 ? -30.0 : -60.0));
    // Monotone: Butterworth has no ripple.
    double previous = 1.0 + 1e-12;
    for (double f = 0.0; f < 999.0; f += 1.0) {
      CHECK(lp.gain(f) <= previous);
      previous = lp.gain(f);
    }
  }
}

TEST_CASE("Butterworth: filtering sines gives the designed gains", "[signal]") {
  for (int order : {2, 4}) {
    CAPTURE(order);
    ButterworthLowPass lp = lowPass(order);
    for (double f : {1.0, 5.0, 17.0, 40.0, 100.0}) {
      CAPTURE(f);
      CHECK(measuredGain(lp, f) == Approx(lp.gain(f)).epsilon(1e-3).margin(1e-6));
    }
    CHECK(dB(measuredGain(lp, 17.0)) == Approx(-3.0103).margin(0.01));
  }
}

TEST_CASE("Butterworth: step response is causal, overshoots as designed and settles to 1",
          "[signal]") {
  // Second-order Butterworth overshoots a step by exp(-pi) = 4.3 %, fourth-order by 10.8 %.
  const std::pair<int, double> cases[] = {{2, 0.0432}, {4, 0.108}};
  for (const auto& [order, overshoot] : cases) {
    CAPTURE(order);
    ButterworthLowPass lp = lowPass(order);
    lp.reset(0.0);
    for (int n = 0; n < 100; ++n) REQUIRE(lp.step(0.0) == 0.0);
    double peak = 0.0, y = 0.0;
    for (int n = 0; n < 2000; ++n) {
      y = lp.step(1.0);
      if (n == 0) CHECK(y > 0.0);   // causal, reacts at once (b0 > 0) ...
      if (n == 0) CHECK(y < 1e-3);  // ... but only a little
      peak = std::max(peak, y);
    }
    CHECK(peak - 1.0 == Approx(overshoot).margin(0.005));
    CHECK(y == Approx(1.0).margin(1e-9));
  }
}

TEST_CASE("Butterworth: the lag of a ramp equals the designed group delay", "[signal]") {
  for (int order : {2, 4}) {
    CAPTURE(order);
    ButterworthLowPass lp = lowPass(order);
    // Analogue DC group delay: sum over pole pairs of 1 / (Q wc).
    double analogue = 0.0;
    for (int i = 0; i < order / 2; ++i) {
      analogue += 2.0 * std::sin((2 * i + 1) * kPi / (2.0 * order)) / (2.0 * kPi * 17.0);
    }
    CHECK(lp.groupDelayAtDc() == Approx(analogue).epsilon(0.01));
    CHECK(lp.groupDelayAtDc() < (order == 2 ? 0.0135 : 0.025));
    lp.reset(0.0);
    double y = 0.0;
    const int n_end = 4000;
    for (int n = 0; n < n_end; ++n) y = lp.step(static_cast<double>(n));
    const double lag_samples = (n_end - 1) - y;
    CHECK(lag_samples / kFs == Approx(lp.groupDelayAtDc()).epsilon(1e-6));
  }
}

TEST_CASE("Butterworth: reset(x0) starts in the steady state of x0", "[signal]") {
  ButterworthLowPass lp = lowPass(4);
  lp.reset(-3.7);
  for (int n = 0; n < 1000; ++n) REQUIRE(lp.step(-3.7) == Approx(-3.7).epsilon(1e-12));
}

TEST_CASE("Butterworth: options are validated with the field named", "[signal]") {
  ButterworthLowPass::Options o;
  CHECK(o.validate().ok());
  o.order = 3;
  REQUIRE_FALSE(o.validate().ok());
  CHECK_THAT(o.validate().error().message, Catch::Contains("order"));
  o.order = 10;
  CHECK_FALSE(o.validate().ok());
  o = {};
  o.cutoff_hz = 1000.0;
  REQUIRE_FALSE(o.validate().ok());
  CHECK_THAT(o.validate().error().message, Catch::Contains("cutoff_hz"));
  o.cutoff_hz = std::nan("");
  CHECK_FALSE(o.validate().ok());
}

TEST_CASE("MovingAverage: 5-point step response, unit DC gain, null at fs/5", "[signal]") {
  MovingAverage ma(5);
  ma.reset(0.0);
  const double expected[] = {0.2, 0.4, 0.6, 0.8, 1.0, 1.0, 1.0};
  for (double e : expected) CHECK(ma.step(1.0) == Approx(e).epsilon(1e-15));
  CHECK(std::abs(ma.response(0.0, kFs)) == Approx(1.0));
  CHECK(std::abs(ma.response(400.0, kFs)) == Approx(0.0).margin(1e-12));
  CHECK(ma.groupDelaySamples() == 2.0);
  CHECK(measuredGain(ma, 100.0) == Approx(std::abs(ma.response(100.0, kFs))).epsilon(1e-6));
  // History sums directly: a huge value leaves no residue once it has passed.
  ma.reset(0.0);
  ma.step(1e16);
  for (int i = 0; i < 4; ++i) ma.step(1.0);
  CHECK(ma.step(1.0) == 1.0);
}

TEST_CASE("SmoothingFilter: the paper's chain keeps 17 Hz at -3 dB and adds 1 ms of delay",
          "[signal]") {
  SmoothingFilter f;
  CHECK(f.gain(0.0) == Approx(1.0).epsilon(1e-12));
  // The 5-point average's gain sin(5x) / (5 sin x), x = pi f / fs, costs 0.025 dB at 17 Hz.
  const double x = kPi * 17.0 / kFs;
  const double ma_17 = std::sin(5.0 * x) / (5.0 * std::sin(x));
  CHECK(dB(ma_17) == Approx(-0.0248).margin(0.0005));
  CHECK(dB(f.gain(17.0)) == Approx(-10.0 * std::log10(2.0) + dB(ma_17)).margin(1e-9));
  CHECK(dB(f.gain(100.0)) < -31.0);
  CHECK(f.groupDelayAtDc() == Approx(lowPass(2).groupDelayAtDc() + 0.001).epsilon(1e-12));
  CHECK(measuredGain(f, 17.0) == Approx(f.gain(17.0)).epsilon(1e-3));
  SmoothingFilter::Options o;
  o.moving_average = 0;
  REQUIRE_FALSE(o.validate().ok());
  CHECK_THAT(o.validate().error().message, Catch::Contains("moving_average"));
}
