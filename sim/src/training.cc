#include "crunch_sim/training.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <utility>

#include "crunch/behaviour/body_whisk.h"
#include "crunch/core/rng.h"
#include "crunch/scene/scene.h"

namespace crunch::sim {

namespace {

// The training arenas: 3 x 3 m, the object in the middle, the boundary walls >= 1 m from any
// whisker (the whiskers reach 0.305 m from the robot's centre).
constexpr double kArena = 3.0;
const Vec2 kObject{1.5, 1.5};
// Where each rig powers up and calibrates: clear of everything.
const Pose2 kRadialStart{0.6, 0.6, 0.0};
const Pose2 kWallStart{1.5, 0.6, 0.0};
constexpr double kPoleLength = 0.01;  // the 1 cm interior wall segment (2 cm thick: World)
constexpr double kWallLength = 2.4;   // long enough that no whisker reaches an end

// Seeds of the independent streams, from the one --seed (so changing one protocol's size never
// changes another's data).
std::uint64_t streamSeed(std::uint64_t seed, std::uint64_t stream) {
  Rng r(seed ^ (0x5DEECE66Dull * (stream + 1)));
  return r.next();
}

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

double whiskDuration(const BodyWhisk::Options& w) {
  return 4.0 * w.whisk_amplitude / w.whisk_rate;  // toward A, away 2A, back A
}

// One whisk at `pose` and the episodes it gives, with the truth for whisker `focus` (-1: none).
struct WhiskResult {
  std::vector<signal::ContactEpisode> episodes;  // copies (windows included)
  std::vector<std::array<WhiskerTruth, signal::kWhiskers>> truths;
  std::vector<Pose2> onset_poses;
  std::uint32_t truth_touched = 0;  // whiskers the simulator saw touch during the whisk
  std::array<double, signal::kWhiskers> max_theta{};  // detector theta, max over the whisk
  double start_time = 0.0;
  Pose2 start_pose;
};

class Collector {
 public:
  Collector(const TrainingOptions& options, int total) : options_(options), total_(total) {}

  Result<std::unique_ptr<WhiskerRig>> makeRig(const World& world, const Pose2& start,
                                              std::uint64_t seed) {
    WhiskerRig::Options ropt = options_.rig;
    ropt.seed = seed;
    auto rig = WhiskerRig::create(world, defaultWhiskerArray(), start, ropt);
    if (!rig) return Error{"training rig: " + rig.error().message};
    simulated_ += rig.value()->robot().now();
    return rig;
  }

  WhiskResult whisk(WhiskerRig& rig, const Pose2& pose) {
    WhiskResult out;
    WhiskeredRobot& robot = rig.robot();
    robot.place(pose);
    rig.resetTruth();
    BodyWhisk::Options wopt;
    wopt.whisker_bearings.clear();
    for (const WhiskerMount& m : robot.mounts()) wopt.whisker_bearings.push_back(m.bearing);
    BodyWhisk whisk(robot, wopt);
    out.start_time = robot.now();
    out.start_pose = robot.odometry();
    // The mapping run's whisk (PhysicsSensorModel): counter-clockwise first.
    (void)whisk.startInPlace(+1);
    const double dt = rig.robot().options().dt;
    const long max_steps =
        static_cast<long>((whiskDuration(wopt) * 1.5 + 2.0 + options_.max_settle_s) / dt);
    bool whisking = true;
    double settle_until = 0.0;
    auto take = [&](const signal::ContactEpisode* ep) {
      if (ep == nullptr) return;
      out.episodes.push_back(*ep);
      out.truths.push_back(rig.episodeTruth());
      out.onset_poses.push_back(rig.poseAtSample(ep->start_sample));
    };
    for (long n = 0; n < max_steps; ++n) {
      take(rig.step());
      for (int w = 0; w < signal::kWhiskers; ++w) {
        if (robot.contact(w)) out.truth_touched |= 1u << w;
        out.max_theta[static_cast<std::size_t>(w)] = std::max(
            out.max_theta[static_cast<std::size_t>(w)], rig.pipeline().detector(w).theta());
      }
      if (whisking) {
        (void)whisk.update(rig.contactMask());
        if (whisk.done()) {
          whisking = false;
          settle_until = robot.now() + options_.max_settle_s;
        }
      } else if (!rig.pipeline().inEpisode() || robot.now() >= settle_until) {
        break;
      }
    }
    (void)robot.drive(0.0, 0.0);
    if (rig.pipeline().inEpisode()) take(rig.finish());
    rig.resetTruth();
    simulated_ += robot.now() - out.start_time;
    return out;
  }

  // Between whisks: stand clear until every detector has released (at least 50 ms, at most
  // 1 s). A whisk that ends pressed against the wall is cut by finish(), and a detector whose
  // whisker is still touching then cannot start an episode before it releases; without this
  // rest the next pressed start would give no onset at the start of its whisk.
  void rest(WhiskerRig& rig, const Pose2& clear) {
    WhiskeredRobot& robot = rig.robot();
    const double t0 = robot.now();
    robot.place(clear);
    const double dt = robot.options().dt;
    for (int n = 0; n < static_cast<int>(1.0 / dt); ++n) {
      (void)rig.step();
      if (n * dt >= 0.05 && rig.contactMask() == 0 && !rig.pipeline().inEpisode()) break;
    }
    if (rig.pipeline().inEpisode()) (void)rig.finish();
    rig.resetTruth();
    simulated_ += robot.now() - t0;
  }

  void tick(const char* phase) {
    ++done_;
    if (options_.progress) options_.progress({done_, total_, phase, simulated_});
  }

  double simulated() const { return simulated_; }

 private:
  const TrainingOptions& options_;
  int total_;
  int done_ = 0;
  double simulated_ = 0.0;
};

double maxFreeTheta(const WhiskResult& r) {
  double m = 0.0;
  for (int w = 0; w < signal::kWhiskers; ++w) {
    if (!(r.truth_touched & (1u << w))) m = std::max(m, r.max_theta[static_cast<std::size_t>(w)]);
  }
  return m;
}

// The pipeline's sample index k is the rig's step k: time k * dt since the rig was created.
double sampleTime(std::uint64_t sample, double dt) { return static_cast<double>(sample) * dt; }

RadialContact radialContact(const WhiskResult& r, int whisker, double dt) {
  RadialContact c;
  c.whisker = whisker;
  c.max_free_theta = maxFreeTheta(r);
  c.other_touched = r.truth_touched & ~(1u << whisker);
  const auto wi = static_cast<std::size_t>(whisker);
  for (std::size_t i = 0; i < r.episodes.size(); ++i) {
    const signal::ContactEpisode& ep = r.episodes[i];
    EpisodeRecord e;
    e.start_s = sampleTime(ep.start_sample, dt) - r.start_time;
    e.duration_s = ep.duration_s;
    e.touched = ep.whiskers[wi].touched;
    e.f1 = e.touched ? ep.whiskers[wi].f1 : 0.0;
    e.truth_touched = r.truths[i][wi].touched;
    e.r_at_peak = r.truths[i][wi].r_at_peak;
    for (int w = 0; w < signal::kWhiskers; ++w) {
      if (ep.whiskers[static_cast<std::size_t>(w)].touched) e.touched_mask |= 1u << w;
    }
    if (ep.truncated || ep.finished_early) c.truncated = true;
    if (e.touched && c.first_episode < 0) {
      c.first_episode = static_cast<int>(i);
      c.first_f1 = e.f1;
      c.first_r = e.r_at_peak;
    }
    if (e.touched && (!c.detected || e.f1 > c.f1)) {
      c.detected = true;
      c.f1 = e.f1;
      c.r = e.r_at_peak;
      c.truth_touched = e.truth_touched;
      c.peak_episode = static_cast<int>(i);
    }
    c.episodes.push_back(e);
  }
  return c;
}

// Straight-whisker reach of the robot at heading theta along unit direction n (from its centre).
double reach(const std::vector<WhiskerMount>& mounts, double theta, const Vec2& n) {
  double best = -1e9;
  const Pose2 at{0.0, 0.0, theta};
  for (const WhiskerMount& m : mounts) {
    const Vec2 base = at.toWorld(m.base);
    const double dir = theta + m.bearing;
    const Vec2 tip = base + m.length * Vec2(std::cos(dir), std::sin(dir));
    best = std::max({best, base.dot(n), tip.dot(n)});
  }
  return best;
}

}  // namespace

WhiskerRig::Options physicsRigOptions(std::uint64_t seed) {
  WhiskerRig::Options o;
  o.pipeline.detector.min_onset_threshold = kPhysicsOnsetThreshold;
  o.seed = seed;
  return o;
}

std::vector<double> trainingAngles() { return signal::defaultOrientationAngles(); }

Status TrainingOptions::validate() const {
  auto bad = [](const std::string& field, const std::string& why) {
    return Error{"training options: " + field + ": " + why};
  };
  for (std::size_t i = 0; i < radial_whiskers.size(); ++i) {
    const int w = radial_whiskers[i];
    if (w < 0 || w >= signal::kWhiskers) {
      return bad("radial_whiskers[" + std::to_string(i) + "]",
                 std::to_string(w) + " is not a whisker index 0..3");
    }
  }
  for (std::size_t i = 0; i < radial_distances.size(); ++i) {
    const double d = radial_distances[i];
    if (!(std::isfinite(d) && d - distance_jitter > 0.0 && d + distance_jitter <= 0.14)) {
      return bad("radial_distances[" + std::to_string(i) + "]",
                 num(d) + " m (with the jitter) is not on the 0.14 m whisker");
    }
  }
  if (radial_repeats < 0) return bad("radial_repeats", "must be >= 0");
  if (!(std::isfinite(eps_min) && std::isfinite(eps_max) && 0.0 < eps_min && eps_min <= eps_max &&
        eps_max < 0.3)) {
    return bad("eps_min/eps_max",
               num(eps_min) + ".." + num(eps_max) + " rad: need 0 < eps_min <= eps_max < 0.3");
  }
  if (!(std::isfinite(distance_jitter) && distance_jitter >= 0.0 && distance_jitter < 0.01)) {
    return bad("distance_jitter", num(distance_jitter) + " m: need [0, 0.01)");
  }
  for (std::size_t i = 0; i < angles.size(); ++i) {
    const double a = angles[i];
    if (!(std::isfinite(a) && a > 0.0 && a < kPi)) {
      return bad("angles[" + std::to_string(i) + "]", num(a) + " rad is not in (0, pi)");
    }
  }
  if (orientation_repeats < 0) return bad("orientation_repeats", "must be >= 0");
  if (!(std::isfinite(depth_min) && std::isfinite(depth_max) && 0.0 <= depth_min &&
        depth_min <= depth_max && depth_max < 0.5 * kWallThickness)) {
    return bad("depth_min/depth_max", num(depth_min) + ".." + num(depth_max) +
                                          " m: need 0 <= min <= max < half the wall thickness");
  }
  if (!(std::isfinite(lateral_jitter) && lateral_jitter >= 0.0 && lateral_jitter <= 0.5)) {
    return bad("lateral_jitter", num(lateral_jitter) + " m: need [0, 0.5]");
  }
  if (!(std::isfinite(max_settle_s) && max_settle_s > 0.0 && max_settle_s <= 60.0)) {
    return bad("max_settle_s", num(max_settle_s) + " s: need (0, 60]");
  }
  if (auto s = rig.validate(); !s) return bad("rig", s.error().message);
  if (plannedWhisks() == 0) return bad("protocol", "no contacts to collect");
  return okStatus();
}

int TrainingOptions::plannedWhisks() const {
  const int radial = static_cast<int>(radial_whiskers.size() * radial_distances.size()) *
                     radial_repeats * (radial_heldout ? 2 : 1);
  return radial + static_cast<int>(angles.size()) * orientation_repeats;
}

Pose2 placeForPole(const std::vector<WhiskerMount>& mounts, int whisker, double d, double eps,
                   const Vec2& face, double axis) {
  const WhiskerMount& m = mounts[static_cast<std::size_t>(whisker)];
  const double heading = axis - m.bearing;
  const Vec2 base = face - d * Vec2(std::cos(axis + eps), std::sin(axis + eps));
  const Pose2 rot{0.0, 0.0, heading};
  const Vec2 centre = base - rot.toWorld(m.base);
  return {centre.x(), centre.y(), heading};
}

Pose2 placeWall(const std::vector<WhiskerMount>& mounts, double angle, double depth, double lateral,
                const Vec2& face_point, double wall_dir, const Vec2& toward) {
  // The perpendicular from the robot to the wall is at bearing angle - pi/2 in the robot frame:
  // the wall's tangent is then at `angle` relative to the heading (modulo pi).
  const Vec2 to_wall = -toward;
  const double heading = std::atan2(to_wall.y(), to_wall.x()) - angle + kPi / 2.0;
  const double dist = reach(mounts, heading, to_wall) - depth;
  const Vec2 t(std::cos(wall_dir), std::sin(wall_dir));
  const Vec2 centre = face_point + lateral * t + dist * toward;
  return {centre.x(), centre.y(), wrapPeriod(heading, 2.0 * kPi)};
}

Result<TrainingData> collectTrainingData(const TrainingOptions& options) {
  if (auto s = options.validate(); !s) return s.error();
  TrainingData data;
  Collector col(options, options.plannedWhisks());
  const std::vector<WhiskerMount> mounts = defaultWhiskerArray();

  // ---- Radial: a 1 cm pole along +x; its near face (toward -y) centred at face.
  const bool radial = !options.radial_whiskers.empty() && !options.radial_distances.empty() &&
                      options.radial_repeats > 0;
  if (radial) {
    Scene scene;
    scene.width = scene.depth = kArena;
    scene.poses.clear();
    scene.source = "<training pole>";
    const Vec2 face = kObject - Vec2(0.0, 0.5 * kWallThickness);
    scene.walls.push_back(
        {kObject - Vec2(0.5 * kPoleLength, 0.0), kObject + Vec2(0.5 * kPoleLength, 0.0)});
    auto world = World::build(scene);
    for (int set = 0; set < (options.radial_heldout ? 2 : 1); ++set) {
      auto made = col.makeRig(*world, kRadialStart, streamSeed(options.seed, 10 + set));
      if (!made) return made.error();
      WhiskerRig& rig = *made.value();
      Rng rng(streamSeed(options.seed, 20 + set));
      const char* phase = set == 0 ? "radial-train" : "radial-heldout";
      for (const int w : options.radial_whiskers) {
        for (const double nominal : options.radial_distances) {
          for (int rep = 0; rep < options.radial_repeats; ++rep) {
            const double eps = rng.uniform(options.eps_min, options.eps_max);
            const double d =
                nominal + rng.uniform(-options.distance_jitter, options.distance_jitter);
            // The whisker's rest direction along the pole (+x): the toward leg (CCW) sweeps
            // it toward +y, into the pole's near face.
            const Pose2 pose = placeForPole(mounts, w, d, eps, face, 0.0);
            const WhiskResult r = col.whisk(rig, pose);
            col.rest(rig, kRadialStart);
            RadialContact c = radialContact(r, w, rig.robot().options().dt);
            c.set = set;
            c.repeat = rep;
            c.nominal_d = nominal;
            c.d = d;
            c.eps = eps;
            c.pose = pose;
            data.radial.push_back(std::move(c));
            col.tick(phase);
          }
        }
      }
      data.missing_frames += rig.missingFrames();
    }
  }

  // ---- Orientation: a long wall along +x; the robot below it (face toward -y).
  if (!options.angles.empty() && options.orientation_repeats > 0) {
    Scene scene;
    scene.width = scene.depth = kArena;
    scene.poses.clear();
    scene.source = "<training wall>";
    scene.walls.push_back(
        {kObject - Vec2(0.5 * kWallLength, 0.0), kObject + Vec2(0.5 * kWallLength, 0.0)});
    const Vec2 face = kObject - Vec2(0.0, 0.5 * kWallThickness);
    auto world = World::build(scene);
    auto made = col.makeRig(*world, kWallStart, streamSeed(options.seed, 30));
    if (!made) return made.error();
    WhiskerRig& rig = *made.value();
    Rng rng(streamSeed(options.seed, 40));
    for (int rep = 0; rep < options.orientation_repeats; ++rep) {
      for (const double angle : options.angles) {
        OrientationContact c;
        c.repeat = rep;
        c.angle = angle;
        c.depth = rng.uniform(options.depth_min, options.depth_max);
        c.lateral = rng.uniform(-options.lateral_jitter, options.lateral_jitter);
        c.pose = placeWall(mounts, angle, c.depth, c.lateral, face, 0.0, Vec2(0.0, -1.0));
        const WhiskResult r = col.whisk(rig, c.pose);
        col.rest(rig, kWallStart);
        c.episodes = static_cast<int>(r.episodes.size());
        c.max_free_theta = maxFreeTheta(r);
        if (!r.episodes.empty()) {
          const signal::ContactEpisode& ep = r.episodes.front();
          c.has_window = ep.window_complete;
          c.window = ep.window;
          c.onset_s = sampleTime(ep.start_sample, rig.robot().options().dt) - r.start_time;
          c.onset_offset = r.onset_poses.front().theta - r.start_pose.theta;
          for (int w = 0; w < signal::kWhiskers; ++w) {
            if (ep.whiskers[static_cast<std::size_t>(w)].touched) c.touched_mask |= 1u << w;
          }
        }
        data.orientation.push_back(std::move(c));
        col.tick("orientation");
      }
    }
    data.missing_frames += rig.missingFrames();
  }
  data.simulated_s = col.simulated();
  return data;
}

const char* radialFeatureName(RadialFeature feature) {
  switch (feature) {
    case RadialFeature::kF1:
      return "f1";
    case RadialFeature::kInvSqrtF1:
      return "f1^-1/2";
  }
  return "?";
}

const char* radialLabelName(RadialLabel label) {
  switch (label) {
    case RadialLabel::kTruthAtPeak:
      return "truth_at_peak";
    case RadialLabel::kNominal:
      return "nominal";
  }
  return "?";
}

const char* f1SourceName(F1Source source) {
  switch (source) {
    case F1Source::kMaxOverWhisk:
      return "max_over_whisk";
    case F1Source::kFirstEpisode:
      return "first_episode";
  }
  return "?";
}

std::vector<RadialVariant> allRadialVariants() {
  std::vector<RadialVariant> v;
  for (const F1Source s : {F1Source::kMaxOverWhisk, F1Source::kFirstEpisode}) {
    for (const RadialFeature f : {RadialFeature::kF1, RadialFeature::kInvSqrtF1}) {
      for (const RadialLabel l : {RadialLabel::kTruthAtPeak, RadialLabel::kNominal}) {
        v.push_back({s, f, l});
      }
    }
  }
  return v;
}

namespace {
double featureOf(RadialFeature feature, double f1) {
  return feature == RadialFeature::kF1 ? f1 : 1.0 / std::sqrt(f1);
}
double f1Of(F1Source source, const RadialContact& c) {
  return source == F1Source::kMaxOverWhisk ? c.f1 : c.first_f1;
}
double labelOf(const RadialVariant& v, const RadialContact& c) {
  if (v.label == RadialLabel::kNominal) return c.nominal_d;
  return v.source == F1Source::kMaxOverWhisk ? c.r : c.first_r;
}
std::string variantName(const RadialVariant& v) {
  return std::string(f1SourceName(v.source)) + ", " + radialFeatureName(v.feature) + ", " +
         radialLabelName(v.label);
}
}  // namespace

Result<RadialEvaluation> evaluateRadial(const std::vector<RadialContact>& contacts,
                                        const RadialVariant& variant,
                                        const signal::RadialOptions& options) {
  const RadialFeature feature = variant.feature;
  std::vector<signal::RadialTrainingSample> train;
  for (const RadialContact& c : contacts) {
    if (c.set != 0 || !c.detected || !(f1Of(variant.source, c) > 0.0)) continue;
    train.push_back({c.whisker, featureOf(feature, f1Of(variant.source, c)), labelOf(variant, c)});
  }
  auto fit = signal::fitRadialModel(train, options);
  if (!fit) return Error{"radial fit (" + variantName(variant) + "): " + fit.error().message};
  RadialEvaluation ev;
  ev.variant = variant;
  ev.fit = std::move(fit).value();
  std::array<double, signal::kWhiskers> sum{}, sum2{};
  double combo2 = 0.0;
  for (const RadialContact& c : contacts) {
    if (c.set != 1 || !c.detected || !(f1Of(variant.source, c) > 0.0)) continue;
    const auto w = static_cast<std::size_t>(c.whisker);
    const double x = featureOf(feature, f1Of(variant.source, c));
    const double e = ev.fit.model.whiskers[w].predict(x) - labelOf(variant, c);
    sum[w] += e;
    sum2[w] += e * e;
    ++ev.heldout_n[w];
    const double ec = ev.fit.summary.combined.predict(x) - labelOf(variant, c);
    combo2 += ec * ec;
  }
  double all = 0.0, all2 = 0.0;
  for (std::size_t w = 0; w < sum.size(); ++w) {
    ev.heldout_n_all += ev.heldout_n[w];
    all += sum[w];
    all2 += sum2[w];
    if (ev.heldout_n[w] > 0) {
      ev.heldout_mean[w] = sum[w] / ev.heldout_n[w];
      ev.heldout_rms[w] = std::sqrt(sum2[w] / ev.heldout_n[w]);
    }
  }
  if (ev.heldout_n_all == 0) {
    return Error{"radial evaluation (" + variantName(variant) +
                 "): the held-out set has no detected contacts"};
  }
  ev.heldout_mean_all = all / ev.heldout_n_all;
  ev.heldout_rms_all = std::sqrt(all2 / ev.heldout_n_all);
  ev.combo_heldout_rms = std::sqrt(combo2 / ev.heldout_n_all);
  return ev;
}

std::vector<signal::LabelledWindow> labelledWindows(
    const std::vector<OrientationContact>& contacts) {
  std::vector<signal::LabelledWindow> out;
  for (const OrientationContact& c : contacts) {
    if (c.has_window) out.push_back({c.angle, c.repeat, c.window});
  }
  return out;
}

}  // namespace crunch::sim
