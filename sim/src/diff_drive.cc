#include "crunch_sim/diff_drive.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <string>

namespace crunch::sim {

Status DiffDrive::Options::validate() const {
  if (!(std::isfinite(wheel_base) && wheel_base > 0.0)) {
    return Error{"wheel_base: must be finite and > 0"};
  }
  if (!(std::isfinite(max_wheel_speed) && max_wheel_speed > 0.0)) {
    return Error{"max_wheel_speed: must be finite and > 0"};
  }
  if (!(std::isfinite(max_wheel_acceleration) && max_wheel_acceleration >= 0.0)) {
    return Error{"max_wheel_acceleration: must be finite and >= 0"};
  }
  return okStatus();
}

DiffDrive::DiffDrive(const Options& options) : options_(options) {
  assert(options_.validate().ok());
}

Status DiffDrive::command(double v, double omega, const char* who) {
  const bool finite = std::isfinite(v) && std::isfinite(omega);
  double right = finite ? v + 0.5 * omega * options_.wheel_base : 0.0;
  double left = finite ? v - 0.5 * omega * options_.wheel_base : 0.0;
  const double biggest = std::max(std::abs(right), std::abs(left));
  clamped_ = biggest > options_.max_wheel_speed;
  if (clamped_) {
    const double s = options_.max_wheel_speed / biggest;
    right *= s;
    left *= s;
  }
  target_right_ = right;
  target_left_ = left;
  if (options_.max_wheel_acceleration <= 0.0) {  // the wheels take the new speed at once
    right_ = right;
    left_ = left;
  }
  if (!finite) {
    return Error{std::string(who) + ": drive(v, omega) needs finite values (got v " +
                 std::to_string(v) + ", omega " + std::to_string(omega) + "); stopping"};
  }
  return okStatus();
}

void DiffDrive::advance(double h) {
  if (options_.max_wheel_acceleration <= 0.0) return;
  // Each wheel ramps toward its commanded speed at the motor's acceleration limit.
  const double dv = options_.max_wheel_acceleration * h;
  left_ += std::clamp(target_left_ - left_, -dv, dv);
  right_ += std::clamp(target_right_ - right_, -dv, dv);
}

void DiffDrive::halt() {
  left_ = right_ = target_left_ = target_right_ = 0.0;
}

}  // namespace crunch::sim
