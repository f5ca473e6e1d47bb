#include "crunch_sim/beam_probe.h"

#include <cmath>
#include <string>

#include "crunch/robot/shapelet.h"
#include "crunch/scene/scene.h"
#include "crunch_sim/world.h"

namespace crunch::sim {
namespace {

constexpr int kWhisker = 2;                   // bearing +11.25 degrees
constexpr Pose2 kRobotPose{2.0, 2.0, 0.3};    // mid-arena, an arbitrary heading
constexpr double kTurnRate = kPi / 24.0;      // the body whisk's rate, rad/s

// A scene with one table whose leg has a vertical edge at `edge`, the leg turned 45 degrees to
// heading `a` so the edge faces the whisker from its left (along -n), and the table's other
// legs on the side away from the robot.
Scene edgeScene(const Vec2& robot, double a, const Vec2& edge) {
  const Vec2 n(-std::sin(a), std::cos(a));
  TableSpec t;
  t.pose.theta = a + 0.25 * kPi;
  const Vec2 leg_centre = edge + (t.leg / std::sqrt(2.0)) * n;
  const double c = std::cos(t.pose.theta), s = std::sin(t.pose.theta);
  double farthest = -1.0;
  for (int k = 0; k < 4; ++k) {
    const double sx = (k & 1) ? 1.0 : -1.0, sy = (k & 2) ? 1.0 : -1.0;
    const Vec2 off(sx * 0.5 * (t.width - t.leg), sy * 0.5 * (t.depth - t.leg));
    const Vec2 centre = leg_centre - Vec2(c * off.x() - s * off.y(), s * off.x() + c * off.y());
    const double dist = (centre - robot).norm();
    if (dist > farthest) {
      farthest = dist;
      t.pose.x = centre.x();
      t.pose.y = centre.y();
    }
  }
  Scene scene;
  scene.width = 4.0;
  scene.depth = 4.0;
  scene.tables.push_back(t);
  return scene;
}

}  // namespace

Result<BeamPush> pushWhisker(const WhiskeredRobot::Options& options, double d, double delta,
                             double settle_s) {
  WhiskeredRobot::Options opt = options;
  opt.friction = 0.0;
  if (Status s = opt.validate(); !s) return s.error();
  const double L = opt.beam.external_length;
  if (!(d > 0.0 && d < L)) return Error{"pushWhisker: d must lie in (0, external_length)"};
  if (!(delta > 0.0 && delta < d)) return Error{"pushWhisker: delta must lie in (0, d)"};
  if (!(settle_s >= 0.0)) return Error{"pushWhisker: settle_s must be >= 0"};

  std::vector<WhiskerMount> mounts = defaultWhiskerArray();
  for (WhiskerMount& m : mounts) m.length = L;
  const WhiskerMount& m = mounts[kWhisker];
  const double a = kRobotPose.theta + m.bearing;
  const Vec2 u(std::cos(a), std::sin(a)), n(-std::sin(a), std::cos(a));
  const double rho = m.base.norm() + d;  // the whisker line passes through the robot's centre
  const Vec2 edge = kRobotPose.position() + rho * u + kBeamProbeGap * n;

  const std::unique_ptr<World> world = World::build(edgeScene(kRobotPose.position(), a, edge));
  auto made = WhiskeredRobot::create(*world, mounts, opt);
  if (!made) return made.error();
  WhiskeredRobot& robot = *made.value();
  robot.place(kRobotPose);

  // The capsule under the edge sets the surface's offset from the centreline.
  int seg = 0;
  for (int i = 0; i < robot.segmentCount(); ++i) {
    if (robot.segmentStart(i) <= d) seg = i;
  }
  const double radius = robot.segmentRadius(seg);
  // In the turning whisker's frame the edge sits at polar (rc, alpha - turn): sideways offset
  // rc sin(alpha - turn), so the centreline is pushed by radius - rc sin(alpha - turn).
  const double rc = std::hypot(rho, kBeamProbeGap);
  const double alpha = std::atan2(kBeamProbeGap, rho);
  const double turn_goal = alpha + std::asin((delta - radius) / rc);
  const int steps = static_cast<int>(std::lround(turn_goal / kTurnRate / opt.dt));
  if (Status s = robot.drive(0.0, kTurnRate); !s) return s.error();
  for (int i = 0; i < steps; ++i) robot.step();
  if (Status s = robot.stop(); !s) return s.error();
  robot.run(settle_s);

  const double turn = robot.odometry().theta - kRobotPose.theta;
  BeamPush out;
  out.delta = radius + rc * std::sin(turn - alpha);
  out.d = rc * std::cos(turn - alpha) - m.base.norm();
  const BaseAngles angles = robot.baseAngles(kWhisker);
  out.simulated = std::abs(angles.horizontal);
  out.vertical = std::abs(angles.vertical);
  out.predicted = opt.beam.baseAngle(out.delta, out.d);
  out.base_moment = out.simulated * opt.beam.follicle_stiffness;
  const auto c = robot.contact(kWhisker);
  if (!c) {
    return Error{"pushWhisker: whisker " + std::to_string(kWhisker) +
                 " is not touching the edge at d = " + std::to_string(d) + " m after settling"};
  }
  out.contact_r = c->r;
  return out;
}

}  // namespace crunch::sim
