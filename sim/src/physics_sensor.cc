#include "crunch_sim/physics_sensor.h"

#include <algorithm>
#include <cmath>
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
  return reports ? std::sqrt(sum_phi2 / reports) : 0.0;
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
    const ContactReport& rep = rig_->chain().evidence().entry(static_cast<int>(w)).report;
    const WhiskerTruth& t = truth[w];
    Score& sc = scores_[w];
    sc = Score{};
    sc.scored = t.touched;
    if (t.touched) {
      sc.err_r = rep.r - t.r_at_peak;
      sc.err_phi = wrapPeriod(rep.phi - (t.surface_tangent - t.pose_at_peak.theta), kPi);
    }
  }
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
  robot.place(pose);
  BodyWhisk::Options wopt;
  wopt.whisker_bearings.clear();
  for (const WhiskerMount& m : mounts_) wopt.whisker_bearings.push_back(m.bearing);
  BodyWhisk whisk(robot, wopt);
  // Untouchable whisks: the whole whisk and the wait after it without ODE (see the header).
  const double checked = wopt.whisk_amplitude + kSkipHeadingSlack;  // each way from theta0
  const bool skip = options_.skip_untouchable &&
                    inPlaceWhiskClear(world_, mounts_, pose, -checked, checked,
                                      options_.skip_margin);
  if (skip) ++skipped_whisks_;
  robot.setFreeRunning(skip);
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
    if (robot.freeRunning() && std::abs(robot.odometry().theta - pose.theta) > checked) {
      robot.setFreeRunning(false);  // outside what was checked: ODE again (never seen)
    }
    if (whisking) {
      (void)whisk.update(rig_->contactMask());
      if (whisk.done()) {
        whisking = false;
        settle_until = robot.now() + options_.max_settle_s;
      }
    } else if (!rig_->pipeline().inEpisode() || robot.now() >= settle_until) {
      break;
    }
  }
  (void)robot.stop();
  robot.setFreeRunning(false);
  {
    const std::uint32_t before = chain.reportedMask();
    if (rig_->finish() != nullptr) score(chain.reportedMask() & ~before);
  }
  rig_->resetTruth();
  errors_.simulated_s += robot.now() - t0;

  const std::size_t first = out.size();
  chain.endWhisk(out, free_);
  errors_.episodes = static_cast<int>(chain.counts().episodes);
  errors_.no_radial = chain.evidence().counts().no_radial;
  errors_.no_orientation = chain.evidence().counts().no_orientation;
  for (std::size_t k = first; k < out.size(); ++k) {
    const Score& sc = scores_[static_cast<std::size_t>(out[k].whisker)];
    if (sc.scored) {
      ++errors_.reports;
      errors_.sum_r += sc.err_r;
      errors_.sum_r2 += sc.err_r * sc.err_r;
      errors_.sum_phi += sc.err_phi;
      errors_.sum_phi2 += sc.err_phi * sc.err_phi;
    } else {
      ++errors_.unscored;
    }
  }
}

}  // namespace crunch::sim
