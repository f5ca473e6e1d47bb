// The whole signal path on synthetic whisker codes: episodes, alignment, radial distance and
// tip/shaft, orientation, invalid samples, truncation and early finish.
#include "crunch/signal/pipeline.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "synthetic.h"

using namespace crunch;
using namespace crunch::signal;
using namespace crunch::signal::testing;

namespace {

constexpr double kNoise = 4.0;  // LSB, the sim's Hall model (sim/include/crunch_sim/hall_model.h)

SignalPipeline makePipeline(const PipelineOptions& o = {}) {
  Result<SignalPipeline> p = SignalPipeline::create(o);
  REQUIRE(p.ok());
  return std::move(p).value();
}

// Peak deflection falls linearly as the contact moves towards the tip; each whisker has its
// own stiffness. Beta follows Alpha at 0.3 (Touch's default), so f1 = |(alpha, beta)| =
// sqrt(1.09) A, hence r = a1 f1 + a0 with a1 = -1 / (0.3 sqrt(1.09) scale),
// a0 = 0.14 + 0.02 / 0.3.
constexpr double kScale[kWhiskers] = {1.0, 0.9, 1.1, 0.95};
double amplitudeAt(int w, double r) { return kScale[w] * (0.02 + 0.3 * (0.14 - r)); }
double trueA1(int w) { return -1.0 / (0.3 * std::sqrt(1.09) * kScale[w]); }
constexpr double kTrueA0 = 0.14 + 0.02 / 0.3;

// Every whisker touches at its own r; amplitude jitter equivalent to sigma_r.
Touches radialTouches(const std::array<double, kWhiskers>& r, double sigma_r, Rng& rng) {
  Touches t;
  for (int w = 0; w < kWhiskers; ++w) {
    t[w].amplitude = amplitudeAt(w, r[w]) + kScale[w] * 0.3 * sigma_r * rng.normal();
    t[w].delay = 0.02 * w;
  }
  return t;
}

constexpr double kBearings[kWhiskers] = {-33.75 * kDegree, -11.25 * kDegree, 11.25 * kDegree,
                                         33.75 * kDegree};

// A drive into a wall at angle psi (as in orientation_templates_test.cc).
Touches wallTouches(double psi, Rng& rng) {
  Touches t;
  for (int w = 0; w < kWhiskers; ++w) {
    const double closeness =
        0.5 + 0.5 * std::cos(psi - 0.5 * std::numbers::pi - 2.0 * kBearings[w]);
    t[w].amplitude = (0.004 + 0.012 * closeness) * (1.0 + 0.03 * rng.normal());
    t[w].beta_share = 0.3 * std::cos(psi);
    t[w].delay = 0.4 * (1.0 - closeness) + 0.005 * rng.normal();
  }
  return t;
}

}  // namespace

TEST_CASE("Pipeline: an episode is aligned to the first onset of any whisker", "[signal]") {
  SignalPipeline p = makePipeline();
  Rng rng(1);
  std::vector<SampleFrame> s = quiet(kCalibrationSeconds, kNoise, rng);
  Touches t;
  t[0] = {0.01, 0.3, 0.0};
  t[2] = {0.02, -0.5, 0.1};  // 100 ms later
  append(s, contactFrames(t, 3.0, kNoise, rng));
  const std::vector<ContactEpisode> e = feed(p, s);
  REQUIRE(e.size() == 1);
  const ContactEpisode& ep = e[0];
  // The contact starts 0.1 s into the segment; the smoothed signal crosses the threshold
  // within the rise.
  const double onset_s = static_cast<double>(ep.start_sample) * kSamplePeriod - kCalibrationSeconds;
  CHECK(onset_s > 0.1);
  CHECK(onset_s < 0.2);
  CHECK(ep.touched_count == 2);
  CHECK(ep.whiskers[0].touched);
  CHECK(ep.whiskers[0].onset_sample == 0);
  CHECK(ep.whiskers[2].touched);
  // 100 ms later, less the head start whisker 2's larger deflection gives it at the threshold.
  CHECK(ep.whiskers[2].onset_sample == Approx(200).margin(30));
  CHECK_FALSE(ep.whiskers[1].touched);
  CHECK_FALSE(ep.whiskers[3].touched);
  // f1 (eq. 1): the peak of |(alpha, beta)| = amplitude * sqrt(1 + share^2), during the hold.
  CHECK(ep.whiskers[0].f1 == Approx(0.01 * std::sqrt(1.09)).epsilon(0.01));
  CHECK(ep.whiskers[2].f1 == Approx(0.02 * std::sqrt(1.25)).epsilon(0.01));
  const double peak2 = ep.whiskers[2].peak_time_s;
  CHECK(peak2 > 0.1 + 0.3 - 0.05);
  CHECK(peak2 < 0.1 + 0.8 + 0.05);
  CHECK(ep.whiskers[1].f1 < 1e-3);  // untouched: noise level
  // Window: 2 s from the onset, decimated to 200 columns; whisker 2's beta sits at -0.01 rad
  // during its hold (0.4 .. 0.9 s after the first onset, columns 40 .. 90).
  CHECK(ep.window_complete);
  REQUIRE(ep.window.data.cols() == 200);
  CHECK(ep.window.data(channelOf(2, 1), 65) == Approx(-0.01).epsilon(0.02));
  CHECK(ep.window.data(channelOf(0, 0), 50) == Approx(0.01).epsilon(0.02));
  CHECK(std::abs(ep.window.data(channelOf(3, 0), 50)) < 1e-3);
  CHECK(ep.length_samples >= 4000);
  CHECK(ep.reliable);
  CHECK_FALSE(ep.truncated);
  CHECK(ep.kind == ContactKind::kUnknown);  // no radial model
  CHECK_FALSE(ep.whiskers[0].has_r);
  CHECK_FALSE(ep.has_orientation);
  CHECK(p.counts().episodes == 1);
}

TEST_CASE("Pipeline: radial lines trained from episodes predict r and decide tip or shaft",
          "[signal]") {
  SignalPipeline p = makePipeline();
  Rng rng(2);
  const double sigma_r = 0.002;
  // Training as in §2.4: contacts every 10 mm over the 50 mm nearest the tip, 5 at each.
  std::vector<RadialTrainingSample> training;
  feed(p, quiet(kCalibrationSeconds, kNoise, rng));
  for (int mm = 90; mm <= 140; mm += 10) {
    for (int k = 0; k < 5; ++k) {
      const double r = mm * 1e-3;
      const std::vector<ContactEpisode> e =
          feed(p, contactFrames(radialTouches({r, r, r, r}, sigma_r, rng), 3.0, kNoise, rng));
      REQUIRE(e.size() == 1);
      for (int w = 0; w < kWhiskers; ++w) {
        REQUIRE(e[0].whiskers[w].touched);
        training.push_back({w, e[0].whiskers[w].f1, r});
      }
    }
  }
  const Result<RadialFit> fit = fitRadialModel(training);
  REQUIRE(fit.ok());
  for (int w = 0; w < kWhiskers; ++w) {
    CAPTURE(w);
    const RadialLine& l = fit.value().model.whiskers[w];
    CHECK(l.a1 == Approx(trueA1(w)).epsilon(0.05));
    // f1 carries the smoothed noise's small positive bias; a0 absorbs it.
    CHECK(l.a0 == Approx(kTrueA0).margin(0.003));
    CHECK(fit.value().summary.sigma[w] == Approx(sigma_r).epsilon(0.4));
  }
  p.setRadialModel(fit.value().model);

  // Tip contacts on every whisker.
  std::vector<ContactEpisode> e =
      feed(p, contactFrames(radialTouches({0.10, 0.12, 0.13, 0.11}, 0.0, rng), 3.0, kNoise, rng));
  REQUIRE(e.size() == 1);
  const std::array<double, kWhiskers> expected = {0.10, 0.12, 0.13, 0.11};
  for (int w = 0; w < kWhiskers; ++w) {
    CHECK(e[0].whiskers[w].has_r);
    CHECK(e[0].whiskers[w].r == Approx(expected[w]).margin(0.004));
    CHECK(e[0].whiskers[w].tip);
  }
  CHECK(e[0].kind == ContactKind::kTip);
  // One whisker touches 70 mm from its base: a shaft contact, move and retry.
  Touches t = radialTouches({0.12, 0.07, 0.12, 0.12}, 0.0, rng);
  t[3].amplitude = 0.0;  // whisker 3 does not touch
  e = feed(p, contactFrames(t, 3.0, kNoise, rng));
  REQUIRE(e.size() == 1);
  CHECK(e[0].kind == ContactKind::kShaft);
  CHECK_FALSE(e[0].whiskers[1].tip);
  CHECK(e[0].whiskers[1].extrapolated);
  CHECK(e[0].whiskers[1].r == Approx(0.07).margin(0.006));
  CHECK(e[0].whiskers[0].tip);
  CHECK_FALSE(e[0].whiskers[3].touched);
  CHECK_FALSE(e[0].whiskers[3].has_r);
  CHECK(e[0].touched_count == 3);
}

TEST_CASE("Pipeline: orientation templates from episode windows classify new walls", "[signal]") {
  SignalPipeline p = makePipeline();
  Rng rng(3);
  feed(p, quiet(kCalibrationSeconds, kNoise, rng));
  std::vector<LabelledWindow> training;
  for (int repeat = 0; repeat < 4; ++repeat) {
    for (double psi : defaultOrientationAngles()) {
      const std::vector<ContactEpisode> e =
          feed(p, contactFrames(wallTouches(psi, rng), 3.0, kNoise, rng));
      REQUIRE(e.size() == 1);
      REQUIRE(e[0].window_complete);
      training.push_back({psi, repeat, e[0].window});
    }
  }
  const Result<CrossValidation> cv = leaveOneRepeatOut(training);
  REQUIRE(cv.ok());
  CHECK(cv.value().accuracy == 1.0);

  const Result<OrientationModel> model = trainOrientationTemplates(training);
  REQUIRE(model.ok());
  REQUIRE(p.setOrientationModel(model.value()).ok());
  for (double psi : defaultOrientationAngles()) {
    const std::vector<ContactEpisode> e =
        feed(p, contactFrames(wallTouches(psi, rng), 3.0, kNoise, rng));
    REQUIRE(e.size() == 1);
    REQUIRE(e[0].has_orientation);
    CHECK(e[0].orientation.angle == Approx(psi));
    CHECK(e[0].orientation.errors.size() == 15);
  }
}

TEST_CASE("Pipeline: corrupt and invalid samples never enter the episode", "[signal]") {
  Rng rng(4);
  std::vector<SampleFrame> clean = quiet(kCalibrationSeconds, kNoise, rng);
  for (int k = 0; k < 4; ++k) {
    append(clean,
           contactFrames(radialTouches({0.10, 0.11, 0.12, 0.13}, 0.0, rng), 3.0, kNoise, rng));
  }
  // 3 % of readings replaced: NO_DATA (Alpha = Beta = 0, half a turn from rest if believed),
  // or flagged by the sensor, STALE or DROPPED with wild values.
  std::vector<SampleFrame> corrupt = clean;
  const std::uint16_t statuses[] = {status::kTimeout, status::kBusy,  0x0400,
                                    0x0200,           status::kStale, status::kDropped};
  std::array<std::uint64_t, kWhiskers> injected{};
  Rng pick(5);
  for (size_t i = 0; i < corrupt.size(); ++i) {
    for (int w = 0; w < kWhiskers; ++w) {
      if (pick.uniform() >= 0.03) continue;
      const std::uint16_t st = statuses[pick.below(6)];
      const bool no_data = (st & status::kNoData) != 0;
      corrupt[i][w] = {static_cast<std::uint16_t>(no_data ? 0 : pick.below(65536)),
                       static_cast<std::uint16_t>(no_data ? 0 : pick.below(65536)), st};
      ++injected[w];
    }
  }
  SignalPipeline a = makePipeline(), b = makePipeline();
  const std::vector<ContactEpisode> ea = feed(a, clean), eb = feed(b, corrupt);
  REQUIRE(ea.size() == 4);
  REQUIRE(eb.size() == ea.size());
  for (size_t k = 0; k < ea.size(); ++k) {
    CAPTURE(k);
    CHECK(eb[k].start_sample == Approx(ea[k].start_sample).margin(10));
    CHECK(eb[k].reliable);
    for (int w = 0; w < kWhiskers; ++w) {
      CHECK(eb[k].whiskers[w].touched);
      CHECK(eb[k].whiskers[w].f1 == Approx(ea[k].whiskers[w].f1).epsilon(0.01));
      CHECK(eb[k].whiskers[w].held_samples > 0);
    }
    // Nothing like the wild values (radians, up to pi) reaches the window.
    CHECK(eb[k].window.data.cwiseAbs().maxCoeff() < 0.04);
    CHECK((eb[k].window.data - ea[k].window.data).cwiseAbs().maxCoeff() < 1e-3);
  }
  for (int w = 0; w < kWhiskers; ++w) {
    CHECK(b.detector(w).counts().held == injected[w]);
    CHECK(b.detector(w).counts().used + injected[w] == corrupt.size());
  }
}

TEST_CASE("Pipeline: a dead whisker board degrades episodes and says so", "[signal]") {
  SignalPipeline p = makePipeline();
  Rng rng(6);
  std::vector<SampleFrame> s = quiet(kCalibrationSeconds, kNoise, rng);
  append(s, contactFrames(radialTouches({0.1, 0.1, 0.1, 0.1}, 0.0, rng), 3.0, kNoise, rng));
  for (SampleFrame& f : s) f[3] = {0, 0, status::kTimeout};
  const std::vector<ContactEpisode> e = feed(p, s);
  REQUIRE(e.size() == 1);
  CHECK(e[0].touched_count == 3);
  CHECK_FALSE(e[0].whiskers[3].touched);
  CHECK_FALSE(e[0].reliable);
  CHECK(e[0].whiskers[3].held_samples == e[0].length_samples);
  CHECK(p.detector(3).state() == DetectorState::kNoData);
  CHECK(p.counts().unreliable == 1);

  // A whisker lost in the middle of a contact marks the episode.
  SignalPipeline q = makePipeline();
  s = quiet(kCalibrationSeconds, kNoise, rng);
  std::vector<SampleFrame> c =
      contactFrames(radialTouches({0.1, 0.1, 0.1, 0.1}, 0.0, rng), 3.0, kNoise, rng);
  for (size_t i = 1000; i < 1300; ++i) c[i][1] = {0, 0, status::kChecksum};
  append(s, c);
  const std::vector<ContactEpisode> f = feed(q, s);
  REQUIRE(f.size() == 1);
  CHECK(f[0].whiskers[1].lost);
  CHECK_FALSE(f[0].reliable);
}

TEST_CASE("Pipeline: a contact that never releases is truncated, and starts nothing new",
          "[signal]") {
  PipelineOptions o;
  o.max_episode_samples = 8000;
  SignalPipeline p = makePipeline(o);
  Rng rng(7);
  std::vector<SampleFrame> s = quiet(kCalibrationSeconds, kNoise, rng);
  Touches t;
  t[1].amplitude = 0.01;
  // Pressed against something for 10 s, then released, then a new touch.
  append(s, contactFrames(t, 10.0, kNoise, rng, 0.1, Bump{.rise = 0.3, .hold = 9.0, .fall = 0.3}));
  append(s, contactFrames(t, 3.0, kNoise, rng));
  const std::vector<ContactEpisode> e = feed(p, s);
  REQUIRE(e.size() == 2);
  CHECK(e[0].truncated);
  CHECK(e[0].length_samples == 8000);
  CHECK(e[0].window_complete);
  CHECK_FALSE(e[1].truncated);
  // The second episode is the new touch, not the tail of the first.
  const double second_s = static_cast<double>(e[1].start_sample) * kSamplePeriod;
  CHECK(second_s > kCalibrationSeconds + 10.0);
  CHECK(p.counts().truncated == 1);
}

TEST_CASE("Pipeline: finish() ends an episode early without an orientation", "[signal]") {
  SignalPipeline p = makePipeline();
  Rng rng(8);
  OrientationModel m;
  m.decimation = 20;
  m.columns = 200;
  m.templates.push_back({1.0, 1, WindowMatrix::Zero(kChannels, 200)});
  REQUIRE(p.setOrientationModel(m).ok());
  CHECK(p.finish() == nullptr);
  feed(p, quiet(kCalibrationSeconds, kNoise, rng));
  Touches t;
  t[0].amplitude = 0.01;
  const std::vector<SampleFrame> c = contactFrames(t, 3.0, kNoise, rng);
  const std::vector<SampleFrame> first(c.begin(), c.begin() + 1000);
  CHECK(feed(p, first).empty());
  REQUIRE(p.inEpisode());
  const ContactEpisode* e = p.finish();
  REQUIRE(e != nullptr);
  CHECK(e->finished_early);
  CHECK_FALSE(e->window_complete);
  CHECK_FALSE(e->has_orientation);
  CHECK_FALSE(p.inEpisode());
  // The rest of the same touch starts no new episode.
  CHECK(feed(p, std::vector<SampleFrame>(c.begin() + 1000, c.end())).empty());
}

TEST_CASE("Pipeline: models must fit the window, options are validated", "[signal]") {
  SignalPipeline p = makePipeline();
  OrientationModel m;
  m.decimation = 10;
  m.columns = 400;
  m.templates.push_back({1.0, 1, WindowMatrix::Zero(kChannels, 400)});
  Status s = p.setOrientationModel(m);
  REQUIRE_FALSE(s.ok());
  CHECK_THAT(s.error().message, Catch::Contains("decimation 10") && Catch::Contains("retrain"));
  CHECK_FALSE(p.hasOrientationModel());
  m.decimation = 20;
  m.columns = 200;
  m.templates[0].mean = WindowMatrix::Zero(kChannels, 200);
  SignalModels models;
  models.orientation = m;
  for (RadialLine& line : models.radial.whiskers) {  // a fitted line of the whisker's scale
    line = {.a1 = -3.3, .a0 = 0.2, .sigma = 0.002, .samples = 30, .f1_min = 0.01,
            .f1_max = 0.04, .r_min = 0.09, .r_max = 0.14};
  }
  models.radial.whiskers[2].a1 = std::nan("");
  s = p.setModels(models);
  REQUIRE_FALSE(s.ok());
  CHECK_THAT(s.error().message, Catch::Contains("radial.whiskers[2].a1"));
  models.radial.whiskers[2].a1 = -3.0;
  REQUIRE(p.setModels(models).ok());
  CHECK(p.hasRadialModel());
  CHECK(p.hasOrientationModel());
  p.clearModels();
  CHECK_FALSE(p.hasRadialModel());

  PipelineOptions o;
  o.max_episode_samples = 100;
  Result<SignalPipeline> bad = SignalPipeline::create(o);
  REQUIRE_FALSE(bad.ok());
  CHECK_THAT(bad.error().message, Catch::Contains("max_episode_samples"));
  o = {};
  o.detector.onset_sigmas = 0.0;
  CHECK_THAT(SignalPipeline::create(o).error().message, Catch::Contains("detector.onset_sigmas"));
  o = {};
  o.window.decimation = 7;
  CHECK_THAT(SignalPipeline::create(o).error().message, Catch::Contains("window.decimation"));
}
