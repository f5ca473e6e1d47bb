#include "crunch_sim/explore_run.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "crunch/mapping/evaluation.h"
#include "crunch/mapping/mapper.h"
#include "crunch/session/explore_loop.h"
#include "crunch_sim/kinematic_base.h"
#include "crunch_sim/ray_sensor.h"

namespace crunch::sim {

namespace {

std::unique_lock<std::mutex> lockWorld(std::mutex* mutex) {
  return mutex ? std::unique_lock<std::mutex>(*mutex) : std::unique_lock<std::mutex>();
}

double reachOf(const std::vector<WhiskerMount>& mounts) {
  double reach = 0.0;
  for (const WhiskerMount& m : mounts) reach = std::max(reach, m.base.norm() + m.length);
  return reach;
}

// The Mapper's region. The grid policy keeps runMapping's (the reach of the pose list), so that
// `--explore grid --teleport` maps exactly what the run without --explore maps; the other
// policies go anywhere in the arena: the arena grown by the whiskers' reach.
std::pair<Vec2, Vec2> mapperRegion(const SimScene& s, const std::vector<WhiskerMount>& mounts,
                                   bool grid) {
  const double reach = reachOf(mounts);
  const Vec2 pad{reach + 0.05, reach + 0.05};
  if (grid) {
    Vec2 lo{0, 0}, hi{0, 0};
    if (!s.poses.empty()) lo = hi = s.poses.front().position();
    for (const Pose2& p : s.poses) {
      lo = lo.cwiseMin(p.position());
      hi = hi.cwiseMax(p.position());
    }
    return {lo - pad, hi + pad};
  }
  return {Vec2(0, 0) - pad, Vec2(s.scene.width, s.scene.depth) + pad};
}

std::string poseText(const Pose2& p) {
  std::ostringstream s;
  s << p.x << "," << p.y << "," << p.theta;
  return s.str();
}

}  // namespace

Result<ExploreRun> runExploration(const SimScene& scene, SensorModel& sensor,
                                  const MappingOptions& mopt,
                                  const exploration::ExploreOptions& eo, std::mutex* world_mutex,
                                  const ExploreSimOptions& so) {
  if (auto st = eo.validate(); !st) return st.error();
  const double width = scene.scene.width, depth = scene.scene.depth;
  Pose2 start;
  if (eo.start) {
    start = *eo.start;
    const std::string flag = "--start " + poseText(start) + ": ";
    if (start.x < 0 || start.y < 0 || start.x > width || start.y > depth) {
      std::ostringstream s;
      s << flag << "outside the arena [0, " << width << "] x [0, " << depth << "]";
      return Error{s.str()};
    }
    auto lock = lockWorld(world_mutex);
    if (scene.world->bodyCollides(start)) {
      return Error{flag + "inside an obstacle (the robot's body overlaps a wall or a leg there)"};
    }
  } else if (!scene.poses.empty()) {
    start = scene.poses.front();
  } else {
    return Error{"--explore: the scene has no reachable pose to start from; give --start x,y,theta"};
  }

  const std::vector<WhiskerMount>& mounts = sensor.mounts();
  const bool grid = eo.policy == exploration::ExplorePolicyKind::kGrid;
  const auto [lo, hi] = mapperRegion(scene, mounts, grid);
  // The known region's edges are the room's walls (the policies and the planner treat them so):
  // a driven robot's blackboard knows no leg stands beyond them. Teleported runs (the paper's
  // idealisation) stay the paper's: neither the room nor the body's sweep.
  MappingOptions room_opt = mopt;
  if (!eo.teleport) room_opt.room = std::pair<Vec2, Vec2>{Vec2(0, 0), Vec2(width, depth)};
  Mapper mapper(mounts, lo, hi, room_opt);
  exploration::KnownSpace known(Vec2(0, 0), Vec2(width, depth), eo.cell);
  auto policy = exploration::makePolicy(eo.policy, eo.policy_options);
  const MatchTolerance tol = matchToleranceFor(mopt.model);

  Rng sense_rng(mopt.seed);
  std::vector<ContactReport> reports;
  std::vector<FreeRay> free_rays;
  std::vector<exploration::CurvePoint> curve;
  // The curve's inferences draw from their own stream: the run's final map does not depend on
  // how often it is scored.
  Rng curve_rng(mopt.seed ^ 0xC0A5EC0ull);
  double next_curve_m = 0.0;
  // Set by the caller before each whisk: the travel so far, for the curve.
  double travel_now = 0.0;
  int whisks_now = 0;
  auto whisked = [&](const Pose2& pose) {
    reports.clear();
    sensor.sense(pose, sense_rng, reports);
    free_rays.clear();
    sensor.freeRays(free_rays);
    mapper.addPose(pose, reports, free_rays);
    if (so.observe) so.observe(mapper, pose);
    for (const FreeRay& r : free_rays) known.markFreeRay(r);
    for (const ContactReport& r : reports) {
      if (r.whisker < 0 || r.whisker >= static_cast<int>(mounts.size()) || !std::isfinite(r.r)) continue;
      known.markContact(mounts[r.whisker].pointAt(r.robot, r.r));
    }
    const Map snap = mapper.snapshot();
    known.setMapObstacles(snap.tables, snap.walls);
    if (curve.empty() || travel_now >= next_curve_m) {
      const Evaluation ev = evaluate(mapper.inferNow(curve_rng), scene.scene, tol);
      curve.push_back({travel_now, whisks_now + 1, ev.recall, ev.precision, ev.f1});
      next_curve_m = (std::floor(travel_now / eo.curve_step_m) + 1.0) * eo.curve_step_m;
    }
  };
  // Simulated time stands still while the draws are made: all at once.
  auto samples = [&](int n, std::vector<MapSample>& out) {
    mapper.drawSamples(n, eo.sample_beta, eo.sample_sweeps, out);
    return true;
  };

  ExploreRun run;
  if (eo.teleport) {
    // The paper's idealisation: jump to each whisk pose; the whisk itself takes its time.
    const BodyWhisk::Options whisk;
    const double whisk_s = 4.0 * whisk.whisk_amplitude / whisk.whisk_rate;
    exploration::ExplorationReport& rep = run.report;
    rep.policy = exploration::explorePolicyName(eo.policy);
    Pose2 at = start;
    rep.path.push_back(at);
    known.markBody(at.position(), eo.planner.robot_radius);
    Rng rng(mopt.seed);
    std::vector<MapSample> drawn;
    double total_ms = 0.0;
    int decisions = 0;
    while (true) {
      if (rep.travel_m >= eo.travel_budget_m) {
        rep.stop_reason = "travel budget reached";
        break;
      }
      if (eo.whisk_budget > 0 && rep.whisks >= eo.whisk_budget) {
        rep.stop_reason = "whisk budget reached";
        break;
      }
      drawn.clear();
      if (policy->samplesWanted() > 0) samples(policy->samplesWanted(), drawn);
      double ms = 0.0;
      const auto d = exploration::decide(*policy, known, eo.planner, at, drawn, mounts, mopt.model,
                                         scene.poses, rep.whisks, rep.travel_m, true, 0.0, {}, 0.0,
                                         rng, &ms);
      total_ms += ms;
      ++decisions;
      rep.decision_ms_max = std::max(rep.decision_ms_max, ms);
      if (!d.goal) {
        rep.stop_reason = d.why;
        break;
      }
      rep.travel_m += (d.goal->position() - at.position()).norm();
      at = *d.goal;
      rep.path.push_back(at);
      known.markBody(at.position(), eo.planner.robot_radius);
      travel_now = rep.travel_m;
      whisks_now = rep.whisks;
      whisked(at);
      ++rep.whisks;
      rep.whisk_poses.push_back(at);
    }
    rep.decision_ms = decisions > 0 ? total_ms / decisions : 0.0;
    rep.sim_time_s = rep.whisks * whisk_s;
  } else {
    KinematicBase base(*scene.world, KinematicBase::Options{.start = start});
    session::ExploreLoop::Options lo_opts;
    lo_opts.explore = eo;
    lo_opts.seed = mopt.seed;
    session::ExploreLoop* loop_ptr = nullptr;
    // Where the body drove is where no leg stands (Mapper::addBodySweep): the path the loop
    // recorded since the last whisk, segment by segment, then on to `to`.
    std::size_t swept = 0;
    std::optional<Vec2> swept_to;
    auto sweepTo = [&](const Vec2& to) {
      const std::vector<Pose2>& path = loop_ptr->report().path;
      for (; swept < path.size(); ++swept) {
        const Vec2 p = path[swept].position();
        mapper.addBodySweep(swept_to.value_or(p), p);
        swept_to = p;
      }
      mapper.addBodySweep(swept_to.value_or(to), to);
      swept_to = to;
    };
    session::ExploreLoop::Hooks hooks{
        .whisked =
            [&](const Pose2& pose) {
              sweepTo(pose.position());
              travel_now = loop_ptr->report().travel_m;
              whisks_now = loop_ptr->report().whisks - 1;  // the loop counted this one already
              whisked(pose);
            },
        .samples = samples,
        // The simulator stands in for a bumper that knows where it was pressed: the nearest
        // point of any wall or leg to the body (the Create's own bumpers tell left from right
        // only; docs/EXPLORATION.md).
        .bump_point = [&](const Pose2& pose) -> std::optional<Vec2> {
          auto lock = lockWorld(world_mutex);
          return scene.world->nearestSurfacePoint(pose.position());
        }};
    session::ExploreLoop loop(base, known, *policy, mounts, mopt.model, scene.poses, lo_opts,
                              std::move(hooks));
    loop_ptr = &loop;
    const double z = RaySensorModel::Options{}.z;
    while (!loop.finished()) {
      if (base.now() >= so.max_sim_time_s) {
        loop.finish("simulated time limit reached");
        break;
      }
      std::uint32_t mask = 0;
      Vec2 touch{0, 0};
      double nearest = std::numeric_limits<double>::infinity();
      {
        auto lock = lockWorld(world_mutex);
        const Pose2 p = base.odometry();
        for (std::size_t w = 0; w < mounts.size() && w < 32; ++w) {
          const WhiskerMount& m = mounts[w];
          const auto hit = scene.world->castRay(p.toWorld(m.base), p.theta + m.bearing, m.length, z);
          if (!hit) continue;
          mask |= 1u << w;
          if (hit->distance < nearest) {
            nearest = hit->distance;
            touch = hit->point;
          }
        }
      }
      if (auto st = loop.update(mask, mask ? &touch : nullptr); !st) return st.error();
      {
        auto lock = lockWorld(world_mutex);
        base.step(so.dt);
      }
      if (so.moved) so.moved(base.odometry(), base.now());
    }
    sweepTo(base.odometry().position());
    run.report = loop.report();
  }
  run.report.teleport = eo.teleport;
  run.map = mapper.finish();
  // The curve ends on the final map (the report's accuracy), at the run's whole travel.
  if (run.report.whisks > 0) {
    const Evaluation ev = evaluate(run.map, scene.scene, tol);
    if (!curve.empty() && curve.back().whisks == run.report.whisks) curve.pop_back();
    curve.push_back({run.report.travel_m, run.report.whisks, ev.recall, ev.precision, ev.f1});
  }
  run.report.curve = std::move(curve);
  run.map.stats.poses = run.report.whisks;
  run.map.stats.skipped_poses = grid ? scene.skipped : 0;
  return run;
}

}  // namespace crunch::sim
