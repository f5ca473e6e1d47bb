#include "crunch/signal/filters.h"

#include <cassert>
#include <cmath>
#include <numbers>
#include <string>

namespace crunch::signal {

namespace {

constexpr double kPi = std::numbers::pi;

// e^{-j w k}
std::complex<double> delay(double w, int k) { return std::polar(1.0, -w * k); }

}  // namespace

std::complex<double> BiquadCoefficients::response(double f_hz, double fs_hz) const {
  const double w = 2.0 * kPi * f_hz / fs_hz;
  const std::complex<double> num = b0 + b1 * delay(w, 1) + b2 * delay(w, 2);
  const std::complex<double> den = 1.0 + a1 * delay(w, 1) + a2 * delay(w, 2);
  return num / den;
}

double BiquadCoefficients::groupDelayAtDc() const {
  // For P(z) = sum p_k z^-k the group delay at w = 0 is sum k p_k / sum p_k; H = N / D.
  return (b1 + 2.0 * b2) / (b0 + b1 + b2) - (a1 + 2.0 * a2) / (1.0 + a1 + a2);
}

void Biquad::reset(double x0) {
  // Steady state of the transposed direct form II for a constant input with DC gain g:
  // y = g x0, s2 = b2 x0 - a2 y, s1 = b1 x0 - a1 y + s2.
  const double g = (c_.b0 + c_.b1 + c_.b2) / (1.0 + c_.a1 + c_.a2);
  const double y = g * x0;
  s2_ = c_.b2 * x0 - c_.a2 * y;
  s1_ = c_.b1 * x0 - c_.a1 * y + s2_;
}

Status ButterworthLowPass::Options::validate() const {
  if (order < 2 || order > kMaxOrder || order % 2 != 0) {
    return Error{"low_pass.order: expected an even number from 2 to " + std::to_string(kMaxOrder) +
                 ", got " + std::to_string(order)};
  }
  if (!std::isfinite(sample_rate_hz) || sample_rate_hz <= 0.0) {
    return Error{"low_pass.sample_rate_hz: expected a positive number"};
  }
  if (!std::isfinite(cutoff_hz) || cutoff_hz <= 0.0 || cutoff_hz >= 0.5 * sample_rate_hz) {
    return Error{"low_pass.cutoff_hz: expected a number in (0, sample_rate_hz / 2)"};
  }
  return okStatus();
}

ButterworthLowPass::ButterworthLowPass(const Options& options) : options_(options) {
  assert(options.validate().ok());
  const int n = options.order;
  sections_ = n / 2;
  // Pre-warping: the analogue prototype's cutoff is placed where the bilinear transform maps it
  // onto cutoff_hz exactly. K = tan(pi fc / fs) is that cutoff in the transform's units.
  const double k = std::tan(kPi * options.cutoff_hz / options.sample_rate_hz);
  const double k2 = k * k;
  for (int i = 0; i < sections_; ++i) {
    // Butterworth pole pair i: s^2 + (1/Q) s + 1 with 1/Q = 2 sin((2i+1) pi / (2n)).
    const double inv_q = 2.0 * std::sin((2 * i + 1) * kPi / (2.0 * n));
    const double norm = 1.0 / (1.0 + k * inv_q + k2);
    BiquadCoefficients c;
    c.b0 = k2 * norm;
    c.b1 = 2.0 * c.b0;
    c.b2 = c.b0;
    c.a1 = 2.0 * (k2 - 1.0) * norm;
    c.a2 = (1.0 - k * inv_q + k2) * norm;
    sections_data_[i] = Biquad(c);
  }
  reset(0.0);
}

void ButterworthLowPass::reset(double x0) {
  // DC gain of every section is 1, so each section's steady input and output are x0.
  for (int i = 0; i < sections_; ++i) sections_data_[i].reset(x0);
}

std::complex<double> ButterworthLowPass::response(double f_hz) const {
  std::complex<double> h = 1.0;
  for (int i = 0; i < sections_; ++i) {
    h *= sections_data_[i].coefficients().response(f_hz, options_.sample_rate_hz);
  }
  return h;
}

double ButterworthLowPass::groupDelayAtDc() const {
  double samples = 0.0;
  for (int i = 0; i < sections_; ++i) samples += sections_data_[i].coefficients().groupDelayAtDc();
  return samples / options_.sample_rate_hz;
}

MovingAverage::MovingAverage(int length) : length_(length) {
  assert(length >= 1 && length <= kMaxLength);
  reset(0.0);
}

void MovingAverage::reset(double x0) {
  history_.fill(x0);
  next_ = 0;
}

double MovingAverage::step(double x) {
  history_[next_] = x;
  next_ = next_ + 1 == length_ ? 0 : next_ + 1;
  double sum = 0.0;
  for (int i = 0; i < length_; ++i) sum += history_[i];
  return sum / length_;
}

std::complex<double> MovingAverage::response(double f_hz, double fs_hz) const {
  const double w = 2.0 * kPi * f_hz / fs_hz;
  std::complex<double> h = 0.0;
  for (int k = 0; k < length_; ++k) h += delay(w, k);
  return h / static_cast<double>(length_);
}

Status SmoothingFilter::Options::validate() const {
  if (Status s = low_pass.validate(); !s.ok()) return s;
  if (moving_average < 1 || moving_average > MovingAverage::kMaxLength) {
    return Error{"moving_average: expected 1 to " + std::to_string(MovingAverage::kMaxLength) +
                 " points, got " + std::to_string(moving_average)};
  }
  return okStatus();
}

SmoothingFilter::SmoothingFilter(const Options& options)
    : low_pass_(options.low_pass), average_(options.moving_average) {
  assert(options.validate().ok());
}

std::complex<double> SmoothingFilter::response(double f_hz) const {
  return low_pass_.response(f_hz) * average_.response(f_hz, low_pass_.options().sample_rate_hz);
}

double SmoothingFilter::groupDelayAtDc() const {
  return low_pass_.groupDelayAtDc() +
         average_.groupDelaySamples() / low_pass_.options().sample_rate_hz;
}

}  // namespace crunch::signal
