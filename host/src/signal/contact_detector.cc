#include "crunch/signal/contact_detector.h"

#include <cassert>
#include <cmath>
#include <string>

namespace crunch::signal {

namespace {

bool positiveFinite(double v) { return std::isfinite(v) && v > 0.0; }

// The signed difference code - ref in [-32768, 32767]: a whisker deflects far less than half a
// turn, so this is the deflection even where the rest sits next to the 0/65535 wrap.
double signedCodeDifference(std::uint16_t code, std::uint16_t ref) {
  const auto d = static_cast<std::uint16_t>(code - ref);
  return d >= 0x8000 ? static_cast<double>(d) - 65536.0 : static_cast<double>(d);
}

}  // namespace

Status ContactDetectorOptions::validate() const {
  if (!positiveFinite(radians_per_code)) return Error{"radians_per_code: expected > 0"};
  if (Status s = smoothing.validate(); !s.ok()) return Error{"smoothing." + s.error().message};
  if (smoothing.low_pass.sample_rate_hz != kSampleRateHz) {
    return Error{"smoothing.low_pass.sample_rate_hz: the whisker boards sample at 2000 Hz"};
  }
  if (settle_samples < 0) return Error{"settle_samples: expected >= 0"};
  if (calibration_samples < 2) return Error{"calibration_samples: expected >= 2"};
  if (!positiveFinite(max_noise_sigma)) return Error{"max_noise_sigma: expected > 0"};
  if (!positiveFinite(onset_sigmas)) return Error{"onset_sigmas: expected > 0"};
  if (!positiveFinite(release_sigmas) || release_sigmas >= onset_sigmas) {
    return Error{"release_sigmas: expected > 0 and < onset_sigmas (hysteresis)"};
  }
  if (!positiveFinite(min_onset_threshold)) return Error{"min_onset_threshold: expected > 0"};
  if (release_samples < 1) return Error{"release_samples: expected >= 1"};
  if (!positiveFinite(baseline_time_constant_s)) {
    return Error{"baseline_time_constant_s: expected > 0"};
  }
  if (max_held_samples < 0) return Error{"max_held_samples: expected >= 0"};
  return okStatus();
}

ContactDetector::ContactDetector(const ContactDetectorOptions& options)
    : options_(options), filter_a_(options.smoothing), filter_b_(options.smoothing) {
  assert(options.validate().ok());
}

void ContactDetector::restart() {
  has_rest_ = false;
  resuming_ = false;
  lose();
}

void ContactDetector::lose() {
  state_ = DetectorState::kNoData;
  deflection_.setZero();
  theta_ = 0.0;
  consecutive_held_ = 0;
  below_release_ = 0;
}

void ContactDetector::startCalibration() {
  state_ = DetectorState::kCalibrating;
  calib_n_ = 0;
  calib_mean_.setZero();
  calib_m2_.setZero();
  deflection_.setZero();
  theta_ = 0.0;
}

double ContactDetector::noiseSigma() const { return std::sqrt(0.5 * variance_.sum()); }

double ContactDetector::onsetThreshold() const {
  return std::max(options_.onset_sigmas * noiseSigma(), options_.min_onset_threshold);
}

double ContactDetector::releaseThreshold() const {
  return onsetThreshold() * options_.release_sigmas / options_.onset_sigmas;
}

DetectorEvent ContactDetector::push(const WhiskerReading& reading) {
  const SampleKind kind = classifyStatus(reading.status);
  switch (kind) {
    case SampleKind::kFresh:
      ++counts_.fresh;
      break;
    case SampleKind::kNoData:
      ++counts_.no_data;
      break;
    case SampleKind::kSensorFlag:
      ++counts_.sensor_flag;
      break;
    case SampleKind::kStale:
      ++counts_.stale;
      break;
    case SampleKind::kDropped:
      ++counts_.dropped;
      break;
  }
  const bool used =
      kind == SampleKind::kFresh || (kind == SampleKind::kDropped && options_.accept_dropped);
  last_held_ = !used;
  if (used) {
    ++counts_.used;
    consecutive_held_ = 0;
    if (state_ == DetectorState::kNoData && has_rest_) {
      // Back after a loss: the rest is the whisker's, not the data link's, so it still holds.
      // The filters restart on this sample and settle; then a whisker still bent (around the
      // leg that clamped its sensor) reads as in contact.
      last_value_ = {signedCodeDifference(reading.alpha, ref_alpha_) * options_.radians_per_code,
                     signedCodeDifference(reading.beta, ref_beta_) * options_.radians_per_code};
      filter_a_.reset(last_value_.x());
      filter_b_.reset(last_value_.y());
      calib_seen_ = 0;
      resuming_ = true;
      startCalibration();
    }
    if (state_ == DetectorState::kNoData) {
      // A new reference: this code reads as 0 rad, and the filters start at rest on it.
      ref_alpha_ = reading.alpha;
      ref_beta_ = reading.beta;
      filter_a_.reset(0.0);
      filter_b_.reset(0.0);
      calib_seen_ = 0;
      startCalibration();
    }
    last_value_ = {signedCodeDifference(reading.alpha, ref_alpha_) * options_.radians_per_code,
                   signedCodeDifference(reading.beta, ref_beta_) * options_.radians_per_code};
  } else {
    ++counts_.held;
    if (state_ == DetectorState::kNoData) return DetectorEvent::kNone;
    if (++consecutive_held_ > options_.max_held_samples) {
      lose();
      return DetectorEvent::kLost;
    }
  }

  // Held samples still advance the filters (with the last used value) so the time base stays
  // at 2 kHz; they never enter the rest or noise statistics below.
  const Eigen::Vector2d smoothed(filter_a_.step(last_value_.x()), filter_b_.step(last_value_.y()));

  switch (state_) {
    case DetectorState::kNoData:
      return DetectorEvent::kNone;  // unreachable: a used sample left kNoData above
    case DetectorState::kCalibrating: {
      if (!used) return DetectorEvent::kNone;
      if (calib_seen_ < options_.settle_samples) {
        ++calib_seen_;
        return DetectorEvent::kNone;
      }
      if (resuming_) {  // settled after a loss: measured against the rest it had
        resuming_ = false;
        deflection_ = smoothed - rest_;
        theta_ = deflection_.norm();
        below_release_ = 0;
        if (theta_ > onsetThreshold()) {
          state_ = DetectorState::kContact;
          return DetectorEvent::kOnset;
        }
        state_ = DetectorState::kQuiet;
        return DetectorEvent::kNone;
      }
      ++calib_n_;
      const Eigen::Vector2d d = smoothed - calib_mean_;
      calib_mean_ += d / calib_n_;
      calib_m2_ += d.cwiseProduct(smoothed - calib_mean_);
      if (calib_n_ < options_.calibration_samples) return DetectorEvent::kNone;
      const Eigen::Vector2d var = calib_m2_ / (calib_n_ - 1);
      if (std::sqrt(0.5 * var.sum()) > options_.max_noise_sigma) {
        ++calibration_retries_;
        startCalibration();  // the filters are settled: no second settling period
        return DetectorEvent::kNone;
      }
      rest_ = calib_mean_;
      variance_ = var;
      has_rest_ = true;
      deflection_ = smoothed - rest_;
      theta_ = deflection_.norm();
      below_release_ = 0;
      state_ = DetectorState::kQuiet;
      return DetectorEvent::kReady;
    }
    case DetectorState::kQuiet: {
      deflection_ = smoothed - rest_;
      theta_ = deflection_.norm();
      if (theta_ > onsetThreshold()) {
        state_ = DetectorState::kContact;
        below_release_ = 0;
        return DetectorEvent::kOnset;
      }
      if (used && theta_ < releaseThreshold()) {
        // Slow tracking of the rest while clearly quiet. Only the rest: a variance tracked the
        // same way would learn any sustained sub-threshold deflection as noise (a 0.7-threshold
        // push for 1 s doubles it) and raise the threshold exactly when a contact builds up.
        const double w = 1.0 / (options_.baseline_time_constant_s * kSampleRateHz);
        rest_ += w * deflection_;
      }
      return DetectorEvent::kNone;
    }
    case DetectorState::kContact: {
      deflection_ = smoothed - rest_;
      theta_ = deflection_.norm();
      if (theta_ < releaseThreshold()) {
        if (++below_release_ >= options_.release_samples) {
          state_ = DetectorState::kQuiet;
          return DetectorEvent::kRelease;
        }
      } else {
        below_release_ = 0;
      }
      return DetectorEvent::kNone;
    }
  }
  return DetectorEvent::kNone;
}

}  // namespace crunch::signal
