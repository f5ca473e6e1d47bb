#include "crunch/mapping/run_mapping.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <vector>

#include "crunch/robot/whiskers.h"

using namespace crunch;

namespace {
// A scripted sensor: every pose reports the same list, shifted by nothing (reports carry their
// own robot pose). Lets a test put any report, good or bad, into the pipeline.
class ScriptedSensor : public SensorModel {
 public:
  explicit ScriptedSensor(std::vector<ContactReport> reports) : reports_(std::move(reports)) {}
  void sense(const Pose2& pose, Rng& rng, std::vector<ContactReport>& out) override {
    for (ContactReport r : reports_) {
      r.robot = pose;
      r.r += rng.normal(0.0, extra_sigma);
      out.push_back(r);
    }
  }
  const std::vector<WhiskerMount>& mounts() const override { return mounts_; }
  double extra_sigma = 0.0;

 private:
  std::vector<ContactReport> reports_;
  std::vector<WhiskerMount> mounts_ = defaultWhiskerArray();
};

ContactReport report(int whisker, double r, double phi) {
  ContactReport c;
  c.whisker = whisker;
  c.r = r;
  c.phi = phi;
  return c;
}
}  // namespace

TEST_CASE("Pipeline: non-finite and absurd reports are counted and never reach the map",
          "[mapping]") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  ScriptedSensor sensor({report(0, nan, 0.0), report(1, 0.1, inf), report(2, 1.0, 0.0),
                         report(9, 0.1, 0.0), report(3, 0.12, 1.0)});
  const std::vector<Pose2> poses = {{1, 1, 0}, {1.5, 1, 0}, {2, 1, 0}};
  const Map map = runMapping(sensor, poses, 0, {}).value();
  CHECK(map.stats.rejected_reports == 4 * 3);  // NaN r, infinite phi, r = 7 lengths, bad index
  CHECK(map.stats.shapelets == 3);             // the one good report per pose
  for (const Shapelet& s : map.shapelets)
    CHECK((std::isfinite(s.x) && std::isfinite(s.y) && std::isfinite(s.phi)));
}

TEST_CASE("Pipeline: extreme noise gives a valid, possibly empty, map", "[mapping]") {
  ScriptedSensor sensor({report(0, 0.1, 0.3), report(1, 0.05, 1.2), report(2, 0.13, 2.0),
                         report(3, 0.02, 0.1)});
  sensor.extra_sigma = 0.5;  // 100 times the realistic sigma_r
  std::vector<Pose2> poses;
  for (int i = 0; i < 40; ++i) poses.push_back({0.5 + 0.07 * i, 1.0 + 0.03 * i, 0.4 * i});
  MappingOptions opt;
  opt.global_chains = 2;
  const Map map = runMapping(sensor, poses, 0, opt).value();
  CHECK(map.stats.poses == 40);
  for (const MapTable& t : map.tables) {
    CHECK((std::isfinite(t.pose.x) && std::isfinite(t.pose.y) && std::isfinite(t.pose.theta)));
    CHECK(t.score >= 0.0);
    CHECK(t.score <= 1.0);
  }
  for (const PoseMap& pm : map.per_pose)
    for (const MapTable& t : pm.tables) CHECK(std::isfinite(t.pose.x));
}

TEST_CASE("Pipeline: the floor under the robot at every pose is free space", "[mapping]") {
  // No contact and no whisker ray: whatever the map's free space holds came from the body.
  ScriptedSensor sensor({});
  const std::vector<Pose2> poses = {{1.0, 1.0, 0.0}, {2.0, 1.5, 1.0}};
  const auto swept = [](const Map& m, const Vec2& p) {
    const FreeSpaceLayer& f = m.free_space;
    if (f.empty()) return false;
    const Vec2 c = (p - f.origin) / f.cell;
    return f.at(static_cast<int>(std::floor(c.x())), static_cast<int>(std::floor(c.y())));
  };
  MappingOptions opt;
  const Map map = runMapping(sensor, poses, 0, opt).value();
  for (const Pose2& p : poses) {
    CHECK(swept(map, p.position()));
    CHECK(swept(map, p.position() + Vec2(0.9 * kRobotRadius, 0.0)));
    CHECK(swept(map, p.position() + Vec2(0.0, -0.9 * kRobotRadius)));
    CHECK_FALSE(swept(map, p.position() + Vec2(1.2 * kRobotRadius, 0.0)));
  }
  CHECK_FALSE(swept(map, {1.5, 1.25}));  // between the poses: teleported, nothing swept
  // The body is evidence only with negative evidence and the body sweep on.
  opt.body_sweep = false;
  CHECK(runMapping(sensor, poses, 0, opt).value().free_space.empty());
}
