// Training and evaluation of the signal models in the simulator, as the paper did it (issue 4;
// paper §2.4-2.5, results §3.1-3.2, Table 1, Figs. 9-10). docs/TRAINING.md has the protocol,
// the measured numbers against the paper's and the command that reproduces them.
//
// Every contact is made by the in-place body whisk (BodyWhisk::startInPlace(+1): toward +A,
// away to -A, back to the start heading at pi/24 rad/s), because the mapping run senses its
// pose grid with exactly this whisk (§2.6, §2.8; PhysicsSensorModel): templates and lines
// trained on another motion would not match what the mapper sees. Each contact runs through the
// whole physics path (WhiskerRig: ODE whiskers -> Hall model -> virtual whisker boards -> bridge
// decoder -> signal pipeline); the simulator's ground truth gives the labels.
//
//   Radial (§2.4, Table 1, Fig. 9). A thin pole (a 1 cm interior wall segment, 2 cm thick: the
//   World's wall thickness) stands with the centre of its near face at distance d from whisker
//   w's base, in a direction rotated by eps from the whisker's rest bearing toward the side the
//   toward leg sweeps the whisker into (CCW). Per whisker, `radial_repeats` contacts at each
//   nominal distance; the repeats jitter eps and d by seed. One contact = one whisk: f1 = the
//   largest f1 of whisker w over the whisk's episodes (one whisk may give several: the whisker can
//   slip past the pole's end and meet it again on the way back); its label r = the true contact
//   distance at that episode's peak (WhiskerTruth::r_at_peak). The nominal distance is kept too.
//   A second set, from another seed, is the held-out evaluation set.
//
//   Ramp (issue 12; docs/TRAINING.md, "Ramp calibration"). What the ramp's calibration
//   (signal::RampCalibration: gain, compliance_scale) is fitted on: point contacts over the
//   whole whisker, from near the follicle to the tip, on the objects the mapper meets. Two
//   objects stand in one World: a table's 5 cm square leg and a 2 cm square post, each met at a
//   vertical edge (corner) C. Per contact, C is at distance d along whisker w's rest line rotated
//   by eps toward the side the whisk first meets it: counter-clockwise (the toward leg) or
//   clockwise (the away leg, the mirror image), and the object's two faces leave C at
//   `edge` and edge + 90 degrees beyond the whisker's sweep, so the straight whisker meets the
//   edge before either face. The label is the simulator's true distance at the first step of the
//   contact (WhiskerTruth::r_at_touch: the point a located report places); the ramp is the
//   pipeline's fit of the first episode in which whisker w touched. A second set from another
//   seed is the held-out set.
//
//   Orientation (§2.5, Fig. 10). A long wall, met at the class angles (20..160 degrees), each
//   `orientation_repeats` times. The angle is the wall's tangent direction relative to the
//   robot's heading when the whisk starts (modulo pi: ContactReport::phi's convention). The
//   robot starts pressed against the wall, as the paper's robot was after driving into it: its
//   deepest straight whisker reaches `depth` past the wall's face at the start heading, so the
//   whiskers bend against the wall from the first samples and the window (aligned to the first
//   onset) opens within ~30 ms and ~0.2 degrees of the start: the heading at the first onset,
//   which PhysicsSensorModel takes as the template angle's reference, is measured and kept
//   (OrientationContact::onset_offset). A clear start does not work at every angle: where a
//   whisker points almost straight at the wall, the in-place turn cannot bring it any nearer
//   (at 60, 80, 100 and 120 degrees a start 3 mm clear gives no contact at all). Repeats jitter
//   the depth (the distance to the wall) and the position along the wall by seed. Each whisk's
//   first episode gives one window, labelled with the class angle and the repeat.
//
// Each protocol's World holds only what a whisker can touch there (the pole, or the wall, plus
// the arena boundary far out of reach); one rig is created clear of everything and the robot is
// re-placed for every contact (WhiskeredRobot::place), so the sensors calibrate once per set.
// Between whisks the robot stands clear until every detector has released: a detector still in
// contact after an episode cut by finish() cannot open the next episode before it releases.
//
// Thread-safety: none. ODE's collision scratch is global in this build (world.h): run one
// collection at a time, on one thread. Deterministic by seed: the same options give the same
// data bit for bit.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/core/result.h"
#include "crunch/robot/ramp_fit.h"
#include "crunch/robot/shapelet.h"
#include "crunch/signal/models_io.h"
#include "crunch/signal/orientation_templates.h"
#include "crunch/signal/radial_distance.h"
#include "crunch/signal/window.h"
#include "crunch_sim/whisker_rig.h"

namespace crunch::sim {

// The onset threshold of the rig's contact detectors the models are trained with (radians).
// A free whisker lags its base by up to ~0.0045 rad when the whisk starts or reverses (its own
// inertia against the follicle spring); the detector's default (max(6 sigma, 3e-4 rad), about
// 3e-4 with the sim's sensor noise) calls that a contact, on every whisker, at every start and
// reversal. Real contacts in the protocols peak at 0.14-0.46 rad. 0.008 rad sits well clear of
// both (docs/TRAINING.md has the measurements; training_report.json records them per run).
inline constexpr double kPhysicsOnsetThreshold = 0.008;

// The rig options the shipped models were trained with. The mapping path
// (`--sensor-model physics`) must build its rig with the same options, or its f1 and windows
// will not match the models: the models file has no room for them (models_io.h is strict), so
// this function is the record. `seed` seeds the Hall sensors' noise only.
WhiskerRig::Options physicsRigOptions(std::uint64_t seed = 1);

// The class angles used for orientation training (20..160 degrees, radians).
std::vector<double> trainingAngles();

struct TrainingProgress {
  int done = 0;              // whisks finished
  int total = 0;             // whisks planned
  const char* phase = "";    // "radial-train", "radial-heldout", "orientation"
  double simulated_s = 0.0;  // simulated time so far
};

struct TrainingOptions {
  std::uint64_t seed = 1;  // every jitter, and the Hall noise of every rig, derive from it
  // The rig (its seed is replaced by one derived from `seed` per rig). Models are only valid
  // for a mapping rig built with the same options: leave this at physicsRigOptions() unless
  // you are measuring what another setting does.
  WhiskerRig::Options rig = physicsRigOptions();

  // Radial protocol (§2.4): 5 contacts at 6 distances 10 mm apart over the 50 mm nearest the
  // tip. The nominal distances are those of the pole's face from the base; the contact slides
  // outward as the whisker bends, so the true r at the peak is ~5-10 mm further (85 -> ~95 mm,
  // 135 -> the tip). Nearer than ~80 mm the peak base angle reaches the Hall model's 30 degree
  // clamp (an invalid sample); 135 mm is the last position that is not past the tip.
  std::vector<int> radial_whiskers = {0, 1, 2, 3};
  std::vector<double> radial_distances = {0.085, 0.095, 0.105, 0.115, 0.125, 0.135};
  int radial_repeats = 5;
  double eps_min = 0.03;           // the pole's angular offset from the rest bearing, radians,
  double eps_max = 0.08;           //   uniform per contact
  double distance_jitter = 0.001;  // +- metres, uniform per contact
  bool radial_heldout = true;      // collect the held-out set (another seed) too

  // Ramp protocol (above): per whisker, per distance, per object (leg, post) and per direction
  // (counter-clockwise, and clockwise if ramp_both_directions), `ramp_repeats` contacts. The
  // distances run from near the follicle (at 20 mm the slope is ~9: the ramp's band is still
  // 80 samples long at the whisk's rate) to the tip; eps is drawn from [eps_min, eps_max] and d
  // jittered by distance_jitter as in the radial protocol; the edge angle is uniform in
  // [edge_min, edge_max] (radians from the line base -> C; in (0, pi/2) so that both faces lie
  // beyond the edge).
  std::vector<int> ramp_whiskers = {0, 1, 2, 3};
  std::vector<double> ramp_distances = {0.02, 0.035, 0.05, 0.065, 0.08, 0.095, 0.11, 0.125, 0.135};
  int ramp_repeats = 1;
  bool ramp_both_directions = true;
  double edge_min = 0.17;  // ~10 degrees
  double edge_max = 1.22;  // ~70 degrees
  bool ramp_heldout = true;  // collect the held-out set (another seed) too

  // Orientation protocol (§2.5): the class angles, `orientation_repeats` times each.
  std::vector<double> angles = trainingAngles();
  int orientation_repeats = 4;
  // How far the deepest straight whisker reaches past the wall's face at the start heading,
  // metres, uniform per contact. Below half the wall's 2 cm thickness, so ODE pushes the tip
  // back out of the near face.
  double depth_min = 0.002;
  double depth_max = 0.008;
  double lateral_jitter = 0.10;  // +- metres along the wall, uniform per contact

  // After the whisk ends, wait at most this long (simulated) for the last episode to end;
  // an episode still running then is ended with finish() (its window incomplete).
  double max_settle_s = 4.0;

  // Called after every whisk (from the collecting thread).
  std::function<void(const TrainingProgress&)> progress;

  // okStatus(), or an Error naming the bad field and its value.
  Status validate() const;
  // Whisks the options ask for.
  int plannedWhisks() const;
};

// Where a whisker's first contact of a whisk was located from (the pipeline's ramp), and the
// truth of that contact.
struct LocatedContact {
  bool detected = false;       // the pipeline saw the whisker touch in some episode
  int episode = -1;            // the first such episode
  signal::ContactRamp ramp;    // its ramp (ramp.valid: a ramp was fitted)
  Pose2 ramp_pose;             // the pose at the ramp's first sample (its position is the touch's)
  double f1 = 0.0;             // that episode's f1 (eq. 1), for eq. 2
  bool truth_touched = false;  // the simulator saw the whisker touch in that episode
  double r_touch = 0.0;        // true distance at the contact's first step (metres)
  double r_peak = 0.0;         // true distance at the episode's peak (eq. 2's label)
  Vec2 point_touch = Vec2::Zero();
};

// One episode of a whisk, as far as whisker `whisker` of the contact is concerned.
struct EpisodeRecord {
  double start_s = 0.0;  // first onset, seconds after the whisk began
  double duration_s = 0.0;
  bool touched = false;  // the pipeline saw whisker w touch in it
  double f1 = 0.0;       // its f1 (0 if not touched)
  bool truth_touched = false;
  double r_at_peak = 0.0;          // the simulator's true contact distance at the truth's peak
  std::uint32_t touched_mask = 0;  // every whisker the pipeline saw touch
};

// One radial-protocol contact (one whisk).
struct RadialContact {
  int set = 0;  // 0: training, 1: held-out
  int whisker = 0;
  int repeat = 0;
  double nominal_d = 0.0;  // metres: the protocol's distance
  double d = 0.0;          // metres: with the jitter (the pole's face from the base)
  double eps = 0.0;        // radians
  Pose2 pose;              // where the robot was placed
  std::vector<EpisodeRecord> episodes;
  bool detected = false;       // some episode saw whisker w touch: f1 and r are valid
  int peak_episode = -1;       // index of the episode with the largest f1
  double f1 = 0.0;             // max over the episodes (eq. 1 over the whole whisk)
  double r = 0.0;              // label: true r at that episode's peak (metres)
  bool truth_touched = false;  // the simulator saw whisker w touch in that episode
  // The same for the first episode in which the pipeline saw whisker w touch (the pass that
  // first met the pole: the toward leg), for the "first pass" variant of the evaluation.
  int first_episode = -1;
  double first_f1 = 0.0;
  double first_r = 0.0;
  LocatedContact located;           // the first pass's ramp and its truth at the touch
  double lever = 0.0;               // the mount's lever offset b
  std::uint32_t other_touched = 0;  // other whiskers the simulator saw touch during the whisk
  double max_free_theta = 0.0;      // largest detector theta of whiskers that never touched, rad
  bool truncated = false;           // some episode was truncated or ended early
};

// The object of a ramp-protocol contact.
enum class RampObject {
  kLeg,   // a table's 5 cm square leg, met at a vertical edge
  kPost,  // a 2 cm square post, met at a vertical edge
};
const char* rampObjectName(RampObject object);

// One ramp-protocol contact (one whisk).
struct RampContact {
  int set = 0;  // 0: training, 1: held-out
  int whisker = 0;
  int repeat = 0;
  RampObject object = RampObject::kLeg;
  int direction = +1;      // +1: met turning counter-clockwise (toward leg); -1: clockwise
  double nominal_d = 0.0;  // metres
  double d = 0.0;          // metres, jittered: the edge's distance from the base
  double eps = 0.0;        // radians, unsigned: the edge's offset from the rest line
  double edge = 0.0;       // radians: the first face's angle from the line base -> edge
  double lever = 0.0;      // the mount's lever offset b (WhiskerMount::base . direction())
  Pose2 pose;              // where the robot was placed
  LocatedContact contact;  // whisker `whisker`'s
  std::uint32_t other_touched = 0;  // other whiskers the simulator saw touch during the whisk
  bool truncated = false;
};

// A pose the pipeline's samples had, kept for locating the contacts afterwards.
struct SamplePose {
  std::uint64_t sample = 0;
  Pose2 pose;
};

// One orientation-protocol contact (one whisk).
struct OrientationContact {
  int repeat = 0;
  double angle = 0.0;    // class angle, radians (the label)
  double depth = 0.0;    // metres
  double lateral = 0.0;  // metres along the wall
  Pose2 pose;            // where the robot was placed
  int episodes = 0;
  bool has_window = false;  // the first episode's window was complete
  signal::ContactWindow window;
  double onset_s = 0.0;  // first onset, seconds after the whisk began
  // Heading change from the start of the whisk to the first onset, radians: the wall's tangent
  // relative to the heading at the first onset is angle - onset_offset.
  double onset_offset = 0.0;
  std::uint32_t touched_mask = 0;  // whiskers the pipeline saw touch in the first episode
  double max_free_theta = 0.0;
  // Every episode of the whisk and the poses of its onset, peaks and ramps: enough to run the
  // host's WhiskEvidence over the whisk afterwards with any models (locating the wall as a face
  // from two whiskers' tips, evaluateFaces).
  std::vector<signal::ContactEpisode> all_episodes;
  std::vector<SamplePose> poses;
};

struct TrainingData {
  std::vector<RadialContact> radial;  // training set, then held-out set
  std::vector<RampContact> ramp;      // training set, then held-out set
  std::vector<OrientationContact> orientation;
  double simulated_s = 0.0;
  std::uint64_t missing_frames = 0;  // bridge frames the rigs' decoders never saw
};

// Runs both protocols. Errors: invalid options, or a rig that cannot be built (the message says
// which). Whisks with no detected episode are kept and counted by the evaluation.
Result<TrainingData> collectTrainingData(const TrainingOptions& options);

// A rigid placement: where to put the robot so that whisker `whisker`'s rest line has the
// pole's near face at distance d from its base, rotated eps CCW about the base (metres,
// radians), given the face's centre `face` (a point in the arena) and the pole's long axis
// direction `axis` (the robot is turned so the whisker's rest direction is along `axis`).
Pose2 placeForPole(const std::vector<WhiskerMount>& mounts, int whisker, double d, double eps,
                   const Vec2& face, double axis);

// The ramp placement: where to put the robot so that whisker `whisker`'s rest line has the edge
// `corner` at distance d from its base, rotated eps (unsigned) toward the side the whisk meets it
// first (direction +1: counter-clockwise, -1: clockwise), the object's faces leaving the corner
// at world directions face_dir and face_dir + pi/2, and the first face of the sweep at `edge`
// radians from the line base -> corner.
Pose2 placeForEdge(const std::vector<WhiskerMount>& mounts, int whisker, double d, double eps,
                   int direction, const Vec2& corner, double face_dir, double edge);

// The orientation placement: the pose at which the wall's tangent is at `angle` relative to
// the robot's heading and the deepest straight whisker reaches `depth` past the wall's face.
// The face is the line through `face_point` along `wall_dir`; the robot stands on the side that
// the unit vector `toward` points into, `lateral` metres along the line from face_point.
Pose2 placeWall(const std::vector<WhiskerMount>& mounts, double angle, double depth, double lateral,
                const Vec2& face_point, double wall_dir, const Vec2& toward);

// ---- Evaluation.

// How r is predicted from f1 (one line per whisker either way).
enum class RadialFeature {
  kF1,         // eq. 2: r = a1 f1 + a0
  kInvSqrtF1,  // r = a1 f1^(-1/2) + a0 (a tapered cantilever's base moment falls ~1/d^2)
};
enum class RadialLabel {
  kTruthAtPeak,  // the simulator's contact distance at the peak
  kNominal,      // the protocol's placement distance (pole face from the base)
};
// Which peak is a contact's f1.
enum class F1Source {
  kMaxOverWhisk,  // the largest over the whisk's episodes (the protocol; PhysicsSensorModel)
  kFirstEpisode,  // the first episode that saw the whisker touch (the first pass)
};
struct RadialVariant {
  F1Source source = F1Source::kMaxOverWhisk;
  RadialFeature feature = RadialFeature::kF1;
  RadialLabel label = RadialLabel::kTruthAtPeak;
};
const char* radialFeatureName(RadialFeature feature);
const char* radialLabelName(RadialLabel label);
const char* f1SourceName(F1Source source);
// Every combination, the protocol's own (max, f1, truth) first.
std::vector<RadialVariant> allRadialVariants();

struct RadialEvaluation {
  RadialVariant variant;
  signal::RadialFit fit;  // on the training set (lines in the feature's x)
  // Held-out errors r_hat - r of the per-whisker lines, metres.
  std::array<double, signal::kWhiskers> heldout_rms{};  // Table 1's sigma per whisker
  std::array<double, signal::kWhiskers> heldout_mean{};
  std::array<int, signal::kWhiskers> heldout_n{};
  double heldout_rms_all = 0.0;  // every whisker's held-out errors together
  double heldout_mean_all = 0.0;
  int heldout_n_all = 0;
  double combo_heldout_rms = 0.0;  // one line through all whiskers' training data ("Combo")
};

// Fits on the training set (set 0) and scores on the held-out set (set 1); contacts without a
// detection are left out (counted by the caller). Error if fitRadialModel fails (e.g. fewer
// than 3 contacts of a whisker) or the held-out set is empty.
// With F1Source::kFirstEpisode the label is the truth at that episode's peak.
Result<RadialEvaluation> evaluateRadial(const std::vector<RadialContact>& contacts,
                                        const RadialVariant& variant,
                                        const signal::RadialOptions& options = {});

// ---- The ramp (issue 12): the host's reading of a located contact, the calibration fit and
// its evaluation (Table 1 re-measured), and faces located from two whiskers (Fig. 10
// re-measured).

// The distance the host reads from a located contact, as session::WhiskEvidence reads it:
// distanceFromRampSlope of the nominal beam with the calibration, at most the whisker's length.
double rampDistance(const LocatedContact& c, double lever, const signal::RampCalibration& cal);

// The calibration fit's samples: the contacts of `set` whose whisker the pipeline and the
// simulator both saw touch and whose contact has a ramp; the label is the truth at the touch.
std::vector<RampSample> rampSamples(const std::vector<RampContact>& contacts, int set);

// Errors of one estimate over a set of contacts (metres): per whisker and all together, and the
// median and 90th percentile of |error|.
struct ErrorStats {
  std::array<double, signal::kWhiskers> rms{}, mean{};
  std::array<int, signal::kWhiskers> n{};
  double rms_all = 0.0, mean_all = 0.0, median_abs = 0.0, p90_abs = 0.0;
  int n_all = 0;
};
// From (whisker, error) pairs.
ErrorStats errorStats(const std::vector<std::pair<int, double>>& errors);

struct RampEvaluation {
  RampFitSummary fit;                   // on the ramp training set
  signal::RampCalibration calibration;  // fit's gain and compliance_scale
  // The ramp held-out set (the whole whisker, legs and posts, both directions): ramp distance
  // with the nominal and the fitted calibration against the truth at the touch, and eq. 2 (the
  // given lines on the first pass's f1) against its own label, the truth at the peak.
  ErrorStats nominal, fitted, eq2;
  // The same on the paper's radial protocol (held-out set: the pole, 85-135 mm), the ramp of
  // the first pass against the truth at the touch.
  ErrorStats radial_nominal, radial_fitted;
  int heldout_contacts = 0;  // ramp held-out whisks
  int heldout_no_ramp = 0;   // of which: the whisker touched but no ramp was fitted
  int heldout_not_seen = 0;  //           the pipeline or the simulator did not see it touch
};

// Fits the calibration on the ramp training set (set 0) and scores it on the held-out sets.
// `eq2` gives the old estimate beside it. Errors: the fit's (ramp_fit.h), or an empty held-out
// set.
Result<RampEvaluation> evaluateRamp(const TrainingData& data, const signal::RadialModel& eq2,
                                    const RampFitOptions& options = {});

// Fig. 10 with the new localisation: each orientation whisk through the host's WhiskEvidence
// with `models`; a whisk whose reports include a face (two tip contacts, whisk_evidence.h)
// gives the face's direction, scored against the wall's (error in (-pi/2, pi/2]).
struct FaceTrial {
  int repeat = 0;
  double true_angle = 0.0;  // the class angle, radians
  bool located = false;     // the whisk gave a face
  double error = 0.0;       // radians (located only)
  int reports = 0;          // located reports of the whisk
  int tips = 0;             // of which tip contacts
};
struct FaceEvaluation {
  std::vector<FaceTrial> trials;
  int located = 0;
  double mean_error = 0.0, sd_error = 0.0, rms_error = 0.0, max_abs_error = 0.0;  // radians
};
FaceEvaluation evaluateFaces(const std::vector<OrientationContact>& contacts,
                             const signal::SignalModels& models);

// The labelled windows of the orientation contacts that have a complete window.
std::vector<signal::LabelledWindow> labelledWindows(
    const std::vector<OrientationContact>& contacts);

}  // namespace crunch::sim
