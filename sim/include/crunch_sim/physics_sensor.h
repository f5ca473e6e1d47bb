// The physics sensor model (`crunchhost --sim --sensor-model physics`, ARCHITECTURE.md §2):
// at each pose the simulated robot performs the in-place body whisk (§2.3, behaviour/
// body_whisk.h) with bending ODE whiskers, and the reports come out of the paper's own
// classifiers — eq. 1-2 radial distance and eq. 3 orientation templates — fed through the
// Hall model, the firmware on virtual whisker boards, the bridge decoder and the signal
// pipeline (WhiskerRig). Its noise is what those classifiers make; nothing is added.
//
// Reports and negative evidence come from the rig's session::SensingChain (session/
// sensing_chain.h: decoder, sample assembler, signal pipeline, WhiskEvidence), the chain
// `crunchhost --robot` runs, with the simulator's exact pose as its pose source (§2.8); sense()
// opens a whisk on it where the robot's control loop writes the whisk-start mark, and closes it
// when the whisk's last episode has ended. One whisk may give several contact episodes (the
// whisker meets the object on the toward and on the return pass); each whisker reports at most
// once per whisk, from the first episode in which it touched: its f1 is the peak of that first
// pass (eq. 1), as the shipped models were trained (`crunchhost train --radial-f1 first`;
// docs/TRAINING.md: the return pass can meet a thin object's far side and peak higher, which
// made the radial error 5.5 mm instead of 1.9 mm):
//   r     the radial model's estimate (eq. 2), clamped to [0, external length];
//   phi   the orientation template's angle (eq. 3), which is relative to the heading at the
//         episode's first contact, turned into the frame of the robot at this whisker's peak;
//   robot the odometry pose at the peak sample (exact in the simulator, §2.8).
// A whisker without a radial estimate, or an episode without an orientation (window cut short),
// gives no report; both are counted.
//
// Arriving: a pose whose straight whiskers would start inside a wall or leg (the grid is laid
// out for the body, not for the whiskers) is driven into along its heading from where they are
// clear, at 5 cm/s, as the robot would arrive; the whisk then starts pressed.
//
// Between poses: a whisk that ended with a whisker still in contact is followed by a rest at the
// clear start pose until the detectors release (at most 1 s), so the next pose starts free.
//
// Negative evidence: the chain's, as on the robot: every WhiskEvidence::kFreeEvery pipeline
// samples (60 ms, ~0.45 degrees of the whisk), at all times — the whisk, the wait for its last
// episode to end, and the rest at the clear pose between whisks — a whisker whose detector saw
// no contact within +-kFreeGuard such samples (0.24 s) contributes its straight rest ray.
// (Before issue 11 the physics path sampled only during the whisk, counted from its start;
// docs/WHISKERS.md, "Physics path through the session", compares the two.)
//
// Untouchable whisks (Options::skip_untouchable, docs/WHISKERS.md "Skipping untouchable
// whisks"): sense() alone decides, before each whisk, whether it may leave ODE out. If no
// straight whisker comes within Options::skip_margin of a wall or leg at any heading of the
// whisk, theta0 +- (A + kSkipHeadingSlack) (inPlaceWhiskClear, whisk_clearance.h), the whole
// whisk and the wait after it run with the robot free-running (WhiskeredRobot::setFreeRunning):
// the base turns exactly as with ODE (same DiffDrive integration, same steps, same time) and the
// whiskers' base angles replay ODE's own free response to the whisk's turns (to 2e-13 rad); the
// Hall model (and its noise stream), the boards, the bridge bytes, the chain and its free-ray
// sampling run unchanged, one 500 us sample at a time. Why it is safe: a whisker that cannot
// reach anything can give no contact, so ODE would compute only that free ringing (<= 5.2 mrad
// at the base, 1.4 mm at the tip), which the margin covers with the capsules' radius. On the
// default arena skipping 224 of its 320 whisks changes nothing sensed: the same 147 reports, r,
// phi and poses bit for bit, the same free rays (test/sim/physics_sensor_test.cc checks a small
// scene). If the heading ever left the checked range, sense() would put the robot back on ODE at
// once (never seen: the whisk overshoots its targets by at most one step's turn, 65 urad).
//
// Time slices (docs/WHISKERS.md "Time slices"): the same question is asked per whisker and per
// kSliceWidth slice of the whisk's headings, and for the straight approach to a pose near a wall
// or leg (straightPathClear). The robot tracks its free responses
// (WhiskeredRobot::trackFreeResponses), so a whisker runs in ODE only in the slices where it can
// touch something (and their neighbours), comes back into ODE in the state ODE would have given
// it, and leaves again once back on its free trajectory (a released whisker's ringing has died
// out). Whisks that start pressed after an approach are sliced as well. On the default arena
// this takes the physics run from 79 to 45 s (docs/BENCHMARKS.md) with the same map; the test
// requires the same reports and free rays bit for bit on whisks with and without approaches.
//
// Scoring: against the simulator's ground truth of the contact (WhiskerTruth: its track of true
// contact points and its first touch), the reports' errors in position, r and phi are
// accumulated (errors()), for report.json's physics block.
//
// Ownership: owns its WhiskerRig; references the World, which must outlive it.
// Thread-safety: none (ODE). Allocation: sense() reuses its buffers after the first poses.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "crunch/mapping/sensor_model.h"
#include "crunch/session/whisk_evidence.h"
#include "crunch/signal/models_io.h"
#include "crunch_sim/whisker_rig.h"
#include "crunch_sim/world.h"

namespace crunch::sim {

// Errors of the reports against the simulator's truth of the contact (WhiskerTruth): where the
// whisker truly touched while it was measured (its track) and where it first touched.
struct ReportErrors {
  int reports = 0;             // reports scored (the truth saw the whisker touch)
  int unscored = 0;            // reports whose whisker the truth never saw touching
  double sum_r = 0.0, sum_r2 = 0.0;      // r_hat - r_true, metres
  // Orientation, scored for flat-surface reports only (ContactReport::oriented): an edge's
  // "normal" is no truth. phi_hat - phi_true wrapped to [-pi/2, pi/2), radians.
  int oriented = 0;
  double sum_phi = 0.0, sum_phi2 = 0.0;
  // Distance from each scored report's contact point to the truth, metres: all, and split by
  // what was touched (a leg: a footprint no side of which is longer than 0.1 m; else a wall).
  // For a leg, to the nearest point of the contact's true track (a pressed tip slides round a
  // leg before and while the ramp measures it: WhiskerTruth::track); for a wall, to the face
  // through the first touch (any point of the face is a true contact). The r error is against
  // the first touch.
  std::vector<double> position_errors, leg_position_errors, wall_position_errors;
  // Legs only: to the first touch (the straight whisker's first contact), which a contact that
  // slid before the ramp was measured no longer touches (docs/SIGNAL.md).
  std::vector<double> leg_first_touch_errors;
  // Tip or shaft (r in the models' tip zone), reported against true: [true shaft][reported shaft].
  int tip_confusion[2][2] = {{0, 0}, {0, 0}};
  int whisks = 0;
  int episodes = 0;
  int no_radial = 0;           // touched whiskers without an r estimate
  int no_orientation = 0;      // touched whiskers whose episode had no orientation
  int no_ramp = 0;             // touched whiskers whose contact had no ramp to locate it
  double simulated_s = 0.0;    // simulated time spent sensing
  // Whisker-steps simulated, and those of them in ODE (the rest replayed their free response:
  // skipped whisks and time slices).
  long long whisker_steps = 0, ode_whisker_steps = 0;

  double meanR() const { return reports ? sum_r / reports : 0.0; }
  double sigmaR() const;       // root mean square error, metres
  double meanPhi() const { return oriented ? sum_phi / oriented : 0.0; }
  double sigmaPhi() const;     // root mean square error, radians
};

// The q-quantile (0..1, linear interpolation) of `v`; 0 for an empty one.
double quantile(std::vector<double> v, double q);
// Smallest Options::skip_margin: twice the reach of ODE's free whisker beyond the straight line
// (1.4 mm of tip ringing, 0.61 mm capsule radius; see Options::skip_margin), rounded up.
inline constexpr double kMinSkipMargin = 0.005;
// Headings beyond the whisk's +-A that the skip check covers as well, radians: a phase ends at
// the first step past its target (65 urad at pi/24 rad/s), and a wheel ramp
// (WhiskeredRobot::Options::max_wheel_acceleration) may carry the turn a few mrad further.
inline constexpr double kSkipHeadingSlack = 0.01;
// Width of the heading slices in which the time-sliced whisk decides which whiskers need ODE,
// radians (0.5 degrees; a slice is about 140 steps of the whisk's turn).
inline constexpr double kSliceWidth = 0.5 * kPi / 180.0;

class PhysicsSensorModel final : public SensorModel {
 public:
  struct Options {
    WhiskerRig::Options rig;  // must be the options the models were trained with
    double max_settle_s = 4.0;  // after the whisk, wait at most this for the episode to end
    // Leave ODE out of whisks that cannot touch anything (see the top of this file). Off: every
    // whisk in ODE, as before issue 12 (for comparing the two).
    bool skip_untouchable = true;
    // How far (metres) every straight whisker must stay from every wall and leg over the whisk
    // for it to be skipped; in [kMinSkipMargin, 0.1]. It covers where ODE's free whisker may be
    // beyond the straight line checked: its ringing (tip <= 1.4 mm off straight), the capsule
    // radius (<= 0.61 mm) and ODE's contact layer (0.01 mm); 10 mm is five times their sum.
    double skip_margin = 0.01;
    Status validate() const;
  };

  // Builds the rig (powering the boards up and calibrating at rest at the first pose of
  // `clear_candidates` where no whisker touches anything) and sets the models. Errors: invalid
  // options or models, or no clear start pose.
  static Result<std::unique_ptr<PhysicsSensorModel>> create(
      const World& world, std::vector<WhiskerMount> mounts, const signal::SignalModels& models,
      const std::vector<Pose2>& clear_candidates, const Options& options);

  // The whisk at `pose`. `rng` is not used: the noise comes from the Hall model's own seeded
  // stream (Options::rig.seed) and the classifiers.
  void sense(const Pose2& pose, Rng& rng, std::vector<ContactReport>& out) override;
  const std::vector<WhiskerMount>& mounts() const override { return mounts_; }
  void freeRays(std::vector<FreeRay>& out) const override {
    out.insert(out.end(), free_.begin(), free_.end());
  }

  const ReportErrors& errors() const { return errors_; }
  const WhiskerRig& rig() const { return *rig_; }
  // Whisks run free-running (without ODE) because they could not touch anything.
  int skippedWhisks() const { return skipped_whisks_; }

 private:
  PhysicsSensorModel(const World& world, std::unique_ptr<WhiskerRig> rig,
                     std::vector<WhiskerMount> mounts, const Options& options);
  // Keeps the truth of the episode that just ended for the whiskers it gave their first report
  // (bit w: whisker w).
  void score(std::uint32_t set);

  // What a report is scored against, kept when the episode that set it ended.
  struct Score {
    bool scored = false;
    WhiskerTruth truth;  // the truth of the episode that set the whisker's report
  };
  // Adds one report's errors to errors_ (scores_ holds its whisker's truth).
  void tally(const ContactReport& report);

  const World& world_;
  std::unique_ptr<WhiskerRig> rig_;
  std::vector<WhiskerMount> mounts_;
  Options options_;
  std::vector<Score> scores_;   // per whisker
  std::vector<FreeRay> free_;
  ReportErrors errors_;
  Pose2 clear_pose_;  // where the rig calibrated: every whisker free
  std::vector<OrientedRect> legs_;  // the World's leg footprints (for scoring by object)
  int skipped_whisks_ = 0;
  std::vector<std::uint32_t> danger_;  // per heading slice of the whisk: whiskers in reach
};

// The options the shipped models were trained with (docs/TRAINING.md), with the Hall noise
// seeded by `seed`.
PhysicsSensorModel::Options physicsSensorOptions(std::uint64_t seed);

}  // namespace crunch::sim
