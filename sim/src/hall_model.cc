#include "crunch_sim/hall_model.h"

#include <cassert>
#include <cmath>
#include <string>

namespace crunch::sim {
namespace {

constexpr double kMaxCode = 65535.0;

Error hallError(const std::string& field, const std::string& what) {
  return Error{"HallSensorModel::Options::" + field + " " + what};
}

}  // namespace

Status HallSensorModel::Options::validate() const {
  if (!std::isfinite(rest_code) || rest_code < 0.0 || rest_code > kMaxCode) {
    return hallError("rest_code", "must be in [0, 65535]");
  }
  if (!std::isfinite(gain) || gain <= 0.0) return hallError("gain", "must be finite and > 0");
  if (!std::isfinite(clamp_angle) || clamp_angle < 0.0) {
    return hallError("clamp_angle", "must be finite and >= 0");
  }
  if (rest_code - gain * clamp_angle < 0.0 || rest_code + gain * clamp_angle > kMaxCode) {
    return hallError("clamp_angle", "puts a clamping level outside the 16-bit range 0..65535");
  }
  if (!std::isfinite(noise_codes) || noise_codes < 0.0) {
    return hallError("noise_codes", "must be finite and >= 0");
  }
  return okStatus();
}

HallSensorModel::HallSensorModel() : HallSensorModel(Options{}) {}

HallSensorModel::HallSensorModel(const Options& options) : options_(options) {
  assert(options_.validate().ok());
  clamp_low_ = static_cast<std::uint16_t>(
      std::lround(options_.rest_code - options_.gain * options_.clamp_angle));
  clamp_high_ = static_cast<std::uint16_t>(
      std::lround(options_.rest_code + options_.gain * options_.clamp_angle));
}

std::uint16_t HallSensorModel::encode(double angle, double noise, bool& clamped) const {
  const double raw = options_.rest_code + options_.gain * angle + noise;
  clamped = true;
  if (std::isnan(raw) || raw <= clamp_low_) return clamp_low_;
  if (raw >= clamp_high_) return clamp_high_;
  const long code = std::lround(raw);
  clamped = code == clamp_low_ || code == clamp_high_;
  return static_cast<std::uint16_t>(code);
}

HallCodes HallSensorModel::sample(double horizontal, double vertical, Rng& rng) const {
  const double na = options_.noise_codes * rng.normal();
  const double nb = options_.noise_codes * rng.normal();
  HallCodes out;
  out.alpha = encode(horizontal, na, out.alpha_clamped);
  out.beta = encode(vertical, nb, out.beta_clamped);
  return out;
}

HallCodes HallSensorModel::ideal(double horizontal, double vertical) const {
  HallCodes out;
  out.alpha = encode(horizontal, 0.0, out.alpha_clamped);
  out.beta = encode(vertical, 0.0, out.beta_clamped);
  return out;
}

}  // namespace crunch::sim
