#include "crunch_sim/physics_sensor.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <utility>

#include "crunch/behaviour/body_whisk.h"
#include "crunch_sim/training.h"
#include "crunch_sim/whisk_clearance.h"

namespace crunch::sim {

namespace {

constexpr int kMaxRestSteps = 2000;  // 1 s: a released detector needs 20 ms below threshold

bool clearOfEverything(const World& world, const std::vector<WhiskerMount>& mounts,
                       const Pose2& pose, double z) {
  if (world.bodyCollides(pose)) return false;
  for (const WhiskerMount& m : mounts) {
    // The whisker and a margin around it (it bends a little when the rig powers up still).
    for (const double spread : {-0.1, 0.0, 0.1}) {
      if (world.castRay(pose.toWorld(m.base), pose.theta + m.bearing + spread, m.length + 0.02,
                        z)) {
        return false;
      }
    }
  }
  return true;
}

// Where the robot comes from to reach `pose`: the pose itself if its straight whiskers are clear
// of everything there; else backed off along its heading, in 5 mm steps up to kMaxApproach, to
// the first place where they are (and the body is). The pose itself if there is none.
constexpr double kMaxApproach = 0.25;   // metres
constexpr double kApproachSpeed = 0.05;  // m/s: slower than roaming, as the robot closes in

Pose2 approachStart(const World& world, const std::vector<WhiskerMount>& mounts,
                    const Pose2& pose, double z) {
  const Vec2 back{-std::cos(pose.theta), -std::sin(pose.theta)};
  for (double d = 0.0; d <= kMaxApproach + 1e-9; d += 0.005) {
    const Pose2 q{pose.x + d * back.x(), pose.y + d * back.y(), pose.theta};
    if (world.bodyCollides(q)) break;
    bool clear = true;
    for (const WhiskerMount& m : mounts) {
      if (world.castRay(q.toWorld(m.base), q.theta + m.bearing, m.length + 0.003, z)) clear = false;
    }
    if (clear) return q;
  }
  return pose;
}

}  // namespace

PhysicsSensorModel::Options physicsSensorOptions(std::uint64_t seed) {
  PhysicsSensorModel::Options o;
  o.rig = physicsRigOptions(seed);  // exactly what the models were trained with
  return o;
}

double ReportErrors::sigmaR() const {
  return reports ? std::sqrt(sum_r2 / reports) : 0.0;
}
double ReportErrors::sigmaPhi() const {
  return oriented ? std::sqrt(sum_phi2 / oriented) : 0.0;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double at = q * static_cast<double>(v.size() - 1);
  const auto i = static_cast<std::size_t>(at);
  if (i + 1 >= v.size()) return v.back();
  return v[i] + (at - static_cast<double>(i)) * (v[i + 1] - v[i]);
}

Status PhysicsSensorModel::Options::validate() const {
  if (auto s = rig.validate(); !s) return s;
  if (!(std::isfinite(max_settle_s) && max_settle_s > 0.0)) {
    return Error{"physics sensor: max_settle_s must be positive"};
  }
  if (!(std::isfinite(skip_margin) && skip_margin >= kMinSkipMargin && skip_margin <= 0.1)) {
    return Error{"physics sensor: skip_margin must be in [" + std::to_string(kMinSkipMargin) +
                 ", 0.1] m (got " + std::to_string(skip_margin) + ")"};
  }
  return okStatus();
}

Result<std::unique_ptr<PhysicsSensorModel>> PhysicsSensorModel::create(
    const World& world, std::vector<WhiskerMount> mounts, const signal::SignalModels& models,
    const std::vector<Pose2>& clear_candidates, const Options& options) {
  if (auto s = options.validate(); !s) return s.error();
  if (auto s = signal::validateModels(models); !s) return s.error();
  const Pose2* start = nullptr;
  for (const Pose2& p : clear_candidates) {
    if (clearOfEverything(world, mounts, p, options.rig.robot.z)) {
      start = &p;
      break;
    }
  }
  if (start == nullptr) {
    return Error{"physics sensor: no pose of the scene leaves every whisker clear of walls and "
                 "legs, so the whisker sensors cannot calibrate at rest; add a clear pose"};
  }
  // The pipeline the models were trained with (carried in the models file), whatever the rig
  // options say: the radial lines and templates are valid only for those settings.
  WhiskerRig::Options rig_options = options.rig;
  rig_options.pipeline = models.pipeline;
  auto rig = WhiskerRig::create(world, mounts, *start, rig_options);
  if (!rig) return rig.error();
  if (auto s = rig.value()->chain().setModels(models); !s) return s.error();
  auto model = std::unique_ptr<PhysicsSensorModel>(
      new PhysicsSensorModel(world, std::move(rig).value(), std::move(mounts), options));
  model->clear_pose_ = *start;
  for (const OrientedRect& f : world.footprints()) {
    if (std::max(f.size_x, f.size_y) <= 0.1) model->legs_.push_back(f);
  }
  return model;
}

PhysicsSensorModel::PhysicsSensorModel(const World& world, std::unique_ptr<WhiskerRig> rig,
                                       std::vector<WhiskerMount> mounts, const Options& options)
    : world_(world),
      rig_(std::move(rig)),
      mounts_(std::move(mounts)),
      options_(options),
      scores_(mounts_.size()) {}

void PhysicsSensorModel::score(std::uint32_t set) {
  const auto& truth = rig_->episodeTruth();
  for (std::size_t w = 0; w < mounts_.size(); ++w) {
    if (!(set & (1u << w))) continue;
    Score& sc = scores_[w];
    sc = Score{};
    sc.scored = truth[w].touched;
    sc.truth = truth[w];
  }
}

void PhysicsSensorModel::tally(const ContactReport& rep) {
  const Score& sc = scores_[static_cast<std::size_t>(rep.whisker)];
  if (!sc.scored) {
    ++errors_.unscored;
    return;
  }
  const WhiskerTruth& t = sc.truth;
  const WhiskerMount& m = mounts_[static_cast<std::size_t>(rep.whisker)];
  const Vec2 at = m.pointAt(rep.robot, rep.r);
  const bool on_leg = std::any_of(legs_.begin(), legs_.end(), [&](const OrientedRect& f) {
    return closestOnPerimeter(f, t.point_at_touch).distance < 0.005;
  });
  // The truth a located report measured: the whisker's true contact point nearest to it on the
  // contact's track (WhiskerTruth::track). A pressed tip slides along a face or round a leg
  // before and during the sweep, and the ramp locates where the contact was while it was
  // measured, not the first touch; every point of the track was touched.
  double err_track = std::numeric_limits<double>::infinity();
  for (const Vec2& p : t.track) err_track = std::min(err_track, (at - p).norm());
  // A leg's contact is a point: the error is the distance to the nearest track point (at most
  // kTrackStep / 2 more than to the path through them). A wall's is a face: the error is the
  // distance to the face.
  const Vec2 along{std::cos(t.tangent_at_touch), std::sin(t.tangent_at_touch)};
  const Vec2 off = at - t.point_at_touch;
  const double err_pos = on_leg ? err_track : std::abs(off.x() * along.y() - off.y() * along.x());
  // r against the first touch: the ramp's intercept is the heading at which the straight whisker
  // met the point (docs/SIGNAL.md).
  const double err_r = rep.r - t.r_at_touch;
  ++errors_.reports;
  errors_.sum_r += err_r;
  errors_.sum_r2 += err_r * err_r;
  if (rep.oriented) {
    const double err_phi = wrapPeriod(rep.phi - (t.tangent_at_touch - rep.robot.theta), kPi);
    ++errors_.oriented;
    errors_.sum_phi += err_phi;
    errors_.sum_phi2 += err_phi * err_phi;
  }
  errors_.position_errors.push_back(err_pos);
  (on_leg ? errors_.leg_position_errors : errors_.wall_position_errors).push_back(err_pos);
  if (on_leg) errors_.leg_first_touch_errors.push_back(off.norm());
  const double tip_from = m.length - rig_->chain().tipZone();
  ++errors_.tip_confusion[t.r_at_touch >= tip_from ? 0 : 1][rep.r < tip_from ? 1 : 0];
}

void PhysicsSensorModel::sense(const Pose2& pose, Rng& /*rng*/,
                               std::vector<ContactReport>& out) {
  for (Score& sc : scores_) sc = Score{};
  free_.clear();
  ++errors_.whisks;

  session::SensingChain& chain = rig_->chain();
  WhiskeredRobot& robot = rig_->robot();
  const double t0 = robot.now();
  // A whisk that ended pressed against something leaves a detector in contact, and it cannot
  // open the next pose's episode until it releases: rest clear of everything first (bounded).
  if (rig_->contactMask() != 0 || rig_->pipeline().inEpisode()) {
    robot.place(clear_pose_);
    for (int i = 0; i < kMaxRestSteps && (rig_->contactMask() != 0); ++i) (void)rig_->step();
    if (rig_->pipeline().inEpisode()) (void)rig_->finish();
    rig_->resetTruth();
  }
  // The robot arrives at the pose as it would drive there: a teleported straight whisker must
  // not start inside a wall or a leg (it would be "touching" nothing real). A pose whose whiskers
  // are not clear is approached along its heading, the whiskers bending on the way: the whisk
  // then starts pressed, as on the robot (ContactRamp handles both).
  const Pose2 from = approachStart(world_, mounts_, pose, options_.rig.robot.z);
  const bool sliced = options_.skip_untouchable;
  // Time slices (see the top of physics_sensor.h): the robot tracks the free response to every
  // change of command, so that each whisker may leave ODE while it cannot touch anything and come
  // back, in the state ODE would have given it, when it can.
  robot.trackFreeResponses(sliced);
  robot.place(from);  // straight and settled: every whisker may leave ODE exactly here
  const double approach = (pose.position() - from.position()).norm();
  if (approach > 0.0) {
    // The approach: the whiskers that come within skip_margin of a wall or leg anywhere on the
    // straight path stay in ODE, the others run free (exact from the settled state of place()).
    std::uint32_t path_free = 0;
    if (sliced) {
      for (std::size_t w = 0; w < mounts_.size(); ++w) {
        if (straightPathClear(world_, std::span(&mounts_[w], 1), from, approach,
                              options_.skip_margin)) {
          path_free |= 1u << w;
        }
      }
    }
    robot.setFreeWhiskers(path_free);
    (void)robot.drive(kApproachSpeed, 0.0);
    const long max_approach_steps =
        static_cast<long>(2.0 * approach / kApproachSpeed / options_.rig.robot.dt) + 1;
    for (long n = 0; n < max_approach_steps; ++n) {
      if ((robot.odometry().position() - from.position()).norm() >= approach || robot.bumped()) break;
      (void)rig_->step();
    }
    (void)robot.drive(0.0, 0.0);
  }
  BodyWhisk::Options wopt;
  wopt.whisker_bearings.clear();
  for (const WhiskerMount& m : mounts_) wopt.whisker_bearings.push_back(m.bearing);
  BodyWhisk whisk(robot, wopt);
  // Per slice of the whisk's headings, the whiskers that come within skip_margin of a wall or leg
  // somewhere in it, from where the robot stands now (an approach may stop short at a bump).
  const Pose2 at = robot.odometry();
  const double checked = wopt.whisk_amplitude + kSkipHeadingSlack;  // each way from theta0
  const int slices = static_cast<int>(std::ceil(2.0 * checked / kSliceWidth));
  const double slice = 2.0 * checked / slices;
  danger_.assign(static_cast<size_t>(slices), 0u);
  std::uint32_t ever = 0;  // whiskers in danger somewhere in the whisk
  if (sliced) {
    for (int k = 0; k < slices; ++k) {
      for (std::size_t w = 0; w < mounts_.size(); ++w) {
        if (!inPlaceWhiskClear(world_, std::span(&mounts_[w], 1), at, -checked + k * slice,
                               -checked + (k + 1) * slice, options_.skip_margin)) {
          danger_[static_cast<size_t>(k)] |= 1u << w;
        }
      }
      ever |= danger_[static_cast<size_t>(k)];
    }
    if (ever == 0) ++skipped_whisks_;
  }
  // The whiskers that must be in ODE for the next step at heading offset d: those in danger in
  // its slice or either neighbour (a step turns 65 urad, a slice is 8.7 mrad); every whisker
  // outside the checked range (never seen).
  const auto needed = [&](double d) -> std::uint32_t {
    if (!sliced || !(std::abs(d) <= checked)) return robot.allWhiskers();
    const int k = std::clamp(static_cast<int>(std::floor((d + checked) / slice)), 0, slices - 1);
    std::uint32_t m = danger_[static_cast<size_t>(k)];
    if (k > 0) m |= danger_[static_cast<size_t>(k - 1)];
    if (k + 1 < slices) m |= danger_[static_cast<size_t>(k + 1)];
    return m;
  };
  // Out of ODE: a whisker not needed there that is free-running, or in ODE but back on its free
  // trajectory (WhiskeredRobot::onFreeTrajectory: it touched, was released and has stopped
  // ringing, or it rang from an approach). Back into ODE: a free whisker that is needed.
  const auto slice_step = [&] {
    const std::uint32_t need = needed(robot.odometry().theta - at.theta);
    std::uint32_t free = robot.freeWhiskers() & ~need;
    for (int w = 0; w < robot.whiskerCount(); ++w) {
      const std::uint32_t bit = 1u << w;
      if (!(need & bit) && !(free & bit) && robot.onFreeTrajectory(w)) free |= bit;
    }
    robot.setFreeWhiskers(free);
  };
  if (sliced) {
    // Settled straight since place() unless an approach drove: then slice_step() decides.
    if (approach == 0.0) robot.setFreeWhiskers(robot.allWhiskers() & ~needed(0.0));
    slice_step();
  }
  // As the robot's control loop marks it: the whisk's episodes are the ones reported.
  chain.beginWhisk();
  (void)whisk.startInPlace(+1);  // the ray model's sweep: toward +A first

  // The whisk, then until the last episode ends (bounded). Each episode the chain takes is
  // scored against the truth of that episode (the whiskers it gave their first report).
  const long max_steps = static_cast<long>(
      (4.0 * wopt.whisk_amplitude / wopt.whisk_rate + 2.0 + options_.max_settle_s) /
      options_.rig.robot.dt);
  bool whisking = true;
  double settle_until = 0.0;
  for (long n = 0; n < max_steps; ++n) {
    const std::uint32_t before = chain.reportedMask();
    if (rig_->step() != nullptr) score(chain.reportedMask() & ~before);
    if (whisking) {
      (void)whisk.update(rig_->contactMask());
      if (whisk.done()) {
        whisking = false;
        settle_until = robot.now() + options_.max_settle_s;
      }
    } else if (!rig_->pipeline().inEpisode() || robot.now() >= settle_until) {
      break;
    }
    if (sliced) slice_step();
  }
  (void)robot.stop();
  robot.setFreeRunning(false);
  {
    const std::uint32_t before = chain.reportedMask();
    if (rig_->finish() != nullptr) score(chain.reportedMask() & ~before);
  }
  rig_->resetTruth();
  errors_.simulated_s += robot.now() - t0;
  errors_.ode_whisker_steps = robot.odeWhiskerSteps();
  errors_.whisker_steps = robot.odeWhiskerSteps() + robot.partlyFreeWhiskerSteps() +
                          robot.freeSteps() * robot.whiskerCount();

  const std::size_t first = out.size();
  chain.endWhisk(out, free_);
  errors_.episodes = static_cast<int>(chain.counts().episodes);
  errors_.no_radial = chain.evidence().counts().no_radial;
  errors_.no_orientation = chain.evidence().counts().no_orientation;
  errors_.no_ramp = chain.evidence().counts().no_ramp;
  // Scored now, not when each episode ended: a report's class and face are settled at the
  // whisk's end (WhiskEvidence::end).
  for (std::size_t k = first; k < out.size(); ++k) tally(out[k]);
}

}  // namespace crunch::sim
