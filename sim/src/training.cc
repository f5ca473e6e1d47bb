#include "crunch_sim/training.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <utility>

#include "crunch/behaviour/body_whisk.h"
#include "crunch/core/rng.h"
#include "crunch/robot/whisker_beam.h"
#include "crunch/session/whisk_evidence.h"
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
  std::vector<SamplePose> poses;  // onset, peaks and ramps of every episode
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
    ropt.negative_evidence = false;  // episodes only; no whisk ever ends on the chain
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
      auto keep = [&](std::uint64_t sample) {
        out.poses.push_back({sample, rig.poseAtSample(sample)});
      };
      keep(ep->start_sample);
      for (const signal::WhiskerContact& c : ep->whiskers) {
        if (!c.touched) continue;
        keep(ep->start_sample + static_cast<std::uint64_t>(std::max<std::int64_t>(c.peak_sample, 0)));
        if (c.ramp.valid) keep(c.ramp.first_sample);
      }
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

Pose2 poseOf(const std::vector<SamplePose>& poses, std::uint64_t sample, const Pose2& fallback) {
  for (const SamplePose& p : poses) {
    if (p.sample == sample) return p.pose;
  }
  return fallback;
}

// Whisker w's first contact of the whisk: the first episode in which the pipeline saw it touch.
LocatedContact locate(const WhiskResult& r, int whisker) {
  LocatedContact out;
  const auto wi = static_cast<std::size_t>(whisker);
  for (std::size_t i = 0; i < r.episodes.size(); ++i) {
    const signal::WhiskerContact& c = r.episodes[i].whiskers[wi];
    if (!c.touched) continue;
    const WhiskerTruth& t = r.truths[i][wi];
    out.detected = true;
    out.episode = static_cast<int>(i);
    out.ramp = c.ramp;
    out.ramp_pose = poseOf(r.poses, c.ramp.first_sample, r.start_pose);
    out.f1 = c.f1;
    out.truth_touched = t.touched;
    out.r_touch = t.r_at_touch;
    out.r_peak = t.r_at_peak;
    out.point_touch = t.point_at_touch;
    break;
  }
  return out;
}

double leverOf(const WhiskerMount& m) { return m.base.dot(m.direction()); }

RadialContact radialContact(const WhiskResult& r, int whisker, double dt) {
  RadialContact c;
  c.located = locate(r, whisker);
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

const char* rampObjectName(RampObject object) {
  return object == RampObject::kLeg ? "leg" : "post";
}

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
  for (std::size_t i = 0; i < ramp_whiskers.size(); ++i) {
    const int w = ramp_whiskers[i];
    if (w < 0 || w >= signal::kWhiskers) {
      return bad("ramp_whiskers[" + std::to_string(i) + "]",
                 std::to_string(w) + " is not a whisker index 0..3");
    }
  }
  for (std::size_t i = 0; i < ramp_distances.size(); ++i) {
    const double d = ramp_distances[i];
    if (!(std::isfinite(d) && d - distance_jitter >= 0.01 && d + distance_jitter <= 0.14)) {
      return bad("ramp_distances[" + std::to_string(i) + "]",
                 num(d) + " m (with the jitter) is not in [0.01, 0.14] m of the whisker");
    }
  }
  if (ramp_repeats < 0) return bad("ramp_repeats", "must be >= 0");
  if (!(std::isfinite(edge_min) && std::isfinite(edge_max) && 0.0 < edge_min &&
        edge_min <= edge_max && edge_max < kPi / 2.0 - 0.1)) {
    return bad("edge_min/edge_max", num(edge_min) + ".." + num(edge_max) +
                                        " rad: need 0 < min <= max < pi/2 - 0.1 (both faces "
                                        "beyond the edge, with the eps margin)");
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
  const int ramp = static_cast<int>(ramp_whiskers.size() * ramp_distances.size()) * 2 *
                   (ramp_both_directions ? 2 : 1) * ramp_repeats * (ramp_heldout ? 2 : 1);
  return radial + ramp + static_cast<int>(angles.size()) * orientation_repeats;
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

Pose2 placeForEdge(const std::vector<WhiskerMount>& mounts, int whisker, double d, double eps,
                   int direction, const Vec2& corner, double face_dir, double edge) {
  // The line base -> corner: the first face of the sweep leaves the corner `edge` beyond it in
  // the sweep's sense, the second a quarter turn further.
  const double radial =
      direction > 0 ? face_dir - edge : face_dir + kPi / 2.0 + edge;
  const double s = direction > 0 ? 1.0 : -1.0;
  return placeForPole(mounts, whisker, d, s * eps, corner, radial - s * eps);
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
            c.lever = leverOf(mounts[static_cast<std::size_t>(w)]);
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

  // ---- Ramp: a table's leg and a post in one 6 x 6 m arena, each met at its corner C whose
  // faces leave it along -x and -y; the table is 2 m square so its other legs are out of reach.
  const bool ramp = !options.ramp_whiskers.empty() && !options.ramp_distances.empty() &&
                    options.ramp_repeats > 0;
  if (ramp) {
    Scene scene;
    scene.width = scene.depth = 6.0;
    scene.poses.clear();
    scene.source = "<training leg and post>";
    TableSpec table;
    table.pose = Pose2{3.0, 3.0, 0.0};
    table.width = table.depth = 2.0;
    table.leg = 0.05;
    scene.tables.push_back(table);
    const Vec2 leg_corner{4.0, 4.0};  // the +x+y leg's outer corner
    constexpr double kPost = 0.02;
    const Vec2 post_corner{1.0, 4.5};
    scene.walls.push_back({post_corner + Vec2(-kPost, -0.5 * kPost),
                           post_corner + Vec2(0.0, -0.5 * kPost)});
    const double face_dir = kPi;  // faces along -x and -y from each corner
    const Pose2 start{1.0, 1.0, 0.0};
    auto world = World::build(scene);
    for (int set = 0; set < (options.ramp_heldout ? 2 : 1); ++set) {
      auto made = col.makeRig(*world, start, streamSeed(options.seed, 50 + set));
      if (!made) return made.error();
      WhiskerRig& rig = *made.value();
      Rng rng(streamSeed(options.seed, 60 + set));
      const char* phase = set == 0 ? "ramp-train" : "ramp-heldout";
      for (const int w : options.ramp_whiskers) {
        for (const double nominal : options.ramp_distances) {
          for (const RampObject object : {RampObject::kLeg, RampObject::kPost}) {
            for (const int direction : {+1, -1}) {
              if (direction < 0 && !options.ramp_both_directions) continue;
              for (int rep = 0; rep < options.ramp_repeats; ++rep) {
                RampContact c;
                c.set = set;
                c.whisker = w;
                c.repeat = rep;
                c.object = object;
                c.direction = direction;
                c.nominal_d = nominal;
                c.eps = rng.uniform(options.eps_min, options.eps_max);
                c.d = nominal + rng.uniform(-options.distance_jitter, options.distance_jitter);
                c.lever = leverOf(mounts[static_cast<std::size_t>(w)]);
                const Vec2& corner = object == RampObject::kLeg ? leg_corner : post_corner;
                // Near the follicle the object's second face points back toward the body: an
                // edge angle whose object would overlap the body is drawn again (so such
                // contacts see the smaller edge angles; the ramp does not depend on it).
                for (int draw = 0;; ++draw) {
                  c.edge = rng.uniform(options.edge_min, options.edge_max);
                  c.pose = placeForEdge(mounts, w, c.d, c.eps, direction, corner, face_dir, c.edge);
                  if (!world->bodyCollides(c.pose)) break;
                  if (draw == 100) {
                    return Error{"ramp protocol: no edge angle in [edge_min, edge_max] keeps the "
                                 "body clear of the " + std::string(rampObjectName(object)) +
                                 " at " + num(c.d) + " m"};
                  }
                }
                const WhiskResult r = col.whisk(rig, c.pose);
                col.rest(rig, start);
                c.contact = locate(r, w);
                c.other_touched = r.truth_touched & ~(1u << w);
                for (const signal::ContactEpisode& ep : r.episodes) {
                  if (ep.truncated || ep.finished_early) c.truncated = true;
                }
                data.ramp.push_back(std::move(c));
                col.tick(phase);
              }
            }
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
        c.all_episodes = r.episodes;
        c.poses = r.poses;
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

namespace crunch::sim {

double rampDistance(const LocatedContact& c, double lever, const signal::RampCalibration& cal) {
  static const WhiskerBeam beam;  // the host's description: the nominal whisker
  return std::min(distanceFromRampSlope(beam, c.ramp.slope, lever, cal.gain, cal.compliance_scale),
                  beam.external_length);
}

std::vector<RampSample> rampSamples(const std::vector<RampContact>& contacts, int set) {
  std::vector<RampSample> out;
  for (const RampContact& c : contacts) {
    const LocatedContact& l = c.contact;
    if (c.set != set || !l.detected || !l.truth_touched || !l.ramp.valid) continue;
    out.push_back({l.ramp.slope, c.lever, l.r_touch});
  }
  return out;
}

ErrorStats errorStats(const std::vector<std::pair<int, double>>& errors) {
  ErrorStats s;
  std::array<double, signal::kWhiskers> sum{}, sum2{};
  std::vector<double> abs;
  double all = 0.0, all2 = 0.0;
  for (const auto& [w, e] : errors) {
    const auto i = static_cast<std::size_t>(w);
    sum[i] += e;
    sum2[i] += e * e;
    ++s.n[i];
    all += e;
    all2 += e * e;
    abs.push_back(std::abs(e));
  }
  for (std::size_t i = 0; i < sum.size(); ++i) {
    if (s.n[i] == 0) continue;
    s.mean[i] = sum[i] / s.n[i];
    s.rms[i] = std::sqrt(sum2[i] / s.n[i]);
  }
  s.n_all = static_cast<int>(errors.size());
  if (s.n_all > 0) {
    s.mean_all = all / s.n_all;
    s.rms_all = std::sqrt(all2 / s.n_all);
    std::sort(abs.begin(), abs.end());
    auto at = [&](double q) {  // nearest rank
      const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(abs.size())));
      return abs[std::min(abs.size() - 1, k == 0 ? 0 : k - 1)];
    };
    s.median_abs = at(0.5);
    s.p90_abs = at(0.9);
  }
  return s;
}

Result<RampEvaluation> evaluateRamp(const TrainingData& data, const signal::RadialModel& eq2,
                                    const RampFitOptions& options) {
  RampEvaluation ev;
  auto fit = fitRampCalibration(WhiskerBeam{}, rampSamples(data.ramp, 0), options);
  if (!fit) return Error{"ramp calibration: " + fit.error().message};
  ev.fit = fit.value();
  ev.calibration.gain = ev.fit.gain;
  ev.calibration.compliance_scale = ev.fit.compliance_scale;
  if (auto s = ev.calibration.validate(); !s) return Error{"ramp calibration: " + s.error().message};
  const signal::RampCalibration nominal;
  std::vector<std::pair<int, double>> en, ef, e2;
  for (const RampContact& c : data.ramp) {
    if (c.set != 1) continue;
    ++ev.heldout_contacts;
    const LocatedContact& l = c.contact;
    if (!l.detected || !l.truth_touched) {
      ++ev.heldout_not_seen;
      continue;
    }
    const auto wi = static_cast<std::size_t>(c.whisker);
    e2.push_back({c.whisker, eq2.whiskers[wi].predict(l.f1) - l.r_peak});
    if (!l.ramp.valid) {
      ++ev.heldout_no_ramp;
      continue;
    }
    en.push_back({c.whisker, rampDistance(l, c.lever, nominal) - l.r_touch});
    ef.push_back({c.whisker, rampDistance(l, c.lever, ev.calibration) - l.r_touch});
  }
  if (ef.empty()) return Error{"ramp evaluation: the held-out set has no located contacts"};
  ev.nominal = errorStats(en);
  ev.fitted = errorStats(ef);
  ev.eq2 = errorStats(e2);
  std::vector<std::pair<int, double>> rn, rf;
  for (const RadialContact& c : data.radial) {
    const LocatedContact& l = c.located;
    if (c.set != 1 || !l.detected || !l.truth_touched || !l.ramp.valid) continue;
    rn.push_back({c.whisker, rampDistance(l, c.lever, nominal) - l.r_touch});
    rf.push_back({c.whisker, rampDistance(l, c.lever, ev.calibration) - l.r_touch});
  }
  ev.radial_nominal = errorStats(rn);
  ev.radial_fitted = errorStats(rf);
  return ev;
}

FaceEvaluation evaluateFaces(const std::vector<OrientationContact>& contacts,
                             const signal::SignalModels& models) {
  FaceEvaluation out;
  WhiskEvidence evidence(defaultWhiskerArray(), WhiskerBeam{});
  evidence.setModels(models);
  std::vector<ContactReport> reports;
  std::vector<FreeRay> rays;
  double sum = 0.0, sum2 = 0.0;
  for (const OrientationContact& c : contacts) {
    FaceTrial t;
    t.repeat = c.repeat;
    t.true_angle = c.angle;
    evidence.begin();
    // The models' radial lines give has_r; the ramp locates (whisk_evidence.h).
    for (signal::ContactEpisode ep : c.all_episodes) {
      for (std::size_t w = 0; w < ep.whiskers.size(); ++w) {
        signal::WhiskerContact& wc = ep.whiskers[w];
        if (!wc.touched) continue;
        wc.has_r = true;
        wc.r = models.radial.whiskers[w].predict(wc.f1);
      }
      evidence.take(ep, [&](std::uint64_t k) { return poseOf(c.poses, k, c.pose); });
    }
    reports.clear();
    rays.clear();
    evidence.end(reports, rays);
    double err = 0.0;
    int faces = 0;
    for (const ContactReport& r : reports) {
      ++t.reports;
      if (r.r >= WhiskerBeam{}.external_length - models.radial.options.tip_zone) ++t.tips;
      if (!r.oriented) continue;
      // The wall runs along +x: its tangent is 0 modulo pi.
      err += std::remainder(r.phi + r.robot.theta, kPi);
      ++faces;
    }
    if (faces > 0) {
      t.located = true;
      t.error = err / faces;
      ++out.located;
      sum += t.error;
      sum2 += t.error * t.error;
      out.max_abs_error = std::max(out.max_abs_error, std::abs(t.error));
    }
    out.trials.push_back(t);
  }
  if (out.located > 0) {
    out.mean_error = sum / out.located;
    out.rms_error = std::sqrt(sum2 / out.located);
    out.sd_error = out.located > 1 ? std::sqrt(std::max(0.0, (sum2 - sum * sum / out.located) /
                                                               (out.located - 1)))
                                   : 0.0;
  }
  return out;
}

}  // namespace crunch::sim
