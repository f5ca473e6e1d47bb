// RobotSession (host/include/crunch/session/robot_session.h) at the chunk level, in process: the simulated robot's
// bridge bytes and OI sensor packets as chunks, marks around an in-place body whisk at a table
// leg, recorded by one session and replayed by another. (The hil tests run the same path through
// real USB and a pty; this one runs under the sanitizers too.)
#include "crunch/session/robot_session.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "crunch/behaviour/body_whisk.h"
#include "crunch/io/create_oi.h"
#include "crunch/io/recording.h"
#include "crunch/mapping/map_io.h"
#include "crunch/scene/scene.h"
#include "crunch/signal/models_io.h"
#include "crunch_sim/training.h"
#include "crunch_sim/whisker_rig.h"
#include "crunch_sim/world.h"
#include "support/one_table.h"
#include "support/temp_dir.h"

namespace {

using namespace crunch;

// One table; the robot whisks in place facing its near-left leg (support/one_table.h).
Scene oneTable() { return oneTableScene(); }

session::RobotSessionOptions sessionOptions(const Pose2& start) {
  auto models = signal::loadModels(std::string(CRUNCH_SOURCE_DIR) + "/models/sim_models.json");
  REQUIRE(models);
  session::RobotSessionOptions o;
  o.models = models.value();
  o.pipeline = sim::physicsRigOptions(1).pipeline;
  o.mounts = defaultWhiskerArray();
  o.mapping.seed = 3;
  o.mapping.global_chains = 2;
  o.start = start;
  o.area_hi = {3.0, 3.0};
  return o;
}

// `n` ticks of the rig's bridge bytes into the session, one chunk each.
void steps(sim::WhiskerRig& rig, session::RobotSession& session, int n) {
  io::Chunk chunk;
  for (int i = 0; i < n; ++i) {
    (void)rig.step();
    chunk.assign(io::StreamId::kBridge, 1, rig.lastTickBytes());
    REQUIRE(session.handle(chunk));
  }
}

// Feeds `session` what the robot would send while `rig` does an in-place whisk: one bridge chunk
// per 1 ms (two ticks), an OI stream packet (bumps, distance, angle, mode) per 15 ms from the
// rig's odometry, whisk start/end marks.
void whiskThroughSession(sim::WhiskerRig& rig, session::RobotSession& session) {
  sim::WhiskeredRobot& robot = rig.robot();
  BodyWhisk::Options wopt;
  BodyWhisk whisk(robot, wopt);
  io::Chunk chunk;
  std::vector<std::uint8_t> bytes;
  Pose2 last = robot.odometry();
  double angle_carry_deg = 0.0, dist_carry_mm = 0.0;
  double next_packet = robot.now();
  std::uint64_t t_ns = 1;
  REQUIRE(session.beginWhisk(t_ns));
  REQUIRE(whisk.startInPlace(+1));
  for (int n = 0; n < 40000 && !whisk.done(); ++n) {
    (void)rig.step();
    const auto tick = rig.lastTickBytes();
    bytes.insert(bytes.end(), tick.begin(), tick.end());
    t_ns += 500000;
    if (n % 2 == 1) {
      chunk.assign(io::StreamId::kBridge, t_ns, bytes);
      REQUIRE(session.handle(chunk));
      bytes.clear();
    }
    if (robot.now() >= next_packet) {
      next_packet += io::oi::kStreamPeriod;
      const Pose2 p = robot.odometry();
      const double turned = wrapPi(p.theta - last.theta) * 180.0 / kPi + angle_carry_deg;
      const double moved = std::hypot(p.x - last.x, p.y - last.y) * 1000.0 + dist_carry_mm;
      // Whole units, the remainder carried, as the Create (and sim/create_emulator.cc) does.
      const int deg = static_cast<int>(std::trunc(turned));
      const int mm = static_cast<int>(std::trunc(moved));
      angle_carry_deg = turned - deg;
      dist_carry_mm = moved - mm;
      last = p;
      io::oi::SensorFrame f;
      f.set(io::oi::kBumpsWheelDrops, 0);
      f.set(io::oi::kDistance, mm);
      f.set(io::oi::kAngle, deg);
      f.set(io::oi::kOiMode, 2);
      std::array<std::uint8_t, 64> packet{};
      const std::size_t len =
          io::oi::encodeStreamPacket(io::oi::kCreateBaseStream, f, true, packet);
      chunk.assign(io::StreamId::kCreate, t_ns, {packet.data(), len});
      REQUIRE(session.handle(chunk));
    }
    REQUIRE(whisk.update(session.contactMask()));
  }
  REQUIRE(whisk.done());
  steps(rig, session, 8000);  // let the last episode end, as the robot backs clear
  REQUIRE(session.endWhisk(t_ns));
}

}  // namespace

TEST_CASE("RobotSession: a whisk at a leg is reported, recorded, and replays to the same map",
          "[app]") {
  const Scene scene = oneTable();
  auto world = sim::World::build(scene);
  // Facing the table's near-left leg (1.1 .. 1.15, 1.25 .. 1.3) from 0.27 m.
  const Pose2 start{0.85, 1.275, 0.0};
  auto rig = sim::WhiskerRig::create(*world, defaultWhiskerArray(), start,
                                     sim::physicsRigOptions(1));
  REQUIRE(rig);
  TempDir dir;
  const std::string path = dir.file("run.crec");
  auto created = session::RobotSession::create(sessionOptions(start));
  REQUIRE(created);
  session::RobotSession& live = *created.value();
  auto writer = io::RecordingWriter::create(path, "{\"test\":1}");
  REQUIRE(writer);
  live.setRecorder(writer.value().get());

  steps(*rig.value(), live, 2400);  // the session's detectors need 1 s of rest first
  REQUIRE(live.calibrated());
  io::Chunk chunk;
  whiskThroughSession(*rig.value(), live);
  REQUIRE(writer.value()->close());

  const auto& c = live.counts();
  CHECK(c.whisks == 1);
  CHECK(c.episodes >= 1);
  CHECK(c.reports >= 1);
  CHECK(live.decoderCounters().crc_failures == 0);
  CHECK(live.tracker().counters().stream.checksum_failures == 0);
  // The odometry from the OI packets follows the simulator's pose.
  const Pose2 truth = rig.value()->robot().odometry();
  CHECK(std::hypot(live.pose().x - truth.x, live.pose().y - truth.y) < 0.005);
  CHECK(std::abs(wrapPi(live.pose().theta - truth.theta)) < 1.0 * kPi / 180.0);
  const Map map = live.finish();
  REQUIRE(!map.shapelets.empty());
  for (const Shapelet& s : map.shapelets) {
    // On the leg's outline. Each sample's pose is the odometry of its moment, interpolated
    // between the OI packets' whole-degree steps (odometry_track.h): measured 2.9 and 1.1 mm, as
    // the physics path with exact poses (docs/SIGNAL.md). Holding each packet's pose, as before,
    // put these contacts 9.5 and 10.5 mm off.
    double d = 1e9;
    for (const OrientedRect& leg : scene.tables[0].legs()) {
      d = std::min(d, closestOnPerimeter(leg, Vec2{s.x, s.y}).distance);
    }
    INFO("shapelet (" << s.x << ", " << s.y << ") from the leg's outline " << d << " m");
    CHECK(d < 0.005);
  }

  // Replay: the same records, the same order, the same map.
  auto reader = io::RecordingReader::open(path);
  REQUIRE(reader);
  CHECK(reader.value()->metadata() == "{\"test\":1}");
  auto again = session::RobotSession::create(sessionOptions(start));
  REQUIRE(again);
  io::RecordingReader::Next next;
  while ((next = reader.value()->next(chunk)) == io::RecordingReader::Next::kRecord) {
    REQUIRE(again.value()->handle(chunk));
  }
  CHECK(next == io::RecordingReader::Next::kEnd);
  CHECK(again.value()->counts().reports == c.reports);
  CHECK(again.value()->counts().samples == c.samples);
  const Map replayed = again.value()->finish();
  CHECK(mapToJson(replayed) == mapToJson([&] {
          Map m = map;
          m.stats.wall_s = replayed.stats.wall_s;  // the only field that is the clock's
          return m;
        }()));
}

TEST_CASE("RobotSession: contacts outside a whisk are counted, not reported", "[app]") {
  const Scene scene = oneTable();
  auto world = sim::World::build(scene);
  const Pose2 start{0.85, 1.275, 0.0};
  auto rig = sim::WhiskerRig::create(*world, defaultWhiskerArray(), start,
                                     sim::physicsRigOptions(1));
  REQUIRE(rig);
  auto created = session::RobotSession::create(sessionOptions(start));
  REQUIRE(created);
  session::RobotSession& session = *created.value();
  steps(*rig.value(), session, 2400);
  io::Chunk chunk;
  // The same sweep, but no whisk-start mark: a robot turning, not whisking.
  sim::WhiskeredRobot& robot = rig.value()->robot();
  BodyWhisk whisk(robot, BodyWhisk::Options{});
  REQUIRE(whisk.startInPlace(+1));
  for (int n = 0; n < 40000 && !whisk.done(); ++n) {
    (void)rig.value()->step();
    chunk.assign(io::StreamId::kBridge, 1, rig.value()->lastTickBytes());
    REQUIRE(session.handle(chunk));
    REQUIRE(whisk.update(session.contactMask()));
  }
  steps(*rig.value(), session, 8000);
  REQUIRE(session.endWhisk(2));
  CHECK(session.counts().roaming_episodes >= 1);
  CHECK(session.counts().episodes == 0);
  CHECK(session.counts().reports == 0);
}

TEST_CASE("RobotSession: a whisker array that is not four whiskers is an error", "[app]") {
  session::RobotSessionOptions o = sessionOptions({});
  o.mounts.pop_back();
  CHECK(!session::RobotSession::create(o));
}
