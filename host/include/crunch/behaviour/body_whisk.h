// The body whisk (paper §2.3): the whiskers are not actuated, so the whole robot turns to sweep
// them over an object. On a contact the robot
//   1. reverses a short distance                       (kBackOff,  reverse_distance),
//   2. rotates toward the object at pi/24 rad/s        (kToward,   heading theta0 -> theta0 + s*A),
//   3. rotates away from it at pi/24 rad/s             (kAway,     -> theta0 - s*A),
//   4. reverses to clear the object                    (kClear,    clear_distance),
//   5. turns a random amount in a random direction     (kTurn,     [turn_min, turn_max]),
//   6. and goes forward again                          (kForward),
// where theta0 is the heading when the whisk begins (after step 1), A = whisk_amplitude and
// s = +1 (counter-clockwise) or -1 the side of the object. The sweep theta0 -> theta0 + s*A ->
// theta0 - s*A is the one the simulator's RaySensorModel performs; with the default A = pi/12
// the toward leg takes 2 s at pi/24 rad/s, the paper's 2 s recording window (§2.5), measured
// from whiskStartTime(); contactTime() is when the contact was first seen.
//
// Which side the object is on: the contact mask's bit w says whisker w touches, and
// Options::whisker_bearings[w] is where that whisker points (radians from the robot's +x, CCW;
// the defaults are defaultWhiskerArray()'s four, in its order). The object is on the side of the
// touching whiskers' mean bearing: s = sign(sum over touching w of sin(bearing_w)), so left
// (positive bearings) turns counter-clockwise; a sum within 1e-9 of 0 (a symmetric pair, a
// whisker straight ahead or behind) turns counter-clockwise. Bits at or past the number of
// bearings are ignored.
//
// The in-place whisk, for the pre-determined pose grid of the mapping experiment (§2.6, §2.8):
// at the current pose rotate toward, then away, then back to the start heading (kToward, kAway,
// kReturn at whisk_rate, no reversing, no turn), then stop and report done() (kDone).
//
// A bump (bumper or wheel drop, MobileBase::bumped()) in any phase but kBumpBackOff stops the
// base in that same update() and, from the next one, reverses bump_backoff (kBumpBackOff).
// Then a roaming robot makes the random turn and goes on; an in-place whisk ends, done() with
// interrupted() set (its sweep is incomplete).
//
// Driving: update() is called by the control loop at any rate. It reads the time from
// base.now() and the motion from base.odometry(), never sleeps, and decides on the state then:
// a phase ends at the first update() at which its target (distance from where the phase began,
// or heading swept, accumulated update to update) is reached, so it overshoots by at most the
// motion between two updates. The whisk's three legs all measure from theta0, so overshoots do
// not add up. A phase that has not reached its target after timeout_factor times its nominal
// duration plus timeout_slack (a base that does not move) ends anyway and is counted in
// stats().timeouts. A command is sent only when it changes; if drive() fails, update() returns
// the Error and sends the command again at the next update().
//
// Ownership: holds a reference to the MobileBase, which must outlive it.
// Thread-safety: none; called from the one control loop that owns the base.
// Allocation: the options' bearing list is copied at construction; start*/update() allocate
// nothing.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "crunch/robot/mobile_base.h"
#include "crunch/core/geometry.h"
#include "crunch/core/result.h"
#include "crunch/core/rng.h"

namespace crunch {

class BodyWhisk {
 public:
  enum class Phase : std::uint8_t {
    kIdle,         // not started, or halted: no command sent
    kForward,      // roaming: forward at forward_speed until a whisker touches
    kBackOff,      // contact seen: reversing reverse_distance
    kToward,       // rotating toward the object at whisk_rate, to theta0 + s*A
    kAway,         // rotating away at whisk_rate, to theta0 - s*A
    kReturn,       // in place only: rotating back to theta0 at whisk_rate
    kClear,        // roaming: reversing clear_distance
    kTurn,         // roaming: the random turn at turn_rate
    kBumpBackOff,  // after a bump: reversing bump_backoff
    kDone,         // in place only: finished (or interrupted by a bump), stopped
  };

  struct Options {
    double forward_speed = 0.1;         // m/s while roaming; > 0
    double reverse_speed = 0.05;        // m/s in every reversing phase; > 0
    double reverse_distance = 0.03;     // m, the short reverse before the whisk; >= 0
    double whisk_rate = kPi / 24;       // rad/s, the paper's rotation rate; > 0
    double whisk_amplitude = kPi / 12;  // A, rad each way: 2 s at pi/24; in (0, pi/2]
    double clear_distance = 0.15;  // m reversed after the whisk: past the 0.14 m whiskers; >= 0
    double turn_min = kPi / 6;     // the random turn's magnitude is uniform in
    double turn_max = kPi;         //   [turn_min, turn_max] rad; 0 <= min <= max <= pi
    double turn_rate = kPi / 4;    // rad/s of the random turn; > 0
    double bump_backoff = 0.05;    // m reversed after a bump; >= 0
    double timeout_factor = 3.0;   // a phase times out after factor * nominal + slack; >= 1
    double timeout_slack = 1.0;    // s; >= 0
    std::uint64_t seed = 1;        // the random turns' stream (crunch::Rng)
    // Whisker w's bearing, radians from the robot's +x, CCW; 1..32 of them. Default: the four of
    // defaultWhiskerArray(), -33.75, -11.25, +11.25, +33.75 degrees.
    std::vector<double> whisker_bearings = {-33.75 * kPi / 180, -11.25 * kPi / 180,
                                            11.25 * kPi / 180, 33.75 * kPi / 180};

    // okStatus(), or an Error naming the first bad field and its value.
    Status validate() const;
  };

  struct Stats {
    int whisks_started = 0;    // contacts acted on, plus in-place whisks begun
    int whisks_completed = 0;  // whisks whose away leg finished (timed out or not)
    int bumps = 0;             // bumps acted on
    int turns = 0;             // random turns begun
    int timeouts = 0;          // phases ended by their deadline, not their target
  };

  // Asserts options.validate() is ok. Sends nothing until a start call.
  BodyWhisk(MobileBase& base, const Options& options);
  BodyWhisk(const BodyWhisk&) = delete;
  BodyWhisk& operator=(const BodyWhisk&) = delete;

  // Begins roaming: kForward, the forward command sent now. Clears done()/interrupted().
  Status startRoaming();
  // Begins an in-place whisk at the current pose: kToward now, toward counter-clockwise first if
  // direction >= 0, clockwise if < 0. whiskStartTime() and contactTime() are now.
  Status startInPlace(int direction = +1);
  // Stops the base and goes to kIdle.
  Status halt();
  // The base dropped the last command (its watchdog stopped the motors while the control loop
  // stalled): the next update() sends the current phase's command again.
  void commandLost() { sent_ = false; }

  // One control step; `contact` has bit w set while whisker w touches (see the top). Contact is
  // acted on only in kForward; during a whisk the whiskers are meant to touch. Returns the Error
  // of a drive() call that failed, else okStatus().
  Status update(std::uint32_t contact);

  Phase phase() const { return phase_; }
  // An in-place whisk has finished (kDone).
  bool done() const { return phase_ == Phase::kDone; }
  // The in-place whisk ended early because of a bump.
  bool interrupted() const { return interrupted_; }
  // base.now() at the update() that saw the contact which began the current (or last) whisk,
  // or at startInPlace(); nullopt before any whisk.
  std::optional<double> contactTime() const { return contact_time_; }
  // base.now() when the current (or last) whisk's toward leg began (theta0); nullopt before.
  std::optional<double> whiskStartTime() const { return whisk_start_time_; }
  // base.now() when the current phase began.
  double phaseStartTime() const { return phase_start_time_; }
  // +1 if the current (or last) whisk turned counter-clockwise first, -1 clockwise.
  int towardSign() const { return side_; }
  // The last random turn drawn, signed (CCW positive), radians; 0 before any.
  double lastTurn() const { return turn_; }
  const Stats& stats() const { return stats_; }
  const Options& options() const { return options_; }

  // The side of the touching whiskers' mean bearing: +1 (left, CCW), -1 (right), or 0 if no
  // whisker in `bearings` touches. A sum of sines within 1e-9 of 0 gives +1.
  static int towardSide(std::uint32_t contact, std::span<const double> bearings);
  static const char* phaseName(Phase phase);

 private:
  void enter(Phase phase, double now, const Pose2& pose);
  // Runs the transitions the current state allows; returns true if the phase changed.
  bool step(std::uint32_t contact, double now, const Pose2& pose);
  Status sendCommand();

  MobileBase& base_;
  Options options_;
  Rng rng_;
  Stats stats_;
  bool in_place_ = false;
  bool interrupted_ = false;
  Phase phase_ = Phase::kIdle;
  double phase_start_time_ = 0.0;
  double deadline_ = 0.0;
  Pose2 phase_start_pose_;
  double last_theta_ = 0.0;  // odometry heading at the last update, for the sweep
  double sweep_ = 0.0;       // heading turned since theta0 (whisk) or since kTurn began, CCW
  int side_ = 1;
  double turn_ = 0.0;
  std::optional<double> contact_time_;
  std::optional<double> whisk_start_time_;
  // The command the phase wants, and the last one the base took.
  double want_v_ = 0.0, want_omega_ = 0.0;
  bool sent_ = false;
  double sent_v_ = 0.0, sent_omega_ = 0.0;
};

}  // namespace crunch
