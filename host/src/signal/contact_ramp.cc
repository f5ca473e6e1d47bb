#include "crunch/signal/contact_ramp.h"

#include <algorithm>
#include <cmath>

#include "crunch/core/range_check.h"

namespace crunch::signal {

namespace {
// Heading turned back from the ramp's furthest point that counts as a reversal, radians: a turn's
// odometry heading does not step back; this is a few samples of the whisk's turn.
constexpr double kReversal = 1e-5;
// Position change between two samples that counts as driving, metres (2 mm/s at 2 kHz): a turn
// in place does not move the odometry's position at all.
constexpr double kStill = 1e-6;
// Heading from the first point beyond which the turn's direction is known, radians.
constexpr double kDirectionKnown = 1e-4;
}  // namespace

Status RampOptions::validate() const {
  if (auto s = checkAbove("theta_low", theta_low, 0.0, 0.5); !s) return s;
  if (auto s = checkAbove("theta_high", theta_high, theta_low, 0.5); !s) return s;
  if (auto s = checkCount("min_points", min_points, 3, 100000); !s) return s;
  if (auto s = checkAbove("min_span", min_span, 0.0, 1.0); !s) return s;
  if (auto s = checkAbove("max_translation", max_translation, 0.0, 0.1); !s) return s;
  return okStatus();
}

Status RampCalibration::validate() const {
  if (auto s = checkAbove("gain", gain, 0.0, 100.0); !s) return s;
  return checkAbove("compliance_scale", compliance_scale, 0.0, 100.0);
}

void RampFitter::reset() {
  done_ = false;
  last_pose_ = Pose2{std::nan(""), std::nan(""), 0.0};
  result_ = ContactRamp{};
  restart();
}

void RampFitter::restart() {
  n_ = 0;
  last_x_ = min_x_ = max_x_ = 0.0;
  dir_ = 0;
  sx_ = sy_ = sxx_ = sxy_ = syy_ = 0.0;
}

void RampFitter::push(double theta, const Pose2& pose, std::uint64_t sample) {
  if (done_) return;
  if (!(theta >= options_.theta_low && theta <= options_.theta_high)) {
    last_pose_ = pose;
    if (n_ > 0) endRamp();
    return;
  }
  const bool moving = (pose.position() - last_pose_.position()).norm() > kStill;
  last_pose_ = pose;
  if (n_ > 0 && (moving || (pose.position() - first_.position()).norm() > options_.max_translation)) {
    restart();  // driving, not turning: start the ramp again from here
  }
  if (moving) return;
  if (n_ == 0) {
    first_ = pose;
    first_sample_ = sample;
  }
  const double x = wrapPi(pose.theta - first_.theta);
  if (dir_ == 0 && std::abs(x) > kDirectionKnown) dir_ = x > 0 ? 1 : -1;
  if ((dir_ > 0 && x < max_x_ - kReversal) || (dir_ < 0 && x > min_x_ + kReversal)) {
    endRamp();  // the turn reversed: friction flips, the ramp of this pass is over
    if (done_) return;
    first_ = pose;
    first_sample_ = sample;
    return push(theta, pose, sample);
  }
  ++n_;
  last_x_ = x;
  if (x < min_x_) min_x_ = x;
  if (x > max_x_) max_x_ = x;
  sx_ += x;
  sy_ += theta;
  sxx_ += x * x;
  sxy_ += x * theta;
  syy_ += theta * theta;
}

void RampFitter::close() {
  if (!done_ && n_ > 0) endRamp();
}

void RampFitter::endRamp() {
  const double n = n_;
  const double span = max_x_ - min_x_;
  const double vxx = sxx_ - sx_ * sx_ / n;
  const double vxy = sxy_ - sx_ * sy_ / n;
  const double vyy = syy_ - sy_ * sy_ / n;
  if (n_ >= options_.min_points && span >= options_.min_span && vxx > 0.0) {
    const double b = vxy / vxx;
    const double a = (sy_ - b * sx_) / n;
    if (std::isfinite(b) && std::abs(b) > 1e-6) {
      ContactRamp r;
      r.valid = true;
      r.slope = std::abs(b);
      r.direction = b > 0 ? 1 : -1;
      r.touch_heading = first_.theta - a / b;
      r.first_sample = first_sample_;
      r.points = n_;
      r.span = span;
      const double ssr = vyy - b * vxy;
      r.residual_rms = std::sqrt(std::max(0.0, ssr) / n);
      result_ = r;
      done_ = true;
      return;
    }
  }
  restart();
}

}  // namespace crunch::signal
