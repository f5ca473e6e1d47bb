// Blackboard snapshots taken during a run (render/blackboard_snapshot.h): the recorder's hooks
// copy the blackboard once, at pose K, after the annealing or after temperature I, and do not
// change the map.
#include "crunch/render/blackboard_snapshot.h"

#include <catch2/catch.hpp>
#include <vector>

#include "crunch/mapping/map_io.h"
#include "crunch/mapping/run_mapping.h"

using namespace crunch;

namespace {
// Every pose reports the same two contacts, in the frame of that pose: new shapelets each time.
class TwoContacts : public SensorModel {
 public:
  void sense(const Pose2& pose, Rng&, std::vector<ContactReport>& out) override {
    for (int w : {0, 2}) {
      ContactReport c;
      c.whisker = w;
      c.r = 0.1;
      c.phi = 0.3;
      c.robot = pose;
      out.push_back(c);
    }
  }
  const std::vector<WhiskerMount>& mounts() const override { return mounts_; }

 private:
  std::vector<WhiskerMount> mounts_ = defaultWhiskerArray();
};

const std::vector<Pose2> kPoses = {{1.0, 1.0, 0.0}, {1.2, 1.0, 0.5}, {1.4, 1.1, 1.0}};

MappingOptions small() {
  MappingOptions o;
  o.sampler.schedule_steps = 4;
  o.global_sweeps = 0;
  return o;
}
}  // namespace

TEST_CASE("SnapshotRecorder: the blackboard at pose K after its annealing", "[snapshot]") {
  TwoContacts sensor;
  MappingOptions o = small();
  SnapshotRecorder rec(1, std::nullopt, kPoses, defaultWhiskerArray());
  rec.install(o);
  const Map map = runMapping(sensor, kPoses, 0, o).value();
  REQUIRE(rec.snapshot());
  const BlackboardSnapshot& s = *rec.snapshot();
  CHECK(s.pose_index == 1);
  CHECK(s.robot.x == kPoses[1].x);
  CHECK(s.whiskers.size() == defaultWhiskerArray().size());
  CHECK(s.shapelets.size() == 4);  // two per pose so far
  CHECK_THAT(s.title, Catch::Contains("pose 1 (1.20, 1.00, 29 deg), annealed at T = exp(-"));
  for (const SnapshotTable& t : s.tables) CHECK(t.map);
  // The hooks only read: the same map as without them.
  const Map plain = runMapping(sensor, kPoses, 0, small()).value();
  CHECK(mapToJson(map).substr(0, mapToJson(map).find("\"stats\"")) ==
        mapToJson(plain).substr(0, mapToJson(plain).find("\"stats\"")));
}

TEST_CASE("SnapshotRecorder: after temperature I of pose K", "[snapshot]") {
  TwoContacts sensor;
  MappingOptions o = small();
  SnapshotRecorder rec(2, 1, kPoses, defaultWhiskerArray());
  rec.install(o);
  REQUIRE(runMapping(sensor, kPoses, 0, o));
  REQUIRE(rec.snapshot());
  CHECK(rec.snapshot()->pose_index == 2);
  CHECK_THAT(rec.snapshot()->title, Catch::Contains("after temperature 1 of 4 (0 hottest)"));
  for (const SnapshotTable& t : rec.snapshot()->tables) CHECK_FALSE(t.map);  // not the coldest
}
