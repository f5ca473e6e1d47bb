// Bending whiskers in ODE (paper §2.1-2.3, issue 4): the physical path from a body whisk to the
// base deflection an MLX90333 Hall sensor sees.
//
// WhiskerBeam (robot/whisker_beam.h, the robot's description: the host locates contacts with
// it too) is one whisker's geometry and material and the tapered Euler-Bernoulli theory the
// simulation is checked against (docs/WHISKERS.md has the sources of every number):
//   D(s)  diameter at distance s from the follicle along the external shaft, linear from
//         1.45 mm at the magnet end of the 160 mm whisker to 0.3 mm at the tip (§2.1); the inner
//         20 mm sit in the polyurethane plug, so the shaft leaves it at D(0) = 1.306 mm;
//   I(s)  = pi D(s)^4 / 64, the second moment of area of the round section;
//   C(d)  = d^2 / k_base + integral_0^d (d - s)^2 / (E I(s)) ds, the lateral compliance at d of a
//         cantilever on a rotational base spring k_base (the "follicle": the plug);
//   a lateral push delta at d then needs F = delta / C(d), gives a base moment M = F d and a
//   base rotation theta = M / k_base, which is what the Hall sensor reads (eq. 1's deflection).
//
// WhiskeredRobot is the simulated CrunchBot of the physics sensor path: a Create-like base
// carrying N such whiskers in an ODE dynamics world, implementing crunch::MobileBase so the same
// behaviour code (body whisk, §2.3) drives it and the robot.
//   - The base is kinematic (infinite mass, moved by its commanded velocity): a differential
//     drive whose wheel speeds are limited to the Create's +-0.5 m/s by scaling both wheels by
//     one factor, keeping the path's curvature, as the Create driver does (DiffDrive,
//     diff_drive.h, shared with KinematicBase; until issue 11 each wheel was clamped on its own,
//     which bent the path). Its pose is integrated
//     exactly (circular arcs); odometry() returns that pose: zero odometry noise, as in the
//     paper's mapping simulation (§2.8). In ODE it is one kinematic body per whisker, all moved
//     together, so that each whisker is an island of its own (see Whisker::follicle).
//   - The base does not collide physically; World::bodyCollides is its bumper. A substep whose
//     end pose would collide and sit deeper in an obstacle than its start pose (a smaller signed
//     clearance to the nearest wall or leg footprint) is refused: the base keeps its position
//     for that substep, still turning in place if commanded (a round body cannot turn deeper),
//     until a command backs it out. bumped() is the Create's bumper, which covers the front
//     half of the body: true while a wall or leg touches the body ahead of the wheel axle
//     (within kRobotRadius + kBumperReach of the centre), at the pose or where the step's
//     command would have taken it, updated every substep (turning in place too). A contact
//     behind the axle stalls the wheels but presses no bumper, as on the Create: a robot that
//     backs into a leg is not told "bumped" and so does not try to back off further into it.
//     bumper() says which of its two switches close (robot/bumper.h, bumperAt: the bearing of
//     the touching wall's or leg's nearest point from the centre; both for several)
//     (the 1 h soak of 2026-11-28 found that loop: docs/HARDENING.md).
//   - Each whisker is a chain of rigid capsules joined by two-axis spring-damper joints (ODE
//     universal joints): axis 1 vertical (in-plane, "horizontal" bending), axis 2 horizontal
//     across the shaft (vertical bending). The shaft is cut into Options::elements beam elements
//     (shorter toward the tip, Options::element_grading); each element's joint lumps its exact
//     bending compliance, 1/k_j = integral over the element of ds / (E I(s)), and sits at the
//     element's compliance centroid, which makes the chain's C(d) exact for pushes beyond the
//     element up to the element's own spread. Capsules run from joint to joint (elements + 1 of
//     them, the last ending at the tip). The follicle joint to the base is the plug's k_base.
//     Springs use ODE's implicit scheme (a joint stop with lo = hi = 0,
//     StopERP = h kp / (h kp + kd), StopCFM = 1 / (h kp + kd)): stable for any stiffness.
//   - ODE's direct solver (dWorldStep) solves each whisker exactly every step. Its iterative
//     one (dWorldQuickStep) was measured 10-80 % off the beam theory at 30-150 iterations.
//   - Whisker-surface contacts are stiff implicit spring-dampers with Coulomb friction
//     (Options::contact_stiffness, friction). Whiskers collide with the World's walls and legs
//     only (the only things built, §3 of ARCHITECTURE.md); not with each other or with the base.
//     No gravity: the contacts are with vertical prisms and so horizontal, and the real
//     whisker's static sag is the rest angle the Hall sensor's calibration removes.
//   - Stability: joint error correction 0.8 per step, a little constraint force mixing to keep
//     the LCP regular, a cap on contact correction speed, and adaptive substeps when a capsule
//     turns fast (Options::max_rotation_per_substep); docs/WHISKERS.md has the measurements.
//   - Free-running (setFreeRunning): for stretches in which the caller has shown that no whisker
//     can touch anything (PhysicsSensorModel's untouchable whisks, whisk_clearance.h), step()
//     moves the base exactly as above — the same DiffDrive, bumper rule, substeps and time — but
//     runs no collision and no dWorldStep, which are 90 % of a step's cost. A free whisker's
//     motion depends only on how its base moves: it rings when the drive command changes (up
//     to 5.2 mrad at the base when a pi/24 rad/s whisk reverses) and settles, to within 3e-14
//     rad, in kFreeResponseTime. So baseAngles() replay ODE's own response to each change,
//     recorded once per distinct (previous command, new command) on a probe robot of the same
//     build standing in an empty world, and hold its settled value after kFreeResponseTime.
//     Against ODE through a body whisk at other poses the replay is within 2e-13 rad (2e-9 of a
//     Hall code), so the sensed codes are the same. It is exact only when the whiskers had
//     settled when free-running began and each change comes at least kFreeResponseTime after
//     the one before (so with max_wheel_acceleration, only if a ramp and its ringing end within
//     that time); other cases replay all the same and are counted (inexactFreeChanges()).
//     segmentEnds() give the straight whisker (the ringing moves the tip by <= 1.4 mm).
//   - Time slices (trackFreeResponses, docs/WHISKERS.md "Time slices"): the free responses then
//     also hold every capsule's full state, so a whisker may leave ODE and come back at any step:
//     it comes back in the state ODE would have given it, and leaves again only once it is on
//     its free trajectory (onFreeTrajectory: after a release, when its own ringing has died out).
//     A change of command before the response settled sends the free whiskers back to ODE, so
//     nothing is replayed inexactly. PhysicsSensorModel keeps each whisker in ODE only in the
//     slices of a whisk in which it can touch something.
//
// Ownership: the robot owns every ODE handle it creates (unique_ptr with deleters) and holds a
// reference to the World, which must outlive it. Non-copyable.
// Thread-safety: none, and not even across instances: this ODE build keeps its collision scratch
// global, so every World and WhiskeredRobot must be used from one thread at a time.
// Allocation: construction and place() allocate; step() does not after its first few calls
// (the contact buffer is sized at construction, ODE reuses its contact-joint arena and step
// memory once they have grown to the largest contact set seen), except that a free-running
// step() at a change of command not seen before records its free response (the probe robot,
// once, and about 230 kB per change with four whiskers; with trackFreeResponses the states too,
// about 6 MB per change).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "crunch/robot/mobile_base.h"
#include "crunch/core/geometry.h"
#include "crunch/core/result.h"
#include "crunch/robot/shapelet.h"
#include "crunch/robot/whisker_beam.h"
#include "crunch_sim/diff_drive.h"
#include "crunch_sim/world.h"

// ODE handle types (see world.h); <ode/ode.h> stays in the .cc.
struct dxWorld;
struct dxBody;
struct dxJoint;
struct dxJointGroup;

namespace crunch::sim {

// A base's two deflection angles: what the follicle's magnet does and the Hall sensor sees.
struct BaseAngles {
  double horizontal = 0.0;  // in-plane bending, about the vertical, CCW from above, radians
  double vertical = 0.0;    // out of plane, positive up, radians
};

// Ground truth about one whisker's contact (for labels, tests and calibration).
struct WhiskerContact {
  double r = 0.0;   // distance from the base along the (bent) whisker to the contact, metres
  Vec2 point;       // contact point in the arena plane
  Vec2 normal;      // unit, in the plane, out of the surface toward the whisker
  double depth = 0.0;  // ODE's penetration depth, metres
  int segment = 0;     // which capsule (0 at the base)
};

class WhiskeredRobot final : public MobileBase {
 public:
  struct Options {
    WhiskerBeam beam;
    // Beam elements per whisker (elements + 1 capsules) and how they shorten toward the tip:
    // element j ends at L (1 - (1 - j/elements)^element_grading). 4 elements graded 1.3 put
    // the base angle within 4.4 % of beam theory over 90-140 mm (10 elements: 0.3 %) at a cost
    // the 10x real-time goal allows; the direct solver's cost grows with the cube of its
    // 6 (elements + 1) constraint rows (docs/WHISKERS.md charts speed against accuracy).
    int elements = 4;
    double element_grading = 1.3;
    // One physics step, seconds: one 2 kHz sample period (§2.1), so step() gives one sample.
    double dt = 0.5e-3;
    int substeps = 1;  // ODE steps per step() at least; each is dt / substeps
    // Adaptive refinement: a step in which some capsule turns faster than
    // max_rotation_per_substep per substep is split further, up to max_substeps. Only whiskers
    // flicking free of a deep bend or whipped by a full-speed spin need it.
    int max_substeps = 8;
    double max_rotation_per_substep = 0.03;  // radians
    double z = 0.1;                   // whisker plane height, metres (as RaySensorModel)
    double friction = 0.3;            // Coulomb mu whisker-surface (plastic on paint/wood)
    int max_contacts_per_segment = 2;
    // Largest speed ODE may use to push a penetrating contact apart, m/s: keeps a deep contact
    // from launching the light tip segments.
    double max_correcting_velocity = 0.2;
    // Whisker-surface contact as a spring-damper, N/m and N s/m: stiff against the whisker
    // (0.3 um of indentation under a 5 mm tip push) yet soft enough to keep ODE's LCP regular.
    double contact_stiffness = 1000.0;
    double contact_damping = 1.0;
    double wheel_base = 0.258;      // Create wheel separation, metres (OI specification)
    double max_wheel_speed = 0.5;   // Create, m/s per wheel (OI specification)
    // Largest change of a wheel's speed, m/s^2; 0: the wheels take a commanded speed at once
    // (the default, with which the signal models were trained: in-place whisks at pi/24 rad/s
    // barely accelerate). A roaming robot needs a limit: stepping the turn rate to pi/4 rad/s
    // at once swings every whisker 12-20 mrad, past the contact detector's onset threshold
    // (docs/ROBOT.md). The Create's own limit is not published; crunch-virtual-robot uses
    // 0.5 m/s^2 (an assumption).
    double max_wheel_acceleration = 0.0;

    Status validate() const;
  };

  // Builds the robot at pose (0, 0, 0) with its whiskers at rest. Error for invalid options, a
  // non-finite mount, or a mount whose length differs from options.beam.external_length.
  static Result<std::unique_ptr<WhiskeredRobot>> create(const World& world,
                                                        std::vector<WhiskerMount> mounts,
                                                        const Options& options);
  ~WhiskeredRobot() override;
  WhiskeredRobot(const WhiskeredRobot&) = delete;
  WhiskeredRobot& operator=(const WhiskeredRobot&) = delete;

  // Teleports the base to `pose`, puts every whisker straight at rest, forgets contacts and
  // stops the base (drive(0, 0)). Time keeps running (now() is monotonic). Asserts a finite pose.
  void place(const Pose2& pose);

  // Advances one Options::dt (in Options::substeps ODE steps). Does not allocate after warm-up.
  void step();
  // Steps until `seconds` more have passed (rounded to whole steps); returns the steps taken.
  int run(double seconds);

  // Free-running on or off (see the top of this file). Only sound while no whisker can touch a
  // wall or leg: the caller guarantees it (nothing here checks). Turning it on drops the current
  // contacts and freezes the ODE whisker state; while on, step() integrates the base only
  // (Options::substeps substeps, the same pose and time as with ODE: a free whisker never needs
  // the adaptive refinement), baseAngles() replay the free whiskers' response to the commands
  // (the first change of command may run the probe robot for kFreeResponseTime of simulated time,
  // allocating), contact() is nullopt and segmentEnds() give the straight whisker. Turning it off
  // puts every whisker straight on the base at the current pose, moving rigidly with it (the
  // base's current v and omega), and the next step() is an ODE step again. Calling it with the
  // current state does nothing. place() works in both states and keeps it.
  void setFreeRunning(bool on) { setFreeWhiskers(on ? allWhiskers() : 0u); }
  // True when every whisker is free-running.
  bool freeRunning() const { return free_mask_ != 0 && free_mask_ == allWhiskers(); }
  // Free-running whisker by whisker (bit w: whisker w), for stretches in which the caller has
  // shown that those whiskers cannot touch a wall or leg while the others may. Each whisker is
  // its own ODE island (Whisker::follicle), so leaving a free one out of dWorldStep (its bodies,
  // follicle, joints and capsule geoms disabled) leaves the others' solution as it was: the same
  // island, built in the same order. A free whisker's baseAngles() replay its free response as
  // above and it has no contacts; the whiskers left in ODE step as before, with the adaptive
  // refinement judged on them alone (a free whisker rings far below its threshold). Turning a
  // whisker back to ODE puts it straight on the base at the current pose, moving rigidly with
  // it. setFreeRunning(on) is setFreeWhiskers(all or none). Bits beyond the whiskers are ignored.
  void setFreeWhiskers(std::uint32_t mask);
  std::uint32_t freeWhiskers() const { return free_mask_; }
  // Tracking the free trajectory (time-sliced ODE, docs/WHISKERS.md "Time slices"): while on,
  // every change of command looks up (recording it the first time, as above) the free response,
  // even when no whisker is free-running, so that a whisker may leave ODE and come back at any
  // step. Each recorded step then holds every capsule's full state (position, orientation,
  // linear and angular velocity) relative to the base, besides the base angles; a whisker that
  // comes back to ODE is put in that state at the current pose rather than straight, so it goes
  // on as if it had been in ODE all along (to the replay's 2e-13 rad), and onFreeTrajectory()
  // tells when a whisker in ODE is back on that path and may leave again. A command that changes
  // before the tracked response has settled (kFreeResponseTime) sends the free whiskers back to
  // ODE in their tracked state first, since the new response is recorded from the settled
  // previous command and would not describe them: with tracking on, a free whisker is never
  // replayed inexactly. Off by default (the roaming robot changes command too often for
  // recording to pay).
  void trackFreeResponses(bool on) { track_free_ = on; }
  // True when whisker w, in ODE, touches nothing and every capsule's state is within
  // kFreeTrajectoryTolerance of the free response being tracked: freeing it then replays what
  // ODE would have computed. False while it is free-running, or when no free response with
  // states is tracked (tracking off, or no change of command since place()).
  bool onFreeTrajectory(int w) const;
  // How close a whisker in ODE must be to its free trajectory to leave ODE: capsule positions
  // (metres) and orientations (quaternion components, times the capsule length) within 1e-12 m,
  // velocities within 1e-12 m over a step (linear: 2e-9 m/s; angular times the capsule length).
  // The base angle it reads then stays within ~1e-10 rad of ODE's (measured 8.7e-11 rad through
  // commands changing every 0.3-2.5 s: 1e-6 of a Hall code); at 1e-10 m it was 7.3e-9 rad. A
  // released whisker's ringing falls 70- to 90-fold every 0.25 s, so each factor of 100 here
  // keeps it in ODE about 0.25 s longer.
  static constexpr double kFreeTrajectoryTolerance = 1e-12;
  // Every whisker's bit.
  std::uint32_t allWhiskers() const {
    return whiskers_.size() >= 32 ? ~0u : (1u << whiskers_.size()) - 1u;
  }
  // Steps taken with every whisker free-running.
  long long freeSteps() const { return free_steps_; }
  // Whisker-steps taken free-running while another whisker ran in ODE.
  long long partlyFreeWhiskerSteps() const { return partly_free_whisker_steps_; }
  // Whisker-steps taken in ODE (each step counts the whiskers it simulated there).
  long long odeWhiskerSteps() const { return ode_whisker_steps_; }
  // Changes of command while free-running, and starts of free-running, that came within
  // kFreeResponseTime of the change before (the whiskers still rang): replayed as if settled.
  long long inexactFreeChanges() const { return inexact_free_changes_; }
  // Distinct changes of command whose free response has been recorded on the probe robot.
  int recordedFreeResponses() const { return static_cast<int>(free_responses_.size()); }
  // How long a free whisker rings after a change of command before it is taken as settled,
  // seconds (docs/WHISKERS.md, "Skipping untouchable whisks": 3e-14 rad left after 1.5 s).
  static constexpr double kFreeResponseTime = 1.8;

  // The follicle's deflection of whisker w, from the direction of its first capsule relative to
  // its rest direction on the base. 0 <= w < whiskerCount().
  BaseAngles baseAngles(int w) const;
  // The contact of whisker w after the last step, if it touches anything: the one nearest the
  // base (it carries the most moment per unit force, and a shaft contact shadows any contact
  // beyond it). nullopt when free.
  std::optional<WhiskerContact> contact(int w) const;
  // Contact points on whisker w after the last step (ODE contacts, up to
  // max_contacts_per_segment per capsule).
  int contactCount(int w) const;

  // MobileBase: the wheels are a DiffDrive (diff_drive.h): both wheels scaled by one factor to
  // +-max_wheel_speed (the curvature is kept), ramped at max_wheel_acceleration if set;
  // non-finite input stops the base and is an Error.
  Status drive(double v, double omega) override;
  // The exact pose (zero odometry noise, §2.8); theta is integrated, not wrapped.
  Pose2 odometry() const override { return pose_; }
  // The bumper is pressed (see the top of this file).
  bool bumped() const override { return bumper_ != Bumper::kReleased; }
  Bumper bumper() const override { return bumper_; }
  double now() const override { return time_; }

  // Wheel speeds (left, right) in effect after clamping, m/s.
  std::pair<double, double> wheelSpeeds() const { return {wheels_.left(), wheels_.right()}; }
  // Substeps in which the bumper rule refused the base's translation.
  long long refusedSteps() const { return refused_steps_; }
  // Steps split into more than Options::substeps by the adaptive refinement.
  long long refinedSteps() const { return refined_steps_; }
  // Contacts ODE found beyond the buffer sized at construction (left out of the step; expected
  // to stay 0: the buffer holds every capsule touching two surfaces at once).
  long long droppedContacts() const { return dropped_contacts_; }

  // Inspection, for tests and pictures.
  int whiskerCount() const { return static_cast<int>(whiskers_.size()); }
  int segmentCount() const { return options_.elements + 1; }
  const std::vector<WhiskerMount>& mounts() const { return mounts_; }
  const Options& options() const { return options_; }
  // The whisker base (follicle) of whisker w in the world, at the whisker plane height.
  Eigen::Vector3d basePoint(int w) const;
  // Both ends of capsule i (0 at the base) of whisker w along its axis, in the world.
  std::pair<Eigen::Vector3d, Eigen::Vector3d> segmentEnds(int w, int i) const;
  // Distance along the rest whisker from the base to the start of capsule i.
  double segmentStart(int i) const { return seg_start_[static_cast<size_t>(i)]; }
  double segmentLength(int i) const { return seg_len_[static_cast<size_t>(i)]; }
  double segmentRadius(int i) const { return seg_radius_[static_cast<size_t>(i)]; }
  // Lumped stiffness of shaft joint j (1 <= j <= elements; j = 0 is the follicle), N m/rad.
  double jointStiffness(int j) const { return joint_k_[static_cast<size_t>(j)]; }

 private:
  struct WorldDeleter {
    void operator()(dxWorld* w) const;
  };
  struct BodyDeleter {
    void operator()(dxBody* b) const;
  };
  struct JointDeleter {
    void operator()(dxJoint* j) const;
  };
  struct JointGroupDeleter {
    void operator()(dxJointGroup* g) const;
  };
  using WorldPtr = std::unique_ptr<dxWorld, WorldDeleter>;
  using BodyPtr = std::unique_ptr<dxBody, BodyDeleter>;
  using JointPtr = std::unique_ptr<dxJoint, JointDeleter>;
  using JointGroupPtr = std::unique_ptr<dxJointGroup, JointGroupDeleter>;
  using SpacePtr = std::unique_ptr<dxSpace, detail::SpaceDeleter>;
  using GeomPtr = std::unique_ptr<dxGeom, detail::GeomDeleter>;

  struct Whisker {
    // The base's part holding this whisker: kinematic, moved with the base. One per whisker, so
    // each whisker is its own ODE island and its own small LCP (one shared body would join all
    // whiskers into one system, and the direct solver's cost grows with the cube of its size).
    BodyPtr follicle;
    std::vector<BodyPtr> bodies;  // capsules, base first
    std::vector<GeomPtr> geoms;   // one capsule geom per body
    std::vector<JointPtr> joints;  // joints[0] is the follicle (base body - capsule 0)
  };
  struct ContactRecord {
    int whisker = 0;
    int segment = 0;
    double pos[3] = {0, 0, 0};
    double normal[3] = {0, 0, 0};  // as ODE gives it for the contact joint
    double depth = 0.0;
  };

  WhiskeredRobot(const World& world, std::vector<WhiskerMount> mounts, const Options& options);
  void build();
  // A drive() command, as given (the key of a recorded free response).
  struct Command {
    double v = 0.0, omega = 0.0;
    bool operator==(const Command&) const = default;
  };
  // ODE's base angles of every free whisker over the kFreeResponseTime after `from` -> `to`.
  struct FreeResponse {
    Command from, to;
    std::vector<BaseAngles> angles;  // step-major: angles[i * whiskers + w], i = 0 the first step
    // With trackFreeResponses on: step-major states[((i * whiskers + w) * capsules + c) *
    // kBodyState + k], each capsule's position, quaternion, linear and angular velocity in the
    // base's frame after step i (bodyState()). Empty otherwise.
    std::vector<double> states;
  };
  static constexpr int kBodyState = 13;
  // Capsule c of whisker w's state in the frame of the base at pose_ (3 position, 4 quaternion,
  // 3 linear and 3 angular velocity), and back.
  void bodyState(size_t w, size_t c, double* out) const;
  void setBodyState(size_t w, size_t c, const double* in);
  // The tracked free state of whisker w after the last step, or null (no free response tracked).
  const double* freeState(size_t w) const;

  // Puts the whiskers of `mask` straight at rest on the base (see place()); every whisker's
  // contacts are forgotten when mask is all of them.
  void resetWhiskers(std::uint32_t mask);
  void clearContacts();
  // Enables or disables whisker w's ODE bodies, joints and capsule geoms.
  void enableInOde(size_t w, bool on);
  BaseAngles odeBaseAngles(int w) const;
  // The response to from -> to, recorded on the probe robot the first time it is asked for.
  const FreeResponse& freeResponse(const Command& from, const Command& to);
  void substep(double h);
  int substepsNeeded() const;
  void moveBase(double h);
  void setBaseBodies(double v, double omega, double h);
  void collide();
  static void nearCallback(void* data, dxGeom* o1, dxGeom* o2);
  void onNear(dxGeom* o1, dxGeom* o2);
  double clearance(const Pose2& p) const;
  // The front bumper's switches at pose p (see the top of this file).
  Bumper frontBumper(const Pose2& p) const;
  // How far beyond the body's rim the bumper still feels a wall or leg, metres: the body stops
  // within one substep's travel (0.5 m/s x 0.5 ms = 0.25 mm) of touching.
  static constexpr double kBumperReach = 0.0005;

  // Declaration order is destruction order reversed: joints and geoms before their bodies,
  // group and space before the world, ODE closed last.
  detail::OdeLibraryRef ode_;
  const World& world_;
  std::vector<WhiskerMount> mounts_;
  Options options_;

  WorldPtr dworld_;
  SpacePtr space_;  // the whisker capsules; does not own them (geoms in Whisker do)
  JointGroupPtr contact_group_;
  std::vector<Whisker> whiskers_;

  // Rest geometry of the chain, shared by all whiskers.
  std::vector<double> seg_start_, seg_len_, seg_radius_, seg_mass_;
  std::vector<double> joint_s_, joint_k_, joint_kd_;  // [0] follicle, [j] shaft joint j

  std::vector<ContactRecord> contacts_;  // this step's contacts, capacity fixed at construction
  std::vector<int> contact_count_;       // per whisker
  std::vector<dxGeom*> world_geoms_;     // the World's walls and legs
  std::vector<double> world_aabbs_;      // 6 per world geom (ODE AABB order)
  long long dropped_contacts_ = 0;

  Pose2 pose_;
  DiffDrive wheels_;  // the commanded and actual wheel speeds
  double time_ = 0.0;
  Bumper bumper_ = Bumper::kReleased;
  long long refused_steps_ = 0;
  long long refined_steps_ = 0;
  // Free-running (see the top of this file).
  std::uint32_t free_mask_ = 0;  // bit w: whisker w free-running
  long long free_steps_ = 0;
  long long partly_free_whisker_steps_ = 0;
  long long ode_whisker_steps_ = 0;
  long long inexact_free_changes_ = 0;
  Command command_;             // the last drive() command (zero after place() or a bad one)
  Command stepped_;             // the command the last step ran with
  long since_change_ = 0;       // steps since stepped_ changed or place(), up to response_steps_
  long response_steps_ = 0;     // kFreeResponseTime in steps
  std::deque<FreeResponse> free_responses_;  // a deque: replay_ stays valid as it grows
  const FreeResponse* replay_ = nullptr;  // being replayed, or null: hold free_angles_
  bool track_free_ = false;               // trackFreeResponses()
  std::vector<BaseAngles> free_angles_;   // per whisker: baseAngles() while free-running
  // The probe: this robot's twin in an empty world, where free responses are recorded. Declared
  // world first, so that the robot goes first.
  std::unique_ptr<World> probe_world_;
  std::unique_ptr<WhiskeredRobot> probe_;
  std::optional<Command> probe_settled_;  // the command the probe has run long enough to settle
  double last_h_ = 0.0;  // substep the joint springs were set for
  double contact_erp_ = 0.2, contact_cfm_ = 0.0;  // for last_h_
};

}  // namespace crunch::sim
