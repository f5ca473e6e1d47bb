// One whisker's contact detector (paper §2.4-2.5): raw MLX90333 codes in, the smoothed
// deflection relative to rest and contact onset/release events out.
//
// Per sample:
//   1. status -> used or held (sample.h): a held sample repeats the last used value; before the
//      first used value there is nothing to hold and the sample is only counted;
//   2. codes -> radians relative to the first used code (signed 16-bit difference, so a rest
//      near a code wrap does not jump), times radians_per_code;
//   3. the paper's smoothing per axis (filters.h: 17 Hz low-pass, 5-point moving average);
//   4. deflection (da, db) = smoothed - rest, and its magnitude theta(t) = |(da, db)|, the
//      theta of eq. 1.
//
// Rest and noise. After the first used sample the detector calibrates: it skips settle_samples
// used samples, then takes the mean (the rest) and variance per axis of the next
// calibration_samples *smoothed* values. A calibration whose noise exceeds max_noise_sigma (the
// whisker was moving or touching) is thrown away and started again. While quiet and below the
// release threshold the rest keeps tracking slowly (exponential average with
// baseline_time_constant_s), so a slow drift (temperature) does not become a contact; it is
// frozen otherwise. The noise is the calibration's: a tracked variance would learn a
// sustained sub-threshold push as noise and raise the threshold as a contact builds up.
// restart() recalibrates (e.g. while the robot stands still). Held samples never enter these
// statistics.
//
// Threshold (docs/SIGNAL.md, "Thresholds"). sigma = sqrt((var_a + var_b) / 2) of the smoothed
// signals. For Gaussian noise theta is Rayleigh-distributed, P(theta > k sigma) = exp(-k^2/2):
// onset at k = 6 is 1.5e-8 per sample, and the smoothed signal has only ~40 independent values
// per second: of the order of one false onset in weeks of continuous running. Onset: theta >
// max(onset_sigmas sigma, min_onset_threshold). Release (hysteresis): theta below onset *
// release_sigmas / onset_sigmas for release_samples consecutive samples. min_onset_threshold keeps
// a noiseless sensor (or one quantised to a constant) from triggering on one code of change.
//
// Loss. After max_held_samples consecutive held samples (a clamped Hall sensor, a silent board)
// the whisker is lost: its state becomes kNoData. With the next used sample it is back: its
// filters restart there and settle (settle_samples, state kCalibrating), then it is measured
// against the rest it had: the rest belongs to the whisker, not to the data link, so a whisker
// that is still bent (around the leg that clamped its sensor) reads as in contact and is never
// taken as free (issue 12: recalibrating there learnt the bend as rest). Only a detector that
// never finished a calibration calibrates from the next used sample.
//
// Allocation-free; not thread-safe.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "crunch/core/result.h"
#include "crunch/signal/filters.h"
#include "crunch/signal/sample.h"

namespace crunch::signal {

struct ContactDetectorOptions {
  // MLX90333 serial angle output: 360 degrees over the 16-bit word.
  double radians_per_code = 6.283185307179586 / 65536.0;
  SmoothingFilter::Options smoothing;
  int settle_samples = 200;        // 0.1 s: the filters forget their start (>> 13 ms lag)
  int calibration_samples = 2000;  // 1 s of rest to estimate the rest and the noise
  double max_noise_sigma = 2e-3;   // rad; a noisier calibration is retried
  double onset_sigmas = 6.0;
  double release_sigmas = 3.0;
  double min_onset_threshold = 3e-4;      // rad (~3 codes, 0.017 degrees)
  int release_samples = 40;               // 20 ms below the release threshold ends a contact
  double baseline_time_constant_s = 2.0;  // follows drifts up to ~release threshold / 2 s
  int max_held_samples = 100;             // 50 ms without a used sample: the whisker is lost
  bool accept_dropped = false;            // use DROPPED-only samples as measurements

  // okStatus(), or an Error naming the bad field.
  Status validate() const;
};

enum class DetectorState {
  kNoData,       // no used sample yet, or lost
  kCalibrating,  // measuring the rest and the noise
  kQuiet,        // ready, not touching
  kContact,      // touching
};

enum class DetectorEvent {
  kNone,
  kReady,    // calibration finished: kCalibrating -> kQuiet
  kOnset,    // kQuiet -> kContact
  kRelease,  // kContact -> kQuiet
  kLost,     // too many held samples: -> kNoData (from any state)
};

class ContactDetector {
 public:
  // Asserts `options.validate()`.
  ContactDetector() : ContactDetector(ContactDetectorOptions{}) {}
  explicit ContactDetector(const ContactDetectorOptions& options);

  // Feeds one 500 us sample; returns what changed.
  DetectorEvent push(const WhiskerReading& reading);

  // Forgets everything, the rest too: state kNoData, calibrates again from the next used sample;
  // counts kept.
  void restart();

  DetectorState state() const { return state_; }
  bool ready() const {
    return state_ == DetectorState::kQuiet || state_ == DetectorState::kContact;
  }
  bool inContact() const { return state_ == DetectorState::kContact; }
  // The smoothed deflection (alpha, beta) relative to rest, radians; zero unless ready().
  const Eigen::Vector2d& deflection() const { return deflection_; }
  // theta(t) = |deflection()|, radians; zero unless ready().
  double theta() const { return theta_; }
  // The rest, radians relative to referenceCode(); valid once ready().
  const Eigen::Vector2d& rest() const { return rest_; }
  // The code that reads as 0 rad (the first used code after a start or loss) per axis.
  std::uint16_t referenceAlpha() const { return ref_alpha_; }
  std::uint16_t referenceBeta() const { return ref_beta_; }
  // sigma of the smoothed signal per axis, pooled: sqrt((var_a + var_b) / 2), radians.
  double noiseSigma() const;
  double onsetThreshold() const;
  double releaseThreshold() const;
  // True if the last push() held rather than used its sample.
  bool lastHeld() const { return last_held_; }
  const SampleCounts& counts() const { return counts_; }
  // Calibrations rejected for noise.
  std::uint64_t calibrationRetries() const { return calibration_retries_; }
  const ContactDetectorOptions& options() const { return options_; }

 private:
  void startCalibration();
  void lose();  // kNoData, keeping the rest

  ContactDetectorOptions options_;
  SmoothingFilter filter_a_, filter_b_;
  DetectorState state_ = DetectorState::kNoData;
  SampleCounts counts_;
  std::uint64_t calibration_retries_ = 0;

  std::uint16_t ref_alpha_ = 0, ref_beta_ = 0;
  Eigen::Vector2d last_value_ = Eigen::Vector2d::Zero();  // last used value, rad
  int consecutive_held_ = 0;
  bool last_held_ = false;

  // Calibration (Welford).
  int calib_seen_ = 0;
  int calib_n_ = 0;
  Eigen::Vector2d calib_mean_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d calib_m2_ = Eigen::Vector2d::Zero();

  bool has_rest_ = false;  // a calibration finished (and restart() has not been called since)
  bool resuming_ = false;  // back after a loss: settling, then measured against rest_
  Eigen::Vector2d rest_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d variance_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d deflection_ = Eigen::Vector2d::Zero();
  double theta_ = 0.0;
  int below_release_ = 0;
};

}  // namespace crunch::signal
