// Eqs. 1-2: least-squares lines from peak deflection to radial distance, Table 1 statistics,
// and the tip/shaft decision.
#include "crunch/signal/radial_distance.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "crunch/core/rng.h"

using namespace crunch;
using namespace crunch::signal;

namespace {

struct TrueLine {
  double a1, a0;
};
// Deflection falls as the contact moves out towards the tip: a1 < 0.
constexpr TrueLine kTruth[kWhiskers] = {{-3.2, 0.21}, {-2.8, 0.20}, {-3.6, 0.22}, {-3.0, 0.205}};
constexpr double kSigma[kWhiskers] = {0.00278, 0.00182, 0.00437, 0.00568};  // Table 1

// The paper's protocol (§2.4): contacts every 10 mm over the 50 mm nearest the tip (r = 90 ..
// 140 mm of the 140 mm external length), `per_point` contacts at each, r observed with noise.
std::vector<RadialTrainingSample> trainingSet(int per_point, double noise_scale, Rng& rng) {
  std::vector<RadialTrainingSample> data;
  for (int w = 0; w < kWhiskers; ++w) {
    for (int mm = 90; mm <= 140; mm += 10) {
      for (int k = 0; k < per_point; ++k) {
        const double r = mm * 1e-3;
        const double f1 = (r - kTruth[w].a0) / kTruth[w].a1;
        data.push_back({w, f1, r + noise_scale * kSigma[w] * rng.normal()});
      }
    }
  }
  return data;
}

}  // namespace

TEST_CASE("Radial: noiseless data gives the true lines exactly", "[signal]") {
  Rng rng(1);
  const Result<RadialFit> fit = fitRadialModel(trainingSet(5, 0.0, rng));
  REQUIRE(fit.ok());
  for (int w = 0; w < kWhiskers; ++w) {
    const RadialLine& l = fit.value().model.whiskers[w];
    CHECK(l.a1 == Approx(kTruth[w].a1).epsilon(1e-9));
    CHECK(l.a0 == Approx(kTruth[w].a0).epsilon(1e-9));
    CHECK(l.sigma < 1e-9);
    CHECK(l.samples == 30);
    CHECK(l.r_min == Approx(0.09));
    CHECK(l.r_max == Approx(0.14));
  }
}

TEST_CASE("Radial: noisy data recovers a0, a1 and sigma per whisker (Table 1)", "[signal]") {
  Rng rng(42);
  const int per_point = 50;  // 300 contacts per whisker: sigma to ~4 %
  const Result<RadialFit> fit = fitRadialModel(trainingSet(per_point, 1.0, rng));
  REQUIRE(fit.ok());
  const RadialFitSummary& s = fit.value().summary;
  double sum_sq = 0.0;
  for (int w = 0; w < kWhiskers; ++w) {
    CAPTURE(w);
    const RadialLine& l = fit.value().model.whiskers[w];
    // Standard error of the slope: sigma / (sqrt(n) sd(f1)); f1 spans 50 mm / |a1|.
    const double sd_f1 = 0.0171 / std::abs(kTruth[w].a1);
    const double se_a1 = kSigma[w] / (std::sqrt(300.0) * sd_f1);
    CHECK(l.a1 == Approx(kTruth[w].a1).margin(4.0 * se_a1));
    CHECK(l.predict((0.115 - kTruth[w].a0) / kTruth[w].a1) == Approx(0.115).margin(0.001));
    CHECK(s.sigma[w] == Approx(kSigma[w]).epsilon(0.12));
    CHECK(s.samples[w] == 300);
    sum_sq += kSigma[w] * kSigma[w];
  }
  CHECK(s.pooled_sigma == Approx(std::sqrt(sum_sq / 4.0)).epsilon(0.08));
  // One line through all whiskers fits worse than each whisker's own line.
  CHECK(s.combined.samples == 1200);
  CHECK(s.combined.sigma > s.pooled_sigma);
}

TEST_CASE("Radial: the tip zone decides tip or shaft", "[signal]") {
  Rng rng(3);
  Result<RadialFit> fit = fitRadialModel(trainingSet(5, 0.0, rng));
  REQUIRE(fit.ok());
  const RadialModel& m = fit.value().model;
  const auto f1For = [&](int w, double r) { return (r - kTruth[w].a0) / kTruth[w].a1; };
  // Default: the 50 mm nearest the tip of 140 mm, i.e. r >= 90 mm.
  RadialEstimate e = m.estimate(1, f1For(1, 0.12));
  CHECK(e.r == Approx(0.12));
  CHECK(e.tip);
  CHECK_FALSE(e.extrapolated);
  e = m.estimate(1, f1For(1, 0.0905));
  CHECK(e.tip);
  e = m.estimate(1, f1For(1, 0.0895));
  CHECK_FALSE(e.tip);
  CHECK(e.extrapolated);  // below the trained 90 mm
  e = m.estimate(2, f1For(2, 0.05));
  CHECK_FALSE(e.tip);
  CHECK(e.r == Approx(0.05));
  // Past the tip (noise) is still a tip contact, but outside the training range.
  e = m.estimate(0, f1For(0, 0.145));
  CHECK(e.tip);
  CHECK(e.extrapolated);
  // A narrower zone.
  Rng rng2(3);
  fit = fitRadialModel(trainingSet(5, 0.0, rng2), {.external_length = 0.14, .tip_zone = 0.02});
  REQUIRE(fit.ok());
  CHECK_FALSE(fit.value().model.estimate(1, f1For(1, 0.115)).tip);
  CHECK(fit.value().model.estimate(1, f1For(1, 0.125)).tip);
}

TEST_CASE("Radial: bad training data is an error naming the sample or whisker", "[signal]") {
  Rng rng(5);
  const std::vector<RadialTrainingSample> good = trainingSet(1, 1.0, rng);
  auto message = [](const std::vector<RadialTrainingSample>& d,
                    const RadialOptions& o = {}) -> std::string {
    const Result<RadialFit> f = fitRadialModel(d, o);
    return f.ok() ? std::string("(ok)") : f.error().message;
  };
  CHECK(message(good) == "(ok)");

  std::vector<RadialTrainingSample> d = good;
  d[7].whisker = 4;
  CHECK_THAT(message(d), Catch::Contains("sample 7") && Catch::Contains("whisker 4"));
  d = good;
  d[3].f1 = std::nan("");
  CHECK_THAT(message(d), Catch::Contains("sample 3") && Catch::Contains("f1"));
  d = good;
  d[2].r = INFINITY;
  CHECK_THAT(message(d), Catch::Contains("sample 2") && Catch::Contains("r is not finite"));
  // Whisker 2 with only two contacts.
  d.clear();
  for (const auto& s : good) {
    if (s.whisker != 2) d.push_back(s);
  }
  d.push_back({2, 0.01, 0.1});
  d.push_back({2, 0.02, 0.11});
  CHECK_THAT(message(d), Catch::Contains("whisker 2") && Catch::Contains("at least 3"));
  // Whisker 1 always at the same f1.
  d = good;
  for (auto& s : d) {
    if (s.whisker == 1) s.f1 = 0.02;
  }
  CHECK_THAT(message(d), Catch::Contains("whisker 1") && Catch::Contains("same"));
  CHECK_THAT(message(good, {.external_length = 0.14, .tip_zone = 0.2}),
             Catch::Contains("tip_zone"));
}
