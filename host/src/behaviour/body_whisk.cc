#include "crunch/behaviour/body_whisk.h"

#include <cassert>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace crunch {

namespace {

constexpr double kNever = std::numeric_limits<double>::infinity();
// Sums of sines within this of 0 count as "straight ahead": the symmetric pairs of a whisker
// array cancel only to rounding.
constexpr double kAheadTolerance = 1e-9;

Status badField(const char* field, double value, const char* rule) {
  std::ostringstream msg;
  msg << "BodyWhisk options: " << field << " = " << value << ", must be " << rule;
  return Error{msg.str()};
}

bool finite(double x) { return std::isfinite(x); }

}  // namespace

Status BodyWhisk::Options::validate() const {
  if (!(forward_speed > 0) || !finite(forward_speed))
    return badField("forward_speed", forward_speed, "finite and > 0 (m/s)");
  if (!(reverse_speed > 0) || !finite(reverse_speed))
    return badField("reverse_speed", reverse_speed, "finite and > 0 (m/s)");
  if (!(reverse_distance >= 0) || !finite(reverse_distance))
    return badField("reverse_distance", reverse_distance, "finite and >= 0 (m)");
  if (!(whisk_rate > 0) || !finite(whisk_rate))
    return badField("whisk_rate", whisk_rate, "finite and > 0 (rad/s)");
  if (!(whisk_amplitude > 0 && whisk_amplitude <= kPi / 2))
    return badField("whisk_amplitude", whisk_amplitude, "in (0, pi/2] (rad)");
  if (!(clear_distance >= 0) || !finite(clear_distance))
    return badField("clear_distance", clear_distance, "finite and >= 0 (m)");
  if (!(turn_min >= 0 && turn_min <= kPi))
    return badField("turn_min", turn_min, "in [0, pi] (rad)");
  if (!(turn_max >= turn_min && turn_max <= kPi))
    return badField("turn_max", turn_max, "in [turn_min, pi] (rad)");
  if (!(turn_rate > 0) || !finite(turn_rate))
    return badField("turn_rate", turn_rate, "finite and > 0 (rad/s)");
  if (!(bump_backoff >= 0) || !finite(bump_backoff))
    return badField("bump_backoff", bump_backoff, "finite and >= 0 (m)");
  if (!(timeout_factor >= 1) || !finite(timeout_factor))
    return badField("timeout_factor", timeout_factor, "finite and >= 1");
  if (!(timeout_slack >= 0) || !finite(timeout_slack))
    return badField("timeout_slack", timeout_slack, "finite and >= 0 (s)");
  if (whisker_bearings.empty() || whisker_bearings.size() > 32)
    return badField("whisker_bearings.size()", static_cast<double>(whisker_bearings.size()),
                    "1..32 (one per contact-mask bit)");
  for (const double b : whisker_bearings)
    if (!finite(b)) return badField("whisker_bearings[]", b, "finite (rad)");
  return okStatus();
}

BodyWhisk::BodyWhisk(MobileBase& base, const Options& options)
    : base_(base), options_(options), rng_(options.seed) {
  [[maybe_unused]] const Status valid = options_.validate();
  assert(valid.ok());
}

int BodyWhisk::towardSide(std::uint32_t contact, std::span<const double> bearings) {
  double sum = 0.0;
  bool any = false;
  for (std::size_t w = 0; w < bearings.size() && w < 32; ++w) {
    if ((contact >> w & 1u) == 0u) continue;
    any = true;
    sum += std::sin(bearings[w]);
  }
  if (!any) return 0;
  return sum > -kAheadTolerance ? +1 : -1;
}

const char* BodyWhisk::phaseName(Phase phase) {
  switch (phase) {
    case Phase::kIdle:
      return "idle";
    case Phase::kForward:
      return "forward";
    case Phase::kBackOff:
      return "back-off";
    case Phase::kToward:
      return "toward";
    case Phase::kAway:
      return "away";
    case Phase::kReturn:
      return "return";
    case Phase::kClear:
      return "clear";
    case Phase::kTurn:
      return "turn";
    case Phase::kBumpBackOff:
      return "bump-back-off";
    case Phase::kDone:
      return "done";
  }
  return "?";
}

void BodyWhisk::enter(Phase phase, double now, const Pose2& pose) {
  const Options& o = options_;
  const double a = o.whisk_amplitude;
  double nominal = kNever;  // seconds the phase should take
  phase_ = phase;
  phase_start_time_ = now;
  phase_start_pose_ = pose;
  want_v_ = 0.0;
  want_omega_ = 0.0;
  switch (phase) {
    case Phase::kIdle:
    case Phase::kDone:
      break;
    case Phase::kForward:
      want_v_ = o.forward_speed;
      break;
    case Phase::kBackOff:
      want_v_ = -o.reverse_speed;
      nominal = o.reverse_distance / o.reverse_speed;
      break;
    case Phase::kToward:
      sweep_ = 0.0;  // theta0
      whisk_start_time_ = now;
      want_omega_ = side_ * o.whisk_rate;
      nominal = a / o.whisk_rate;
      break;
    case Phase::kAway:
      want_omega_ = -side_ * o.whisk_rate;
      nominal = 2 * a / o.whisk_rate;
      break;
    case Phase::kReturn:
      want_omega_ = side_ * o.whisk_rate;
      nominal = a / o.whisk_rate;
      break;
    case Phase::kClear:
      want_v_ = -o.reverse_speed;
      nominal = o.clear_distance / o.reverse_speed;
      break;
    case Phase::kTurn: {
      // Direction first, then magnitude: two draws per turn, so a seed fixes every turn.
      const double sign = rng_.below(2) == 0 ? +1.0 : -1.0;
      turn_ = sign * rng_.uniform(o.turn_min, o.turn_max);
      sweep_ = 0.0;
      ++stats_.turns;
      want_omega_ = sign * o.turn_rate;
      nominal = std::abs(turn_) / o.turn_rate;
      break;
    }
    case Phase::kBumpBackOff:
      want_v_ = -o.reverse_speed;
      nominal = o.bump_backoff / o.reverse_speed;
      break;
  }
  deadline_ = now + o.timeout_factor * nominal + o.timeout_slack;
}

bool BodyWhisk::step(std::uint32_t contact, double now, const Pose2& pose) {
  const Options& o = options_;
  const double moved = std::hypot(pose.x - phase_start_pose_.x, pose.y - phase_start_pose_.y);
  const bool late = now >= deadline_;
  // Ends the phase if `reached`, or late; a phase that ends late is counted.
  auto ends = [&](bool reached) {
    if (!reached && late) ++stats_.timeouts;
    return reached || late;
  };

  switch (phase_) {
    case Phase::kIdle:
    case Phase::kDone:
      return false;
    case Phase::kForward: {
      const int side = towardSide(contact, o.whisker_bearings);
      if (side == 0) return false;
      side_ = side;
      contact_time_ = now;
      ++stats_.whisks_started;
      enter(Phase::kBackOff, now, pose);
      return true;
    }
    case Phase::kBackOff:
      if (!ends(moved >= o.reverse_distance)) return false;
      enter(Phase::kToward, now, pose);
      return true;
    case Phase::kToward:
      if (!ends(side_ * sweep_ >= o.whisk_amplitude)) return false;
      enter(Phase::kAway, now, pose);
      return true;
    case Phase::kAway:
      if (!ends(side_ * sweep_ <= -o.whisk_amplitude)) return false;
      ++stats_.whisks_completed;
      enter(in_place_ ? Phase::kReturn : Phase::kClear, now, pose);
      return true;
    case Phase::kReturn:
      if (!ends(side_ * sweep_ >= 0.0)) return false;
      enter(Phase::kDone, now, pose);
      return true;
    case Phase::kClear:
      if (!ends(moved >= o.clear_distance)) return false;
      enter(Phase::kTurn, now, pose);
      return true;
    case Phase::kTurn:
      if (!ends(std::abs(sweep_) >= std::abs(turn_))) return false;
      enter(Phase::kForward, now, pose);
      return true;
    case Phase::kBumpBackOff:
      if (!ends(moved >= o.bump_backoff)) return false;
      if (in_place_) {
        interrupted_ = true;
        enter(Phase::kDone, now, pose);
      } else {
        enter(Phase::kTurn, now, pose);
      }
      return true;
  }
  return false;
}

Status BodyWhisk::sendCommand() {
  if (sent_ && want_v_ == sent_v_ && want_omega_ == sent_omega_) return okStatus();
  Status s = base_.drive(want_v_, want_omega_);
  if (s.ok()) {
    sent_ = true;
    sent_v_ = want_v_;
    sent_omega_ = want_omega_;
  }
  return s;
}

Status BodyWhisk::startRoaming() {
  const Pose2 pose = base_.odometry();
  in_place_ = false;
  interrupted_ = false;
  last_theta_ = pose.theta;
  enter(Phase::kForward, base_.now(), pose);
  return sendCommand();
}

Status BodyWhisk::startInPlace(int direction) {
  const Pose2 pose = base_.odometry();
  const double now = base_.now();
  in_place_ = true;
  interrupted_ = false;
  last_theta_ = pose.theta;
  side_ = direction >= 0 ? +1 : -1;
  contact_time_ = now;
  ++stats_.whisks_started;
  enter(Phase::kToward, now, pose);
  return sendCommand();
}

Status BodyWhisk::halt() {
  enter(Phase::kIdle, base_.now(), base_.odometry());
  Status s = base_.stop();
  if (s.ok()) {
    sent_ = true;
    sent_v_ = 0.0;
    sent_omega_ = 0.0;
  }
  return s;
}

Status BodyWhisk::update(std::uint32_t contact) {
  if (phase_ == Phase::kIdle) return okStatus();
  const double now = base_.now();
  const Pose2 pose = base_.odometry();
  // Heading turned since the last update, wrapped, so turns of any size accumulate correctly
  // as long as the base turns less than pi between two updates.
  sweep_ += wrapPi(pose.theta - last_theta_);
  last_theta_ = pose.theta;

  if (phase_ != Phase::kDone && phase_ != Phase::kBumpBackOff && base_.bumped()) {
    // Stop now; the back-off's reverse command goes out at the next update.
    ++stats_.bumps;
    enter(Phase::kBumpBackOff, now, pose);
    Status s = base_.stop();
    if (s.ok()) {
      sent_ = true;
      sent_v_ = 0.0;
      sent_omega_ = 0.0;
    }
    return s;
  }
  // Phases whose target is already met (a zero distance) pass through in the same update.
  for (int i = 0; i < 8 && step(contact, now, pose); ++i) {
  }
  return sendCommand();
}

}  // namespace crunch
