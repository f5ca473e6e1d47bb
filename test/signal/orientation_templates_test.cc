// Eq. 3: templates from labelled 8-channel windows, classification by lowest mean squared
// error, the paper's leave-one-repeat-out protocol, and decimation to 100 Hz.
#include "crunch/signal/orientation_templates.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>

#include "crunch/core/rng.h"
#include "crunch/signal/filters.h"
#include "synthetic.h"

using namespace crunch;
using namespace crunch::signal;
using namespace crunch::signal::testing;

namespace {

constexpr double kBearings[kWhiskers] = {-33.75 * kDegree, -11.25 * kDegree, 11.25 * kDegree,
                                         33.75 * kDegree};

// A full-rate (2 kHz, 4000 samples) 8-channel window of a robot driving into a wall at angle
// psi: each whisker touches with an amplitude and a delay that depend on psi and its bearing,
// with repeat-to-repeat jitter in both, plus sensor noise smoothed like the pipeline does.
WindowMatrix wallWindow(double psi, double noise_rad, Rng& rng) {
  WindowMatrix m = WindowMatrix::Zero(kChannels, 4000);
  for (int w = 0; w < kWhiskers; ++w) {
    const double closeness = 0.5 + 0.5 * std::cos(psi - 0.5 * kPi - 2.0 * kBearings[w]);
    const double amplitude = 0.004 + 0.012 * closeness * (1.0 + 0.03 * rng.normal());
    Bump bump;
    bump.start = 0.05 + 0.4 * (1.0 - closeness) + 0.005 * rng.normal();
    const double beta_share = 0.3 * std::cos(psi);
    SmoothingFilter fa, fb;
    for (int n = 0; n < 4000; ++n) {
      const double b = bump(n * kSamplePeriod);
      m(channelOf(w, 0), n) = amplitude * b + fa.step(noise_rad * rng.normal());
      m(channelOf(w, 1), n) = amplitude * beta_share * b + fb.step(noise_rad * rng.normal());
    }
  }
  return m;
}

struct FullRateSet {
  std::vector<double> angles;
  std::vector<int> repeats;
  std::vector<WindowMatrix> windows;

  std::vector<LabelledWindow> decimated(int decimation) const {
    std::vector<LabelledWindow> out;
    for (size_t i = 0; i < windows.size(); ++i) {
      out.push_back({angles[i], repeats[i], decimateWindow(windows[i], decimation)});
    }
    return out;
  }
};

// The paper's training set: 15 angles x 4 repeats.
FullRateSet wallSet(double noise_rad, std::uint64_t seed) {
  Rng rng(seed);
  FullRateSet set;
  for (int repeat = 0; repeat < 4; ++repeat) {
    for (double psi : defaultOrientationAngles()) {
      set.angles.push_back(psi);
      set.repeats.push_back(repeat);
      set.windows.push_back(wallWindow(psi, noise_rad, rng));
    }
  }
  return set;
}

ContactWindow constantWindow(double v, int columns = 1) {
  return {1, WindowMatrix::Constant(kChannels, columns, v)};
}

}  // namespace

TEST_CASE("Orientation: 15 classes from 20 to 160 degrees", "[signal]") {
  const std::vector<double> a = defaultOrientationAngles();
  REQUIRE(a.size() == 15);
  CHECK(a.front() == Approx(20.0 * kDegree));
  CHECK(a.back() == Approx(160.0 * kDegree));
  CHECK(a[7] == Approx(0.5 * kPi));
}

TEST_CASE("Orientation: templates are class means, eq. 3 is the mean squared error", "[signal]") {
  const OrientationOptions o{.angles = {0.5, 1.0}};
  const std::vector<LabelledWindow> data = {{0.5, 0, constantWindow(1.0, 2)},
                                            {0.5, 1, constantWindow(3.0, 2)},
                                            {1.0, 0, constantWindow(-1.0, 2)}};
  const Result<OrientationModel> m = trainOrientationTemplates(data, o);
  REQUIRE(m.ok());
  REQUIRE(m.value().templates.size() == 2);
  CHECK(m.value().templates[0].windows == 2);
  CHECK(m.value().templates[0].mean.isConstant(2.0));
  CHECK(m.value().templates[1].mean.isConstant(-1.0));
  CHECK(m.value().columns == 2);

  ContactWindow w = constantWindow(0.0, 2);
  w.data(3, 1) = 8.0;  // one element of 16 off
  const OrientationEstimate e = m.value().classify(w);
  // e(T0) = (15 * 4 + 36) / 16, e(T1) = (15 * 1 + 81) / 16.
  REQUIRE(e.errors.size() == 2);
  CHECK(e.errors[0] == Approx(96.0 / 16.0));
  CHECK(e.errors[1] == Approx(96.0 / 16.0));
  CHECK(e.class_index == 0);  // a tie goes to the lower index
  w.data(3, 1) = 7.0;         // e(T0) = 85/16, e(T1) = 79/16
  CHECK(m.value().classify(w).class_index == 1);
  CHECK(m.value().classify(w).angle == 1.0);
}

TEST_CASE("Orientation: leave-one-repeat-out classifies noisy synthetic walls", "[signal]") {
  // Noise of 4e-4 rad (4 codes) per raw sample, smoothed as in the pipeline.
  const FullRateSet set = wallSet(4e-4, 11);
  const Result<CrossValidation> cv = leaveOneRepeatOut(set.decimated(20));
  REQUIRE(cv.ok());
  const CrossValidation& r = cv.value();
  REQUIRE(r.trials.size() == 60);
  REQUIRE(r.per_angle.size() == 15);
  for (const AngleErrors& a : r.per_angle) CHECK(a.errors.size() == 4);
  CHECK(r.accuracy == 1.0);
  CHECK(r.mean_error == 0.0);
  CHECK(r.sd_error == 0.0);
  for (int repeat = 0; repeat < 4; ++repeat) {
    int n = 0;
    for (const OrientationTrial& t : r.trials) n += t.repeat == repeat;
    CHECK(n == 15);
  }
}

TEST_CASE("Orientation: a classifier that cannot separate classes shows in the errors",
          "[signal]") {
  // Huge noise: classification is near chance, and the statistics say so.
  const FullRateSet set = wallSet(0.5, 12);
  const Result<CrossValidation> cv = leaveOneRepeatOut(set.decimated(20));
  REQUIRE(cv.ok());
  CHECK(cv.value().accuracy < 0.5);
  CHECK(cv.value().sd_error > 20.0 * kDegree);
}

namespace {

// For every leave-one-repeat-out test window: the estimate at full rate and at decimation 20.
std::vector<std::pair<OrientationEstimate, OrientationEstimate>> fullVersusDecimated(
    const FullRateSet& set) {
  const std::vector<LabelledWindow> full = set.decimated(1), dec = set.decimated(20);
  std::vector<std::pair<OrientationEstimate, OrientationEstimate>> out;
  for (int repeat = 0; repeat < 4; ++repeat) {
    std::vector<LabelledWindow> train_full, train_dec;
    for (size_t i = 0; i < full.size(); ++i) {
      if (full[i].repeat == repeat) continue;
      train_full.push_back(full[i]);
      train_dec.push_back(dec[i]);
    }
    const OrientationModel m_full = trainOrientationTemplates(train_full).value();
    const OrientationModel m_dec = trainOrientationTemplates(train_dec).value();
    CHECK(m_dec.columns == 200);
    CHECK(m_dec.decimation == 20);
    for (size_t i = 0; i < full.size(); ++i) {
      if (full[i].repeat != repeat) continue;
      out.emplace_back(m_full.classify(full[i].window), m_dec.classify(dec[i].window));
    }
  }
  return out;
}

// Template indices from best to worst.
std::vector<size_t> ranking(const std::vector<double>& errors) {
  std::vector<size_t> r(errors.size());
  for (size_t k = 0; k < r.size(); ++k) r[k] = k;
  std::stable_sort(r.begin(), r.end(), [&](size_t a, size_t b) { return errors[a] < errors[b]; });
  return r;
}

}  // namespace

TEST_CASE("Orientation: decimating to 100 Hz leaves every classification unchanged", "[signal]") {
  // Sensor noise of 4 codes (the Hall model's), smoothed: the whole ranking of the 15
  // templates, not only the winner, is the same at 2 kHz and at 100 Hz. At ten times that
  // noise the winner is the same (lower places may swap where two errors nearly tie).
  for (double noise : {4e-4, 4e-3}) {
    CAPTURE(noise);
    const auto pairs = fullVersusDecimated(wallSet(noise, 21));
    REQUIRE(pairs.size() == 60);
    for (const auto& [full, dec] : pairs) {
      CHECK(full.class_index == dec.class_index);
      if (noise < 1e-3) CHECK(ranking(full.errors) == ranking(dec.errors));
      // Block means drop only the high-frequency part of the noise: e(T) shrinks a little.
      for (size_t k = 0; k < 15; ++k) CHECK(dec.errors[k] <= full.errors[k]);
    }
  }
}

TEST_CASE("Orientation: under heavy noise decimation changes only near-ties", "[signal]") {
  // At noise where half the windows are misclassified, a handful of decisions flip; each one
  // is a tie at full rate (the two templates' errors within 1 %).
  int flips = 0, trials = 0;
  for (std::uint64_t seed : {13, 16}) {
    const auto pairs = fullVersusDecimated(wallSet(0.02, seed));
    for (const auto& [full, dec] : pairs) {
      ++trials;
      if (full.class_index == dec.class_index) continue;
      ++flips;
      const double best = full.errors[full.class_index];
      CHECK((full.errors[dec.class_index] - best) / best < 0.01);
    }
  }
  CHECK(flips <= trials / 20);
}

TEST_CASE("Orientation: bad training data is an error naming the window or class", "[signal]") {
  const OrientationOptions o{.angles = {0.5, 1.0}};
  auto message = [&](const std::vector<LabelledWindow>& d) -> std::string {
    const Result<OrientationModel> m = trainOrientationTemplates(d, o);
    return m.ok() ? std::string("(ok)") : m.error().message;
  };
  std::vector<LabelledWindow> good = {{0.5, 0, constantWindow(1.0, 3)},
                                      {1.0, 0, constantWindow(2.0, 3)},
                                      {0.5, 1, constantWindow(1.5, 3)},
                                      {1.0, 1, constantWindow(2.5, 3)}};
  CHECK(message(good) == "(ok)");
  CHECK_THAT(message({}), Catch::Contains("no windows"));

  std::vector<LabelledWindow> d = good;
  d[2].window = constantWindow(1.0, 4);
  CHECK_THAT(message(d), Catch::Contains("window 2") && Catch::Contains("shape"));
  d = good;
  d[3].window.decimation = 20;
  CHECK_THAT(message(d), Catch::Contains("window 3"));
  d = good;
  d[1].window.data(5, 2) = std::nan("");
  CHECK_THAT(message(d), Catch::Contains("window 1") && Catch::Contains("finite"));
  d = good;
  d[0].angle = 0.7;
  CHECK_THAT(message(d), Catch::Contains("window 0") && Catch::Contains("not one of the classes"));
  d = {good[0], good[2]};
  CHECK_THAT(message(d), Catch::Contains("no window for 57 degrees"));

  // Cross-validation: a fold without a class names the repeat left out.
  d = good;
  d[3].repeat = 0;  // class 1.0 only in repeat 0
  const Result<CrossValidation> cv = leaveOneRepeatOut(d, o);
  REQUIRE_FALSE(cv.ok());
  CHECK_THAT(cv.error().message, Catch::Contains("leaving out repeat 0"));
  for (auto& x : d) x.repeat = 3;
  CHECK_THAT(leaveOneRepeatOut(d, o).error().message, Catch::Contains("at least 2 repeats"));
  CHECK_FALSE(OrientationOptions{.angles = {0.5, 0.5}}.validate().ok());
  CHECK_FALSE(OrientationOptions{.angles = {}}.validate().ok());
}
