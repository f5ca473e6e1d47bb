// The exploring robot's behaviour (issue 14, paper §2.9; docs/EXPLORATION.md "Driving"): drives
// any MobileBase — the simulator's KinematicBase under `--sim --explore`, the Create under
// `--robot --explore` — through
//   decide (the policy, on the KnownSpace's costmap and distance field)
//   -> plan (A*, exploration/path_planner.h)
//   -> follow the waypoints: turn-then-go (turn in place at up to turn_rate while the waypoint's
//      bearing is off by more than aim_tolerance, else drive at `speed` with a proportional
//      heading correction), the Create's 0.2 m/s and pi/4 rad/s by default
//   -> at the goal turn to its heading -> whisk in place (BodyWhisk::startInPlace)
//   -> Hooks::whisked(pose where the whisk began): the caller senses and maps, and marks the
//      KnownSpace (free rays, contacts, the map's obstacles)
//   -> decide again.
// A bump (base.bumped()) while driving or turning: stop, record the bump point (Hooks::bump_point,
// else where the base's bumper switches put it, robot/bumper.h expectedBumpPoint on the rim of
// radius PlannerOptions::robot_radius) as occupied in the KnownSpace and in the report, back off
// `backoff` straight away from the bump point, facing it (turned in place first unless it is
// within 30 degrees of ahead, as a hit that closes both switches is), and, if the bump point is
// touch_separation from every touch and bump acted on before, whisk in place there (a touch
// whisk: the whiskers locate what the bumper only felt, so the next plan goes round it); then
// replan to the same goal (a new decision if it is now unreachable, or after max_bumps_per_goal
// bumps on the way to it within touch_separation of a touch or bump before: the switches give
// the side, not the point, so an object can bump again; a bump at a new place is a new
// obstacle, marked, and does not count).
// A whisker touching while driving (update's contact mask): if the touch is at least
// touch_separation from every occupied cell of the KnownSpace and every touch acted on before,
// stop and whisk in place there (new evidence, reported like any whisk), then replan to the goal;
// else keep driving (a known object would stop the robot at every step).
// Stop rules, checked before each decision and while driving: the travel budget (metres the
// base's centre moved, translation only), the whisk budget, the policy's no-goal (its why), and
// max_failed_goals goals in a row that could not be planned or reached in time (boxed in).
// A goal given up is remembered: no later decision chooses a whisk pose within give_up_radius of
// it (ExploreState::given_up), so the policy looks elsewhere instead of retrying the same gap.
//
// Driving: update() is called by the control loop at any rate; it reads base.now(), odometry()
// and bumped(), never sleeps, and sends a command only when it changes.
// Ownership: references the base, known space and policy (they must outlive the loop); owns its
// BodyWhisk. Thread-safety: none. Allocation: a decision and a plan allocate (the policy's
// candidates, the search); following and whisking do not.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "crunch/behaviour/body_whisk.h"
#include "crunch/blackboard/params.h"
#include "crunch/core/rng.h"
#include "crunch/exploration/exploration.h"
#include "crunch/robot/mobile_base.h"

namespace crunch::session {

class ExploreLoop {
 public:
  enum class Phase : std::uint8_t { kDecide, kFollow, kAlign, kWhisk, kTouchWhisk, kBackOff, kDone };

  struct Options {
    exploration::ExploreOptions explore;  // policy, budgets, planner (validated)
    double speed = 0.2;               // m/s while following; > 0
    double turn_rate = kPi / 4;       // rad/s at most; > 0
    double waypoint_tolerance = 0.05; // m: a waypoint is reached
    double heading_tolerance = 0.03;  // rad: the goal heading is reached
    double aim_tolerance = 0.2;       // rad: turn in place above this bearing error
    double backoff = 0.05;            // m reversed after a bump
    double backoff_speed = 0.05;      // m/s
    double touch_separation = 0.05;   // m: a transit touch nearer known contacts is not new
    double record_every = 0.05;       // m between the path's recorded poses
    int max_failed_goals = 10;        // goal positions in a row not reached: boxed in
    int max_bumps_per_goal = 3;       // repeated bumps on the way to one goal: give it up
    // m: no whisk pose is chosen this near a goal given up (ExploreState::given_up): the
    // Create's diameter, so a goal approached through the same gap is not tried again.
    double give_up_radius = 2.0 * kRobotRadius;
    std::uint64_t seed = 1;           // the policy's stream
    BodyWhisk::Options whisk;         // the in-place whisk
    Status validate() const;
  };

  struct Hooks {
    // A whisk finished; `pose` is where it began. The caller senses, maps, updates the KnownSpace.
    std::function<void(const Pose2& pose)> whisked;
    // n posterior draws for the policy (when it wants any), appended to `out`; unset: none.
    // Returns false while the draws are not all made yet: the loop stands still and calls it
    // again, with the same `out`, at each update until it returns true (the robot's control
    // loop draws a slice per step and so never stalls; the simulator draws all at once).
    std::function<bool(int n, std::vector<MapSample>& out)> samples;
    // Where the body hit, if the base can tell (the simulator knows the obstacle; the Create's
    // bumpers say only left/right). Unset or nullopt: from base.bumper() (robot/bumper.h).
    std::function<std::optional<Vec2>(const Pose2& pose)> bump_point;
  };

  // Asserts options.validate(). Marks the body's disc at the start as free.
  ExploreLoop(MobileBase& base, exploration::KnownSpace& known, exploration::ExplorePolicy& policy,
              std::vector<WhiskerMount> mounts, ModelParams model, std::vector<Pose2> grid_poses,
              const Options& options, Hooks hooks);
  ExploreLoop(const ExploreLoop&) = delete;
  ExploreLoop& operator=(const ExploreLoop&) = delete;

  // One control step. `contact`: bit w while whisker w touches; `touch`: where, if the caller
  // knows (the simulator); else the loop takes the touching whisker's point at 2/3 of its length.
  // Returns the Error of a drive() that failed (the run should end).
  Status update(std::uint32_t contact, const Vec2* touch = nullptr);

  bool finished() const { return phase_ == Phase::kDone; }
  Phase phase() const { return phase_; }
  const std::optional<Pose2>& goal() const { return goal_; }
  // The report so far (path, whisk poses, bumps, travel, decisions); the caller adds the curve.
  exploration::ExplorationReport& report() { return report_; }
  const exploration::ExplorationReport& report() const { return report_; }
  // Ends the run now (e.g. the caller's time limit), with `why`.
  void finish(const std::string& why);
  // The base dropped or was told to drop the last command (a paused robot, a watchdog stop):
  // the next update() sends the current command again.
  void commandLost() {
    sent_ = false;
    whisk_.commandLost();
  }

 private:
  Status decideAndPlan();
  bool plan();
  int failGoal();  // counts the current goal as failed; returns the failures in a row
  Status command(double v, double omega);
  bool newTouch(const Vec2& p) const;
  Status afterBump();  // backed off (and whisked): replan to the goal, or give it up
  bool budgetReached(std::string& why) const;
  void track(const Pose2& pose);

  MobileBase& base_;
  exploration::KnownSpace& known_;
  exploration::ExplorePolicy& policy_;
  std::vector<WhiskerMount> mounts_;
  ModelParams model_;
  std::vector<Pose2> grid_;
  Options options_;
  Hooks hooks_;
  BodyWhisk whisk_;
  Rng rng_;
  exploration::ExplorationReport report_;
  Phase phase_ = Phase::kDecide;
  std::optional<Pose2> goal_;
  std::vector<Vec2> waypoints_;
  std::size_t next_wp_ = 0;
  double deadline_ = 0.0;
  Pose2 last_pose_, recorded_, whisk_pose_, backoff_from_;
  int failed_ = 0;
  std::vector<Vec2> given_up_;  // every goal given up, in order (ExploreState::given_up)
  int goal_bumps_ = 0;
  std::optional<Pose2> last_failed_;
  double decision_total_ms_ = 0.0;
  int decisions_ = 0;
  double start_time_ = 0.0;
  std::vector<Vec2> touches_;
  std::vector<MapSample> samples_;
  bool drawing_ = false;  // the samples hook is still drawing this decision's samples
  bool sent_ = false;
  bool bump_whisk_ = false;  // the bump was at a new place: whisk there once backed off
  double escape_heading_ = 0.0;  // the back-off: face this heading, then reverse
  bool escape_turned_ = false;
  double sent_v_ = 0.0, sent_omega_ = 0.0;
};

}  // namespace crunch::session
