// Builders for synthetic whisker signals shared by the signal tests: MLX90333 codes from
// deflection angles (the sim's Hall model convention: rest 32768, 65536 / 2 pi codes per
// radian), smooth contact bumps, and streams of SampleFrames.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <numbers>
#include <vector>

#include "crunch/core/rng.h"
#include "crunch/signal/pipeline.h"
#include "crunch/signal/sample.h"

namespace crunch::signal::testing {

inline constexpr double kCodesPerRadian = 65536.0 / (2.0 * std::numbers::pi);
inline constexpr double kRestCode = 32768.0;
inline constexpr double kDegree = std::numbers::pi / 180.0;

// A code for `angle` radians from rest (plus `rest_offset` codes), with Gaussian noise of
// `noise_codes` LSB, wrapped to 16 bits.
inline std::uint16_t code(double angle, double noise_codes, Rng& rng, double rest_offset = 0.0) {
  const double c =
      std::round(kRestCode + rest_offset + angle * kCodesPerRadian + noise_codes * rng.normal());
  const long v = static_cast<long>(c) % 65536;
  return static_cast<std::uint16_t>(v < 0 ? v + 65536 : v);
}

// A smooth contact: 0 before `start`, raised-cosine rise over `rise`, flat for `hold`,
// raised-cosine fall over `fall`; peak value 1. Times in seconds.
struct Bump {
  double start = 0.0;
  double rise = 0.3;
  double hold = 0.5;
  double fall = 0.3;

  double operator()(double t) const {
    const double u = t - start;
    if (u <= 0.0) return 0.0;
    if (u < rise) return 0.5 - 0.5 * std::cos(std::numbers::pi * u / rise);
    if (u < rise + hold) return 1.0;
    const double v = u - rise - hold;
    if (v < fall) return 0.5 + 0.5 * std::cos(std::numbers::pi * v / fall);
    return 0.0;
  }
  double end() const { return start + rise + hold + fall; }
};

// Deflection (alpha, beta) of every whisker at time t, radians.
using DeflectionFn = std::function<std::array<std::array<double, 2>, kWhiskers>(double t)>;

// Frames for `seconds` of the deflection function from time t0 with noise.
inline std::vector<SampleFrame> frames(const DeflectionFn& f, double t0, double seconds,
                                       double noise_codes, Rng& rng) {
  const auto n = static_cast<size_t>(std::llround(seconds * kSampleRateHz));
  std::vector<SampleFrame> out(n);
  for (size_t i = 0; i < n; ++i) {
    const auto d = f(t0 + static_cast<double>(i) * kSamplePeriod);
    for (int w = 0; w < kWhiskers; ++w) {
      out[i][w].alpha = code(d[w][0], noise_codes, rng);
      out[i][w].beta = code(d[w][1], noise_codes, rng);
      out[i][w].status = 0;
    }
  }
  return out;
}

// Quiet frames (rest plus noise).
inline std::vector<SampleFrame> quiet(double seconds, double noise_codes, Rng& rng) {
  return frames([](double) { return std::array<std::array<double, 2>, kWhiskers>{}; }, 0.0, seconds,
                noise_codes, rng);
}

// Feeds frames; collects copies of the completed episodes.
inline std::vector<ContactEpisode> feed(SignalPipeline& p, const std::vector<SampleFrame>& fs) {
  std::vector<ContactEpisode> episodes;
  for (const SampleFrame& f : fs) {
    if (const ContactEpisode* e = p.push(f)) episodes.push_back(*e);
  }
  return episodes;
}

// One whisker's part in a synthetic contact: a Bump of `amplitude` radians in Alpha and
// amplitude * beta_share in Beta, starting `delay` seconds after the segment's lead-in.
// amplitude 0: the whisker does not touch.
struct Touch {
  double amplitude = 0.0;
  double beta_share = 0.3;
  double delay = 0.0;
};
using Touches = std::array<Touch, kWhiskers>;

// A contact segment of `seconds`: quiet for `lead` seconds, then each touching whisker's bump.
inline std::vector<SampleFrame> contactFrames(const Touches& touches, double seconds,
                                              double noise_codes, Rng& rng, double lead = 0.1,
                                              const Bump& shape = {}) {
  return frames(
      [&](double t) {
        std::array<std::array<double, 2>, kWhiskers> d{};
        for (int w = 0; w < kWhiskers; ++w) {
          Bump b = shape;
          b.start = lead + touches[w].delay;
          const double v = touches[w].amplitude * b(t);
          d[w] = {v, v * touches[w].beta_share};
        }
        return d;
      },
      0.0, seconds, noise_codes, rng);
}

inline void append(std::vector<SampleFrame>& dst, const std::vector<SampleFrame>& src) {
  dst.insert(dst.end(), src.begin(), src.end());
}

// The pipeline's calibration time with default options, plus margin: quiet this long first.
inline constexpr double kCalibrationSeconds = 1.5;

}  // namespace crunch::signal::testing
