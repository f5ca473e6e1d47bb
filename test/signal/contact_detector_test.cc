// One whisker's rest, noise, threshold, hysteresis and handling of invalid samples.
#include "crunch/signal/contact_detector.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "synthetic.h"

using namespace crunch;
using namespace crunch::signal;
using namespace crunch::signal::testing;

namespace {

constexpr double kRadPerCode = 1.0 / kCodesPerRadian;

// Drives one detector sample by sample and remembers when each event happened.
struct Driver {
  explicit Driver(const ContactDetectorOptions& o = {}, std::uint64_t seed = 1)
      : det(o), rng(seed) {}

  DetectorEvent push(double alpha, double beta, double noise, std::uint16_t st = 0,
                     double offset = 0.0) {
    WhiskerReading r{code(alpha, noise, rng, offset), code(beta, noise, rng, offset), st};
    const DetectorEvent e = det.push(r);
    if (e != DetectorEvent::kNone) events.push_back({n, e});
    ++n;
    return e;
  }
  DetectorEvent pushRaw(std::uint16_t a, std::uint16_t b, std::uint16_t st) {
    const DetectorEvent e = det.push({a, b, st});
    if (e != DetectorEvent::kNone) events.push_back({n, e});
    ++n;
    return e;
  }
  void quiet(int samples, double noise, double offset = 0.0) {
    for (int i = 0; i < samples; ++i) push(0.0, 0.0, noise, 0, offset);
  }
  int countOf(DetectorEvent e) const {
    int c = 0;
    for (const auto& [when, what] : events) c += what == e;
    return c;
  }
  long firstOf(DetectorEvent e) const {
    for (const auto& [when, what] : events) {
      if (what == e) return when;
    }
    return -1;
  }

  ContactDetector det;
  Rng rng;
  long n = 0;
  std::vector<std::pair<long, DetectorEvent>> events;
};

// sqrt(sum h^2) of the smoothing chain: the factor from white input noise to output noise.
double noiseGain() {
  SmoothingFilter f;
  f.reset(0.0);
  double sum = 0.0;
  for (int n = 0; n < 20000; ++n) {
    const double h = f.step(n == 0 ? 1.0 : 0.0);
    sum += h * h;
  }
  return std::sqrt(sum);
}

}  // namespace

TEST_CASE("ContactDetector: calibrates rest and noise on quiet samples, then is ready",
          "[signal]") {
  const ContactDetectorOptions o;
  Driver d(o);
  CHECK(d.det.state() == DetectorState::kNoData);
  const double noise_codes = 20.0;
  d.quiet(5000, noise_codes, 1234.0);
  // The first used sample starts calibration; settle_samples are skipped, then
  // calibration_samples are measured.
  CHECK(d.firstOf(DetectorEvent::kReady) == o.settle_samples + o.calibration_samples - 1);
  CHECK(d.countOf(DetectorEvent::kOnset) == 0);
  CHECK(d.det.ready());
  // The rest is measured relative to the first code, which carries one sample of noise.
  const double rest_codes = d.det.rest().x() / kRadPerCode + d.det.referenceAlpha() - kRestCode;
  CHECK(rest_codes == Approx(1234.0).margin(2.0));
  // Noise of the smoothed signal: white input noise times the chain's noise gain (~0.14). The
  // estimate comes from ~1 s of strongly correlated smoothed values: 30 % tolerance.
  const double expected_sigma = noise_codes * kRadPerCode * noiseGain();
  CHECK(noiseGain() == Approx(0.14).margin(0.02));
  CHECK(d.det.noiseSigma() == Approx(expected_sigma).epsilon(0.3));
  CHECK(d.det.onsetThreshold() == Approx(6.0 * d.det.noiseSigma()));
  CHECK(d.det.releaseThreshold() == Approx(3.0 * d.det.noiseSigma()));
  CHECK(d.det.counts().fresh == 5000);
  CHECK(d.det.counts().used == 5000);
}

TEST_CASE("ContactDetector: a noiseless sensor gets the minimum threshold", "[signal]") {
  ContactDetectorOptions o;
  Driver d(o);
  d.quiet(3000, 0.0);
  REQUIRE(d.det.ready());
  CHECK(d.det.noiseSigma() == 0.0);
  CHECK(d.det.onsetThreshold() == o.min_onset_threshold);
  // Four codes of change (above the 3-code floor) is a contact; two is not.
  for (int i = 0; i < 2000; ++i) d.push(2.0 * kRadPerCode, 0.0, 0.0);
  CHECK(d.countOf(DetectorEvent::kOnset) == 0);
  for (int i = 0; i < 2000; ++i) d.push(4.0 * kRadPerCode, 0.0, 0.0);
  CHECK(d.countOf(DetectorEvent::kOnset) == 1);
}

TEST_CASE("ContactDetector: no onset in a minute of noise", "[signal]") {
  for (double noise : {4.0, 20.0}) {
    CAPTURE(noise);
    Driver d({}, 7);
    d.quiet(120000, noise);
    CHECK(d.countOf(DetectorEvent::kReady) == 1);
    CHECK(d.countOf(DetectorEvent::kOnset) == 0);
  }
}

TEST_CASE("ContactDetector: onset and release with hysteresis", "[signal]") {
  // Little noise (1 LSB: the floor sets the threshold), so the levels below sit clearly inside
  // and outside the hysteresis band; with noise at the threshold's own scale a level in the
  // band is crossed by noise excursions (the band is only 3 sigma wide).
  ContactDetectorOptions o;
  Driver d(o);
  const double noise = 1.0;
  d.quiet(3000, noise);
  REQUIRE(d.det.ready());
  const double on = d.det.onsetThreshold();
  CHECK(on == o.min_onset_threshold);
  // Step to 0.7 of the onset threshold in beta only: no contact.
  for (int i = 0; i < 2000; ++i) d.push(0.0, 0.7 * on, noise);
  CHECK(d.countOf(DetectorEvent::kOnset) == 0);
  // A contact along a diagonal: theta uses both axes.
  const long start = d.n;
  for (int i = 0; i < 2000; ++i) d.push(2.0 * on, 2.0 * on, noise);
  REQUIRE(d.countOf(DetectorEvent::kOnset) == 1);
  // The smoothed step crosses the threshold (35 % of the step) within the filter's rise time:
  // ~9 ms for the noiseless step response, 25 ms allowed for noise.
  CHECK(d.firstOf(DetectorEvent::kOnset) - start < 50);
  CHECK(d.det.theta() == Approx(2.0 * std::sqrt(2.0) * on).epsilon(0.1));
  // Back to 0.7 of the onset threshold: above the release threshold (0.5): still touching.
  for (int i = 0; i < 4000; ++i) d.push(0.0, 0.7 * on, noise);
  CHECK(d.det.inContact());
  CHECK(d.countOf(DetectorEvent::kRelease) == 0);
  // Rest and noise are frozen during a contact.
  CHECK(d.det.onsetThreshold() == on);
  // To rest: release after the smoothed signal has been below release_samples long.
  const long down = d.n;
  for (int i = 0; i < 2000; ++i) d.push(0.0, 0.0, noise);
  REQUIRE(d.countOf(DetectorEvent::kRelease) == 1);
  const long release_delay = d.firstOf(DetectorEvent::kRelease) - down;
  CHECK(release_delay >= o.release_samples);
  CHECK(release_delay < o.release_samples + 40);
}

TEST_CASE("ContactDetector: invalid samples are held and counted, never measurements", "[signal]") {
  // Rest tracking off, so the comparison with the twin below is exact.
  ContactDetectorOptions o;
  o.baseline_time_constant_s = 1e12;
  Driver d(o), twin(o);
  Rng noise(3);
  auto fresh = [&] { return WhiskerReading{code(0.0, 4.0, noise), code(0.0, 4.0, noise), 0}; };
  for (int i = 0; i < 3000; ++i) {
    const WhiskerReading r = fresh();
    d.det.push(r);
    twin.det.push(r);
  }
  REQUIRE(d.det.ready());
  const double on = d.det.onsetThreshold();
  const SampleCounts before = d.det.counts();

  // Every third sample is a NO_DATA frame (Alpha = Beta = 0: half a turn from rest if taken as
  // a measurement), an MLX-flagged wild value, a STALE wild value, or a DROPPED wild value.
  // The twin gets the last valid reading again instead: holding must be exactly that.
  const std::uint16_t statuses[] = {
      status::kTimeout,       status::kChecksum, status::kPowerUp, 0x0400 /* field low */,
      0x0200 /* saturated */, status::kStale,    status::kDropped};
  int injected = 0;
  double max_theta = 0.0, max_difference = 0.0;
  WhiskerReading last = fresh();
  for (int i = 0; i < 21000; ++i) {
    if (i % 3 == 2) {
      const std::uint16_t st = statuses[(i / 3) % 7];
      const bool no_data = (st & status::kNoData) != 0;
      d.pushRaw(no_data ? 0 : 60000, no_data ? 0 : 5000, st);
      twin.det.push(last);
      ++injected;
    } else {
      last = fresh();
      d.det.push(last);
      twin.det.push(last);
    }
    max_theta = std::max(max_theta, d.det.theta());
    max_difference = std::max(max_difference, (d.det.deflection() - twin.det.deflection()).norm());
  }
  CHECK(d.countOf(DetectorEvent::kOnset) == 0);
  CHECK(d.countOf(DetectorEvent::kLost) == 0);
  CHECK(max_theta < on);
  CHECK(max_difference < 1e-12);
  const SampleCounts& c = d.det.counts();
  CHECK(c.held - before.held == static_cast<std::uint64_t>(injected));
  CHECK(c.no_data - before.no_data == 3000);
  CHECK(c.sensor_flag - before.sensor_flag == 2000);
  CHECK(c.stale - before.stale == 1000);
  CHECK(c.dropped - before.dropped == 1000);
  CHECK(c.used - before.used == 14000);
  CHECK(twin.det.counts().held == 0);
}

TEST_CASE("ContactDetector: held samples do not count towards calibration", "[signal]") {
  ContactDetectorOptions o;
  Driver d(o);
  // Every other sample after the first is NO_DATA.
  for (int i = 0; i < 2 * (o.settle_samples + o.calibration_samples) + 10; ++i) {
    if (i % 2 == 1) {
      d.pushRaw(0, 0, status::kBusy);
    } else {
      d.push(0.0, 0.0, 4.0);
    }
    if (d.det.ready()) break;
  }
  REQUIRE(d.det.ready());
  CHECK(d.det.counts().used ==
        static_cast<std::uint64_t>(o.settle_samples + o.calibration_samples));
  CHECK(d.det.counts().held == d.det.counts().used - 1);
}

TEST_CASE("ContactDetector: DROPPED-only samples are measurements when accepted", "[signal]") {
  ContactDetectorOptions o;
  o.accept_dropped = true;
  Driver d(o);
  d.quiet(3000, 4.0);
  REQUIRE(d.det.ready());
  for (int i = 0; i < 200; ++i) d.push(0.01, 0.0, 4.0, status::kDropped);
  CHECK(d.countOf(DetectorEvent::kOnset) == 1);
  CHECK(d.det.counts().dropped == 200);
  CHECK(d.det.counts().held == 0);
}

TEST_CASE("ContactDetector: samples before the first valid one are only counted", "[signal]") {
  Driver d;
  for (int i = 0; i < 500; ++i) d.pushRaw(0, 0, status::kPowerUp);
  CHECK(d.det.state() == DetectorState::kNoData);
  CHECK(d.det.counts().held == 500);
  CHECK(d.events.empty());
  d.quiet(2200, 4.0);
  CHECK(d.firstOf(DetectorEvent::kReady) == 500 + 2199);
  // The reference is the first valid code, not the zeros before it.
  CHECK(std::abs(d.det.referenceAlpha() - kRestCode) < 30);
}

TEST_CASE("ContactDetector: a lost whisker comes back measured against its own rest",
          "[signal]") {
  ContactDetectorOptions o;
  Driver d(o);
  d.quiet(3000, 4.0);
  for (int i = 0; i < 500; ++i) d.push(0.01, 0.0, 4.0);  // touching
  REQUIRE(d.det.inContact());
  const long gap = d.n;
  for (int i = 0; i < 200; ++i) d.pushRaw(0, 0, status::kTimeout);
  CHECK(d.firstOf(DetectorEvent::kLost) == gap + o.max_held_samples);
  CHECK(d.det.state() == DetectorState::kNoData);
  CHECK(d.det.theta() == 0.0);
  SECTION("still bent: in contact from the first sample back, the bend never taken as rest") {
    const long back = d.n;
    for (int i = 0; i < 3000; ++i) d.push(0.01, 0.0, 4.0);
    CHECK(d.det.inContact());
    CHECK(d.countOf(DetectorEvent::kReady) == 1);
    CHECK(d.countOf(DetectorEvent::kOnset) == 2);
    CHECK(d.events.back() ==
          std::pair<long, DetectorEvent>{back + o.settle_samples, DetectorEvent::kOnset});
    CHECK(d.det.deflection().x() == Approx(0.01).epsilon(0.1));
  }
  SECTION("back at rest: quiet at once, no new calibration") {
    const long back = d.n;
    d.quiet(3000, 4.0);
    CHECK(d.det.state() == DetectorState::kQuiet);
    CHECK(d.countOf(DetectorEvent::kReady) == 1);
    CHECK(d.countOf(DetectorEvent::kOnset) == 1);
    CHECK(d.events.back().first < back);
  }
  SECTION("restart() forgets the rest: the magnet 300 codes off is a new rest, no onset") {
    d.det.restart();
    const long back = d.n;
    d.quiet(3000, 4.0, 300.0);
    CHECK(d.countOf(DetectorEvent::kReady) == 2);
    CHECK(d.events.back().first == back + o.settle_samples + o.calibration_samples - 1);
    CHECK(d.countOf(DetectorEvent::kOnset) == 1);
  }
}

TEST_CASE("ContactDetector: a rest next to the 16-bit wrap reads continuously", "[signal]") {
  Driver d;
  // Rest at code 65534: noise carries the codes across 65535 -> 0.
  d.quiet(20000, 4.0, 32766.0);
  CHECK(d.countOf(DetectorEvent::kReady) == 1);
  CHECK(d.countOf(DetectorEvent::kOnset) == 0);
  CHECK(d.det.noiseSigma() < 10.0 * kRadPerCode);
  for (int i = 0; i < 200; ++i) d.push(0.01, 0.0, 4.0, 0, 32766.0);
  CHECK(d.countOf(DetectorEvent::kOnset) == 1);
  CHECK(d.det.deflection().x() == Approx(0.01).epsilon(0.2));
}

TEST_CASE("ContactDetector: a calibration disturbed by motion is retried", "[signal]") {
  Driver d;
  // 3 s of a 2 Hz wobble of 0.02 rad (a whisker brushing something at start-up), then rest.
  for (int i = 0; i < 6000; ++i) d.push(0.02 * std::sin(2.0 * kPi * 2.0 * i / 2000.0), 0.0, 4.0);
  CHECK(d.det.state() == DetectorState::kCalibrating);
  CHECK(d.det.calibrationRetries() >= 2);
  d.quiet(4400, 4.0);
  REQUIRE(d.det.ready());
  CHECK(std::abs(d.det.rest().x() + (static_cast<double>(d.det.referenceAlpha()) - kRestCode) *
                                        kRadPerCode) < 3.0 * kRadPerCode);
  CHECK(d.det.noiseSigma() < 4.0 * kRadPerCode);
}

TEST_CASE("ContactDetector: the rest follows a slow drift while quiet", "[signal]") {
  Driver d;
  d.quiet(3000, 4.0);
  const double rest0 = d.det.rest().x();
  // 20 codes (2e-3 rad, six times the onset threshold) over 100 s.
  const int n = 200000;
  for (int i = 0; i < n; ++i) d.push(20.0 * kRadPerCode * i / n, 0.0, 4.0);
  CHECK(d.countOf(DetectorEvent::kOnset) == 0);
  CHECK((d.det.rest().x() - rest0) / kRadPerCode == Approx(20.0).margin(2.0));
}

TEST_CASE("ContactDetector: options are validated with the field named", "[signal]") {
  CHECK(ContactDetectorOptions{}.validate().ok());
  ContactDetectorOptions o;
  o.release_sigmas = 7.0;
  REQUIRE_FALSE(o.validate().ok());
  CHECK_THAT(o.validate().error().message, Catch::Contains("release_sigmas"));
  o = {};
  o.smoothing.low_pass.cutoff_hz = -1.0;
  REQUIRE_FALSE(o.validate().ok());
  CHECK_THAT(o.validate().error().message, Catch::Contains("smoothing.low_pass.cutoff_hz"));
  o = {};
  o.smoothing.low_pass.sample_rate_hz = 1000.0;
  CHECK_FALSE(o.validate().ok());
  o = {};
  o.calibration_samples = 1;
  CHECK_FALSE(o.validate().ok());
}
