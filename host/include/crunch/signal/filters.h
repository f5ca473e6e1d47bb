// The paper's smoothing (§2.5): "low pass filtered (17Hz) to remove oscillations caused by robot
// body movement ... and smoothed with a five-point moving average".
//
// The paper gives only the cutoff. We use a causal Butterworth low-pass built from second-order
// sections (biquads) by the bilinear transform with the cutoff pre-warped, so the digital filter
// is exactly -3 dB at 17 Hz at fs = 2 kHz. Default order 2 (docs/SIGNAL.md, "Filter design"):
//   - the whisk moves the whisker slowly (pi/24 rad/s, a 2 s sweep), so the signal lives well
//     below 5 Hz and a steep cutoff buys nothing;
//   - order 2 overshoots a step by 4.3 % (order 4: 10.8 %), which keeps the peak f1 (eq. 1)
//     close to the true peak on sharp contact onsets;
//   - group delay at DC 13.2 ms (order 4: 24.5 ms), against a 2 s window;
//   - 100 Hz is still attenuated by 31 dB (order 4: 62 dB).
// The moving average of 5 samples adds 2 samples (1 ms) of delay and a null at 400 Hz.
// Training and use run the same filter, so its lag and overshoot are learnt, not an error.
//
// Every filter here is allocation-free per sample (fixed-size state), causal, and O(1) per step;
// not thread-safe (one instance per channel).
#pragma once

#include <array>
#include <complex>

#include "crunch/core/result.h"

namespace crunch::signal {

// H(z) = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2).
struct BiquadCoefficients {
  double b0 = 1.0, b1 = 0.0, b2 = 0.0;
  double a1 = 0.0, a2 = 0.0;

  // The frequency response at `f_hz` for sample rate `fs_hz`.
  std::complex<double> response(double f_hz, double fs_hz) const;
  // Group delay at DC, in samples.
  double groupDelayAtDc() const;
};

// One second-order section, transposed direct form II (the form with the best numerical
// behaviour for floating point).
class Biquad {
 public:
  Biquad() = default;
  explicit Biquad(const BiquadCoefficients& c) : c_(c) {}

  // Sets the state to the steady state for a constant input x0 (output x0 for DC gain 1), so
  // a filter started on a resting whisker shows no start-up transient.
  void reset(double x0);
  double step(double x) {
    const double y = c_.b0 * x + s1_;
    s1_ = c_.b1 * x - c_.a1 * y + s2_;
    s2_ = c_.b2 * x - c_.a2 * y;
    return y;
  }
  const BiquadCoefficients& coefficients() const { return c_; }

 private:
  BiquadCoefficients c_;
  double s1_ = 0.0, s2_ = 0.0;
};

// Causal Butterworth low-pass of even order 2..8 as cascaded biquads.
class ButterworthLowPass {
 public:
  static constexpr int kMaxOrder = 8;

  struct Options {
    int order = 2;            // even, 2..kMaxOrder
    double cutoff_hz = 17.0;  // -3 dB point (paper §2.5)
    double sample_rate_hz = 2000.0;
    // okStatus(), or an Error naming the bad field (odd or out-of-range order, cutoff not in
    // (0, fs/2), non-finite values).
    Status validate() const;
  };

  // Asserts `options.validate()`.
  ButterworthLowPass() : ButterworthLowPass(Options{}) {}
  explicit ButterworthLowPass(const Options& options);

  void reset(double x0);
  double step(double x) {
    for (int i = 0; i < sections_; ++i) x = sections_data_[i].step(x);
    return x;
  }

  std::complex<double> response(double f_hz) const;
  double gain(double f_hz) const { return std::abs(response(f_hz)); }
  // Group delay at DC, seconds.
  double groupDelayAtDc() const;
  int sections() const { return sections_; }
  const BiquadCoefficients& section(int i) const { return sections_data_[i].coefficients(); }
  const Options& options() const { return options_; }

 private:
  Options options_;
  int sections_ = 0;
  std::array<Biquad, kMaxOrder / 2> sections_data_{};
};

// Causal moving average of the last `length` samples (1..kMaxLength).
class MovingAverage {
 public:
  static constexpr int kMaxLength = 64;

  // Asserts 1 <= length <= kMaxLength.
  explicit MovingAverage(int length = 5);

  // Fills the history with x0.
  void reset(double x0);
  // The mean of this and the previous length-1 inputs. Sums the history directly (at most 64
  // additions) rather than keeping a running sum, so no rounding drift builds up over hours.
  double step(double x);

  std::complex<double> response(double f_hz, double fs_hz) const;
  // (length - 1) / 2 samples.
  double groupDelaySamples() const { return 0.5 * (length_ - 1); }
  int length() const { return length_; }

 private:
  int length_;
  int next_ = 0;
  std::array<double, kMaxLength> history_{};
};

// The paper's chain for one channel: low-pass, then moving average.
class SmoothingFilter {
 public:
  struct Options {
    ButterworthLowPass::Options low_pass;
    int moving_average = 5;  // points (paper §2.5)
    Status validate() const;
  };

  // Asserts `options.validate()`.
  SmoothingFilter() : SmoothingFilter(Options{}) {}
  explicit SmoothingFilter(const Options& options);

  void reset(double x0) {
    low_pass_.reset(x0);
    average_.reset(x0);
  }
  double step(double x) { return average_.step(low_pass_.step(x)); }

  std::complex<double> response(double f_hz) const;
  double gain(double f_hz) const { return std::abs(response(f_hz)); }
  double groupDelayAtDc() const;  // seconds

 private:
  ButterworthLowPass low_pass_;
  MovingAverage average_;
};

}  // namespace crunch::signal
