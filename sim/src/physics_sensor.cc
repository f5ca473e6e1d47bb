#include "crunch_sim/physics_sensor.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "crunch/behaviour/body_whisk.h"
#include "crunch_sim/training.h"

namespace crunch::sim {

namespace {

// An orientation modulo pi, as a value in [0, pi) (ContactReport::phi's convention).
double halfTurn(double a) {
  double w = wrapPeriod(a, kPi);
  if (w < 0.0) w += kPi;
  if (w >= kPi) w -= kPi;
  return w;
}

constexpr int kFreeEvery = 120;  // samples between negative-evidence rays: ~0.45 deg of whisk
constexpr int kFreeGuard = 4;    // records either side (+-0.24 s) that must show no contact
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
  auto rig = WhiskerRig::create(world, mounts, *start, options.rig);
  if (!rig) return rig.error();
  if (auto s = rig.value()->pipeline().setModels(models); !s) return s.error();
  auto model = std::unique_ptr<PhysicsSensorModel>(
      new PhysicsSensorModel(std::move(rig).value(), std::move(mounts), options));
  model->clear_pose_ = *start;
  return model;
}

PhysicsSensorModel::PhysicsSensorModel(std::unique_ptr<WhiskerRig> rig,
                                       std::vector<WhiskerMount> mounts, const Options& options)
    : rig_(std::move(rig)), mounts_(std::move(mounts)), options_(options), best_(mounts_.size()) {}

void PhysicsSensorModel::takeEpisode(const signal::ContactEpisode& ep) {
  ++errors_.episodes;
  const auto& truth = rig_->episodeTruth();
  const Pose2 onset_pose = rig_->poseAtSample(ep.start_sample);
  for (std::size_t w = 0; w < mounts_.size(); ++w) {
    const signal::WhiskerContact& c = ep.whiskers[w];
    if (!c.touched) continue;
    Best& b = best_[w];
    if (b.have) continue;  // the first pass (docs/TRAINING.md: the models' f1)
    b = Best{};
    b.have = true;
    b.f1 = c.f1;
    const Pose2 peak_pose =
        rig_->poseAtSample(ep.start_sample + static_cast<std::uint64_t>(std::max<std::int64_t>(
                                                 c.peak_sample, 0)));
    b.report.whisker = static_cast<int>(w);
    b.report.robot = peak_pose;
    b.has_r = c.has_r;
    b.report.r = std::clamp(c.r, 0.0, mounts_[w].length);
    b.has_phi = ep.has_orientation;
    // The template's angle is relative to the heading at the first contact (the window's
    // alignment, §2.5); the report is relative to the heading at this whisker's peak.
    b.report.phi = halfTurn(ep.orientation.angle + onset_pose.theta - peak_pose.theta);
    const WhiskerTruth& t = truth[w];
    b.scored = t.touched;
    if (t.touched) {
      b.err_r = b.report.r - t.r_at_peak;
      b.err_phi = wrapPeriod(b.report.phi - (t.surface_tangent - t.pose_at_peak.theta), kPi);
    }
  }
}

void PhysicsSensorModel::sense(const Pose2& pose, Rng& /*rng*/,
                               std::vector<ContactReport>& out) {
  for (Best& b : best_) b = Best{};
  samples_.clear();
  free_.clear();
  ++errors_.whisks;

  WhiskeredRobot& robot = rig_->robot();
  const double t0 = robot.now();
  // A whisk that ended pressed against something leaves a detector in contact, and it cannot
  // open the next pose's episode until it releases: rest clear of everything first (bounded).
  if (rig_->contactMask() != 0 || rig_->pipeline().inEpisode()) {
    robot.place(clear_pose_);
    for (int i = 0; i < kMaxRestSteps && (rig_->contactMask() != 0); ++i) rig_->step();
    if (rig_->pipeline().inEpisode()) (void)rig_->finish();
    rig_->resetTruth();
  }
  robot.place(pose);
  BodyWhisk::Options wopt;
  wopt.whisker_bearings.clear();
  for (const WhiskerMount& m : mounts_) wopt.whisker_bearings.push_back(m.bearing);
  BodyWhisk whisk(robot, wopt);
  (void)whisk.startInPlace(+1);  // the ray model's sweep: toward +A first

  // The whisk, then until the last episode ends (bounded).
  const long max_steps = static_cast<long>(
      (4.0 * wopt.whisk_amplitude / wopt.whisk_rate + 2.0 + options_.max_settle_s) /
      options_.rig.robot.dt);
  long n = 0;
  bool whisking = true;
  double settle_until = 0.0;
  for (; n < max_steps; ++n) {
    if (const signal::ContactEpisode* ep = rig_->step()) takeEpisode(*ep);
    const std::uint32_t mask = rig_->contactMask();
    if (whisking) {
      (void)whisk.update(mask);
      if (n % kFreeEvery == 0) samples_.push_back({robot.odometry(), 0});
      if (!samples_.empty()) samples_.back().mask |= mask;
      if (whisk.done()) {
        whisking = false;
        settle_until = robot.now() + options_.max_settle_s;
      }
    } else if (!rig_->pipeline().inEpisode() || robot.now() >= settle_until) {
      break;
    }
  }
  (void)robot.stop();
  if (rig_->pipeline().inEpisode()) {
    if (const signal::ContactEpisode* ep = rig_->finish()) takeEpisode(*ep);
  }
  rig_->resetTruth();
  errors_.simulated_s += robot.now() - t0;

  for (const Best& b : best_) {
    if (!b.have) continue;
    if (!b.has_r) {
      ++errors_.no_radial;
      continue;
    }
    if (!b.has_phi) {
      ++errors_.no_orientation;
      continue;
    }
    out.push_back(b.report);
    if (b.scored) {
      ++errors_.reports;
      errors_.sum_r += b.err_r;
      errors_.sum_r2 += b.err_r * b.err_r;
      errors_.sum_phi += b.err_phi;
      errors_.sum_phi2 += b.err_phi * b.err_phi;
    } else {
      ++errors_.unscored;
    }
  }

  // Negative evidence: whisk samples far (in time) from any detected contact of the whisker.
  const int ns = static_cast<int>(samples_.size());
  for (int i = 0; i < ns; ++i) {
    const Pose2& p = samples_[static_cast<std::size_t>(i)].pose;
    for (std::size_t w = 0; w < mounts_.size(); ++w) {
      bool clear = true;
      for (int j = std::max(0, i - kFreeGuard); j <= std::min(ns - 1, i + kFreeGuard); ++j) {
        if (samples_[static_cast<std::size_t>(j)].mask & (1u << w)) clear = false;
      }
      if (!clear) continue;
      const WhiskerMount& m = mounts_[w];
      const Vec2 base = p.toWorld(m.base);
      const double dir = p.theta + m.bearing;
      free_.push_back({base, base + m.length * Vec2{std::cos(dir), std::sin(dir)}});
    }
  }
}

}  // namespace crunch::sim
