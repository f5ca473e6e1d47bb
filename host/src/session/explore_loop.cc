#include "crunch/session/explore_loop.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace crunch::session {

namespace {
double clampAbs(double v, double m) { return std::clamp(v, -m, m); }
constexpr double kHeadingGain = 2.0;   // rad/s per rad of heading error
constexpr double kMinTurn = 0.1;       // rad/s: the slowest turn commanded while aligning
}  // namespace

Status ExploreLoop::Options::validate() const {
  if (auto st = explore.validate(); !st) return st.error();
  auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  if (!positive(speed)) return Error{"explore loop speed: must be above 0"};
  if (!positive(turn_rate)) return Error{"explore loop turn_rate: must be above 0"};
  if (!positive(waypoint_tolerance)) return Error{"explore loop waypoint_tolerance: must be above 0"};
  if (!positive(heading_tolerance)) return Error{"explore loop heading_tolerance: must be above 0"};
  if (!positive(aim_tolerance)) return Error{"explore loop aim_tolerance: must be above 0"};
  if (!std::isfinite(backoff) || backoff < 0) return Error{"explore loop backoff: must be >= 0"};
  if (!positive(backoff_speed)) return Error{"explore loop backoff_speed: must be above 0"};
  if (!std::isfinite(touch_separation) || touch_separation < 0) {
    return Error{"explore loop touch_separation: must be >= 0"};
  }
  if (!positive(record_every)) return Error{"explore loop record_every: must be above 0"};
  if (max_failed_goals < 1) return Error{"explore loop max_failed_goals: must be >= 1"};
  if (max_bumps_per_goal < 1) return Error{"explore loop max_bumps_per_goal: must be >= 1"};
  if (!std::isfinite(give_up_radius) || give_up_radius < 0) {
    return Error{"explore loop give_up_radius: must be >= 0"};
  }
  return whisk.validate();
}

ExploreLoop::ExploreLoop(MobileBase& base, exploration::KnownSpace& known,
                         exploration::ExplorePolicy& policy, std::vector<WhiskerMount> mounts,
                         ModelParams model, std::vector<Pose2> grid_poses, const Options& options,
                         Hooks hooks)
    : base_(base),
      known_(known),
      policy_(policy),
      mounts_(std::move(mounts)),
      model_(std::move(model)),
      grid_(std::move(grid_poses)),
      options_(options),
      hooks_(std::move(hooks)),
      whisk_(base, options.whisk),
      rng_(options.seed) {
  assert(options.validate());
  report_.policy = exploration::explorePolicyName(policy.kind());
  last_pose_ = recorded_ = base.odometry();
  start_time_ = base.now();
  report_.path.push_back(last_pose_);
  known_.markBody(last_pose_.position(), options.explore.planner.robot_radius);
}

Status ExploreLoop::command(double v, double omega) {
  if (sent_ && v == sent_v_ && omega == sent_omega_) return okStatus();
  if (auto st = base_.drive(v, omega); !st) {
    sent_ = false;
    return st;
  }
  sent_ = true;
  sent_v_ = v;
  sent_omega_ = omega;
  return okStatus();
}

void ExploreLoop::finish(const std::string& why) {
  if (phase_ == Phase::kDone) return;
  (void)command(0.0, 0.0);
  phase_ = Phase::kDone;
  report_.stop_reason = why;
  report_.sim_time_s = base_.now() - start_time_;
  report_.decision_ms = decisions_ > 0 ? decision_total_ms_ / decisions_ : 0.0;
  if (report_.path.empty() || (report_.path.back().position() - last_pose_.position()).norm() > 0) {
    report_.path.push_back(last_pose_);
  }
}

void ExploreLoop::track(const Pose2& pose) {
  const double step = (pose.position() - last_pose_.position()).norm();
  if (std::isfinite(step)) report_.travel_m += step;
  // Cells the centre drives through stay passable (path_planner.h); standing is not driving,
  // so a robot that has not moved is boxed in where the costmap says it is.
  if (step > 0.0) known_.markVisited(last_pose_.position(), pose.position());
  last_pose_ = pose;
  if ((pose.position() - recorded_.position()).norm() >= options_.record_every) {
    recorded_ = pose;
    report_.path.push_back(pose);
    known_.markBody(pose.position(), options_.explore.planner.robot_radius);
  }
}

bool ExploreLoop::budgetReached(std::string& why) const {
  if (report_.travel_m >= options_.explore.travel_budget_m) {
    why = "travel budget reached";
    return true;
  }
  if (options_.explore.whisk_budget > 0 && report_.whisks >= options_.explore.whisk_budget) {
    why = "whisk budget reached";
    return true;
  }
  return false;
}

Status ExploreLoop::afterBump() {
  // A goal that keeps bumping where it bumped before (the bumper's switches give the side, not
  // the point, so an object can stay unmarked) is given up after max_bumps_per_goal.
  if (goal_bumps_ >= options_.max_bumps_per_goal || !plan()) {
    if (failGoal() >= options_.max_failed_goals) {
      finish("boxed in: " + std::to_string(failed_) + " goals in a row could not be reached");
      return okStatus();
    }
    phase_ = Phase::kDecide;
    return okStatus();
  }
  phase_ = Phase::kFollow;
  return okStatus();
}

bool ExploreLoop::newTouch(const Vec2& p) const {
  for (const Vec2& t : touches_) {
    if ((t - p).norm() < options_.touch_separation) return false;
  }
  const double r = options_.touch_separation;
  int cx, cy;
  if (!known_.index(p, cx, cy)) return false;  // outside the region: the room's wall
  const int k = static_cast<int>(std::ceil(r / known_.cell()));
  for (int iy = cy - k; iy <= cy + k; ++iy) {
    for (int ix = cx - k; ix <= cx + k; ++ix) {
      if (ix < 0 || iy < 0 || ix >= known_.nx() || iy >= known_.ny()) continue;
      if ((known_.centre(ix, iy) - p).norm() > r + 0.5 * known_.cell()) continue;
      if (known_.at(ix, iy) == exploration::KnownSpace::Cell::kOccupied) return false;
    }
  }
  return true;
}

int ExploreLoop::failGoal() {
  given_up_.push_back(goal_->position());
  // Goals at one position (the grid's headings) count once: boxed in means positions.
  if (!last_failed_ || (last_failed_->position() - goal_->position()).norm() > 1e-9) ++failed_;
  last_failed_ = goal_;
  return failed_;
}

bool ExploreLoop::plan() {
  const exploration::Costmap costmap(known_, options_.explore.planner);
  const auto p = exploration::planPath(costmap, last_pose_.position(), goal_->position());
  if (!p) return false;
  waypoints_ = p->waypoints;
  next_wp_ = 0;
  // Time to get there: the path at speed, a full turn at each waypoint, three times over.
  deadline_ = base_.now() + 3.0 * (p->length / options_.speed +
                                   (waypoints_.size() + 1) * 2 * kPi / options_.turn_rate) + 10.0;
  return true;
}

Status ExploreLoop::decideAndPlan() {
  std::string why;
  if (budgetReached(why)) {
    finish(why);
    return okStatus();
  }
  if (!drawing_) samples_.clear();
  const int wanted = policy_.samplesWanted();
  if (wanted > 0 && hooks_.samples) {
    drawing_ = !hooks_.samples(wanted, samples_);
    if (drawing_) return okStatus();  // standing still; drawn on at the next update
  }
  double ms = 0.0;
  const exploration::Decision d = exploration::decide(
      policy_, known_, options_.explore.planner, last_pose_, samples_, mounts_, model_, grid_,
      report_.whisks, report_.travel_m, false, options_.waypoint_tolerance, given_up_,
      options_.give_up_radius, rng_, &ms);
  decision_total_ms_ += ms;
  ++decisions_;
  report_.decision_ms_max = std::max(report_.decision_ms_max, ms);
  if (!d.goal) {
    finish(d.why);
    return okStatus();
  }
  goal_ = d.goal;
  goal_bumps_ = 0;
  if (!plan()) {
    if (failGoal() >= options_.max_failed_goals) {
      finish("boxed in: " + std::to_string(failed_) + " goals in a row could not be reached");
    }
    return okStatus();
  }
  phase_ = Phase::kFollow;
  return okStatus();
}

Status ExploreLoop::update(std::uint32_t contact, const Vec2* touch) {
  if (phase_ == Phase::kDone) return okStatus();
  const Pose2 pose = base_.odometry();
  track(pose);

  if (base_.bumped() && (phase_ == Phase::kFollow || phase_ == Phase::kAlign)) {
    std::optional<Vec2> told;
    if (hooks_.bump_point) told = hooks_.bump_point(pose);
    // Else where the bumper's switches say (robot/bumper.h): ahead for both, 41.5 degrees to
    // the side for one, the expected bearing of a hit that closes only that switch.
    const Vec2 hit = told ? *told
                          : expectedBumpPoint(pose, base_.bumper(),
                                              options_.explore.planner.robot_radius);
    known_.markBump(hit);
    ++report_.bumps;
    report_.bump_points.push_back(hit);
    // The bumper says only that something is at the front; the whiskers can say where. Once
    // backed off, a whisk in place sweeps the front (the four whiskers' sweeps join from -49
    // to +49 degrees, reaching from 5 cm beyond the rim): its contacts mark the object where it
    // is, and the planner goes round it instead of into it again. Once per place.
    bump_whisk_ = std::none_of(touches_.begin(), touches_.end(), [&](const Vec2& t) {
      return (t - hit).norm() < options_.touch_separation;
    });
    if (bump_whisk_) touches_.push_back(hit);
    // A bump at a new place found an obstacle the plan did not know, now marked: replanning is
    // progress. A bump again where one was is what makes a goal futile.
    if (!bump_whisk_) ++goal_bumps_;
    // Straight away from the hit, facing it: reversing at once when it is ahead (the Create's
    // bumpers are at the front), else first turned in place to face it (the body is a disc): a
    // body grazing a leg at its side would graze it again backing along its heading, and the
    // whisk that follows must sweep where the hit was.
    const Vec2 toward = hit - pose.position();
    escape_heading_ = toward.norm() > 1e-9 ? std::atan2(toward.y(), toward.x()) : pose.theta;
    if (std::abs(wrapPi(escape_heading_ - pose.theta)) < kPi / 6) escape_heading_ = pose.theta;
    escape_turned_ = false;
    backoff_from_ = pose;
    deadline_ = base_.now() + 3.0 * options_.backoff / options_.backoff_speed + 1.0 +
                3.0 * kPi / options_.turn_rate;
    phase_ = Phase::kBackOff;
    return command(0.0, 0.0);
  }

  switch (phase_) {
    case Phase::kDecide:
      return decideAndPlan();

    case Phase::kFollow: {
      std::string why;
      if (report_.travel_m >= options_.explore.travel_budget_m) {
        finish("travel budget reached");
        return okStatus();
      }
      if (contact != 0) {
        Vec2 p;
        if (touch) {
          p = *touch;
        } else {
          int w = 0;
          while (w < 32 && !((contact >> w) & 1u)) ++w;
          p = w < static_cast<int>(mounts_.size())
                  ? mounts_[w].pointAt(pose, 2.0 / 3.0 * mounts_[w].length)
                  : pose.position();
        }
        if (newTouch(p)) {
          touches_.push_back(p);
          if (auto st = command(0.0, 0.0); !st) return st;
          whisk_pose_ = pose;
          phase_ = Phase::kTouchWhisk;
          sent_ = false;  // BodyWhisk commands the base from here
          return whisk_.startInPlace(+1);
        }
      }
      if (base_.now() > deadline_) {
        if (failGoal() >= options_.max_failed_goals) {
          finish("boxed in: " + std::to_string(failed_) + " goals in a row could not be reached");
          return okStatus();
        }
        phase_ = Phase::kDecide;
        return command(0.0, 0.0);
      }
      while (next_wp_ < waypoints_.size() &&
             (waypoints_[next_wp_] - pose.position()).norm() < options_.waypoint_tolerance) {
        ++next_wp_;
      }
      if (next_wp_ >= waypoints_.size()) {
        phase_ = Phase::kAlign;
        return command(0.0, 0.0);
      }
      const Vec2 d = waypoints_[next_wp_] - pose.position();
      const double e = wrapPi(std::atan2(d.y(), d.x()) - pose.theta);
      const double omega = clampAbs(kHeadingGain * e, options_.turn_rate);
      if (std::abs(e) > options_.aim_tolerance) return command(0.0, omega);
      return command(options_.speed, omega);
    }

    case Phase::kAlign: {
      const double e = wrapPi(goal_->theta - pose.theta);
      if (std::abs(e) <= options_.heading_tolerance) {
        if (auto st = command(0.0, 0.0); !st) return st;
        whisk_pose_ = pose;
        phase_ = Phase::kWhisk;
        sent_ = false;
        return whisk_.startInPlace(+1);
      }
      const double mag = std::clamp(kHeadingGain * std::abs(e), kMinTurn, options_.turn_rate);
      return command(0.0, std::copysign(mag, e));
    }

    case Phase::kWhisk:
    case Phase::kTouchWhisk: {
      if (auto st = whisk_.update(contact); !st) return st;
      if (!whisk_.done()) return okStatus();
      sent_ = false;
      ++report_.whisks;
      report_.whisk_poses.push_back(whisk_pose_);
      if (hooks_.whisked) hooks_.whisked(whisk_pose_);
      if (phase_ == Phase::kWhisk) {
        failed_ = 0;
        last_failed_.reset();
        phase_ = Phase::kDecide;
        return okStatus();
      }
      std::string why;
      if (bump_whisk_) {  // the whisk after a bump: on as after any bump
        bump_whisk_ = false;
        if (budgetReached(why)) {
          phase_ = Phase::kDecide;
          return okStatus();
        }
        return afterBump();
      }
      if (budgetReached(why) || !plan()) {
        phase_ = Phase::kDecide;
        return okStatus();
      }
      phase_ = Phase::kFollow;
      return okStatus();
    }

    case Phase::kBackOff: {
      if (!escape_turned_) {
        const double e = wrapPi(escape_heading_ - pose.theta);
        if (std::abs(e) > options_.heading_tolerance && base_.now() <= deadline_) {
          const double mag = std::clamp(kHeadingGain * std::abs(e), kMinTurn, options_.turn_rate);
          return command(0.0, std::copysign(mag, e));
        }
        escape_turned_ = true;
        backoff_from_ = pose;
      }
      const bool done =
          (pose.position() - backoff_from_.position()).norm() >= options_.backoff ||
          base_.now() > deadline_;
      if (!done) return command(-options_.backoff_speed, 0.0);
      if (auto st = command(0.0, 0.0); !st) return st;
      if (bump_whisk_) {
        whisk_pose_ = pose;
        phase_ = Phase::kTouchWhisk;
        sent_ = false;  // BodyWhisk commands the base from here
        return whisk_.startInPlace(+1);
      }
      return afterBump();
    }

    case Phase::kDone:
      break;
  }
  return okStatus();
}

}  // namespace crunch::session
