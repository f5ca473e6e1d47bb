// SensingChain (crunch/session/sensing_chain.h): bridge bytes in, reports and free rays out.
// Synthetic bridge frames check the pose stamping, the assembler's time base and the
// negative-evidence sampling; the simulator's rig (its bytes, its exact pose) checks whisks at a
// table leg: reported inside a whisk, counted outside one.
#include "crunch/session/sensing_chain.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "crunch/behaviour/body_whisk.h"
#include "crunch/scene/scene.h"
#include "crunch/signal/models_io.h"
#include "crunch_sim/training.h"
#include "crunch_sim/whisker_rig.h"
#include "crunch_sim/world.h"

extern "C" {
#include "whisker/bridge_frame.h"
}

#include "support/one_table.h"

namespace {

using namespace crunch;
using session::SensingChain;
using session::SensingChainOptions;

SensingChainOptions chainOptions(const Pose2& start = {}) {
  SensingChainOptions o;
  o.pipeline = sim::physicsRigOptions(1).pipeline;
  o.mounts = defaultWhiskerArray();
  o.start = start;
  return o;
}

// The bridge bytes of tick `tick`: one frame per board (all four unless `skip` names one), a
// quiet reading with a little deterministic jitter.
std::vector<std::uint8_t> tickBytes(std::uint32_t tick, int skip = -1) {
  std::vector<std::uint8_t> out;
  for (int b = 0; b < signal::kWhiskers; ++b) {
    if (b == skip) continue;
    bridge_frame_t f{};
    f.board = static_cast<std::uint8_t>(b);
    f.seq = static_cast<std::uint16_t>(tick);
    f.tick = tick;
    f.alpha = static_cast<std::uint16_t>(8000 + (tick * 7 + static_cast<std::uint32_t>(b)) % 5);
    f.beta = static_cast<std::uint16_t>(8000 + (tick * 3 + static_cast<std::uint32_t>(b)) % 4);
    f.status = 0;
    std::uint8_t bytes[BRIDGE_FRAME_LEN];
    REQUIRE(bridge_encode(&f, bytes) == 0);
    out.insert(out.end(), bytes, bytes + BRIDGE_FRAME_LEN);
  }
  return out;
}

// The pose source of the synthetic tests: the robot creeping along +x and turning.
Pose2 poseOfTick(std::uint32_t t) {
  const double k = static_cast<double>(t);
  return {1.0 + 1e-4 * k, 2.0, 0.1 + 1e-4 * k};
}

// One table; the robot whisks in place facing its near-left leg (support/one_table.h).
Scene oneTable() { return oneTableScene(); }

// A rig facing the leg from 0.27 m, its chain carrying the shipped models.
std::unique_ptr<sim::WhiskerRig> rigAtLeg(const sim::World& world) {
  auto rig = sim::WhiskerRig::create(world, defaultWhiskerArray(), {0.85, 1.275, 0.0},
                                     sim::physicsRigOptions(1));
  REQUIRE(rig);
  auto models = signal::loadModels(std::string(CRUNCH_SOURCE_DIR) + "/models/sim_models.json");
  REQUIRE(models);
  REQUIRE(rig.value()->chain().setModels(models.value()));
  return std::move(rig).value();
}

// The in-place body whisk, then 4 s for the last episode to end; the whisk is opened on the
// chain first when `mark` is set. Returns the episodes the rig saw end.
int whisk(sim::WhiskerRig& rig, bool mark) {
  BodyWhisk whisk(rig.robot(), BodyWhisk::Options{});
  if (mark) rig.chain().beginWhisk();
  REQUIRE(whisk.startInPlace(+1));
  int episodes = 0;
  for (int n = 0; n < 40000 && !whisk.done(); ++n) {
    if (rig.step() != nullptr) ++episodes;
    REQUIRE(whisk.update(rig.contactMask()));
  }
  REQUIRE(whisk.done());
  for (int n = 0; n < 8000 && rig.pipeline().inEpisode(); ++n) {
    if (rig.step() != nullptr) ++episodes;
  }
  if (rig.finish() != nullptr) ++episodes;
  return episodes;
}

}  // namespace

TEST_CASE("SensingChain: options name the bad field", "[session]") {
  SensingChainOptions o = chainOptions();
  CHECK(o.validate());
  o.mounts.pop_back();
  CHECK_THAT(o.validate().error().message, Catch::StartsWith("mounts:"));
  o = chainOptions();
  o.pipeline.max_episode_samples = static_cast<std::int64_t>(session::kPoseHistory);
  CHECK_THAT(o.validate().error().message, Catch::Contains("max_episode_samples"));
  CHECK(!SensingChain::create(o));
}

TEST_CASE("SensingChain: each sample carries the pose given with the bytes that completed it",
          "[session]") {
  auto chain = SensingChain::create(chainOptions({0.5, 0.5, 0.0}));
  REQUIRE(chain);
  SensingChain& c = *chain.value();
  CHECK(c.poseAtSample(0).x == 0.5);  // before any sample: the start
  for (std::uint32_t t = 0; t < 500; ++t) c.feed(tickBytes(t), poseOfTick(t));
  CHECK(c.counts().samples == 500);
  CHECK(c.assemblerCounters().samples == 500);
  for (std::uint32_t t = 0; t < 500; t += 37) {
    CHECK(c.poseAtSample(t).x == poseOfTick(t).x);
    CHECK(c.poseAtSample(t).theta == poseOfTick(t).theta);
  }
  // Bytes cut anywhere: a sample completed by the second chunk takes the second chunk's pose.
  const std::vector<std::uint8_t> b = tickBytes(500);
  const std::size_t cut = 3 * BRIDGE_FRAME_LEN + 5;  // within the last board's frame
  c.feed({b.data(), cut}, poseOfTick(1000));
  CHECK(c.counts().samples == 500);
  c.feed({b.data() + cut, b.size() - cut}, poseOfTick(2000));
  CHECK(c.counts().samples == 501);
  CHECK(c.poseAtSample(500).x == poseOfTick(2000).x);
}

TEST_CASE("SensingChain: timed samples wait for their pose, live detectors do not wait",
          "[session]") {
  auto chain = SensingChain::create(chainOptions({0.5, 0.5, 0.0}));
  REQUIRE(chain);
  SensingChain& c = *chain.value();
  // The pose source: x is the time asked for, in milliseconds.
  std::vector<std::uint64_t> asked;
  auto pose_at = [&](std::uint64_t t_ns) {
    asked.push_back(t_ns);
    return Pose2{static_cast<double>(t_ns) / 1e6, 0.0, 0.0};
  };
  // 3000 ticks (1.5 s), four ticks per chunk, the chunk stamped when its last sample completed.
  for (std::uint32_t t = 0; t < 3000; t += 4) {
    std::vector<std::uint8_t> bytes;
    for (std::uint32_t k = t; k < t + 4; ++k) {
      const auto b = tickBytes(k);
      bytes.insert(bytes.end(), b.begin(), b.end());
    }
    c.feedTimed(bytes, (t + 3) * 500000ull + 7, pose_at);
  }
  CHECK(c.queued() == 3000);
  CHECK(c.counts().samples == 0);  // nothing went through the pipeline
  CHECK(asked.empty());
  CHECK(c.liveCalibrated());  // the live detectors saw every sample (1 s of rest calibrates)
  CHECK_FALSE(c.calibrated());
  // Up to 1 s: samples 0 .. 2000, each stamped 500 us after the one before.
  c.release(1000000007ull, pose_at);
  CHECK(c.counts().samples == 2001);
  CHECK(c.queued() == 999);
  REQUIRE(asked.size() == 2001);
  for (std::size_t i = 0; i < asked.size(); i += 97) CHECK(asked[i] == i * 500000ull + 7);
  CHECK(c.poseAtSample(1000).x == Approx(500.000007));
  CHECK_FALSE(c.calibrated());  // settling and 1 s of rest: 2200 samples
  c.release(~0ull, pose_at);
  CHECK(c.queued() == 0);
  CHECK(c.counts().samples == 3000);
  CHECK(c.calibrated());
}

TEST_CASE("SensingChain: a board's missing frame is filled, the 2 kHz time base kept",
          "[session]") {
  auto chain = SensingChain::create(chainOptions());
  REQUIRE(chain);
  SensingChain& c = *chain.value();
  for (std::uint32_t t = 0; t < 300; ++t) c.feed(tickBytes(t, t == 150 ? 2 : -1), poseOfTick(t));
  // Board 2's frame of tick 150 is missing: its next frame (seq 151) is preceded by a
  // placeholder, so tick 151's sample is still sample 151.
  CHECK(c.counts().samples == 300);
  CHECK(c.assemblerCounters().placeholders == 1);
  CHECK(c.decoderCounters().boards[2].lost_frames == 1);
}

TEST_CASE("SensingChain: free rays every kFreeEvery samples, at the pose of each sample's start",
          "[session]") {
  auto chain = SensingChain::create(chainOptions());
  REQUIRE(chain);
  SensingChain& c = *chain.value();
  constexpr std::uint32_t kEvery = WhiskEvidence::kFreeEvery;
  // Until the detectors have calibrated their rest they cannot say free: no rays.
  constexpr std::uint32_t kWarm = 25 * kEvery;
  for (std::uint32_t t = 0; t < kWarm; ++t) c.feed(tickBytes(t), poseOfTick(t));
  REQUIRE(c.calibrated());
  std::vector<ContactReport> reports;
  std::vector<FreeRay> rays;
  c.endWhisk(reports, rays);
  const std::size_t warm_rays = rays.size();
  CHECK(warm_rays < (kWarm / kEvery - 1) * defaultWhiskerArray().size() / 2);
  rays.clear();
  constexpr std::uint32_t kTicks = 5 * kEvery + 10;
  for (std::uint32_t t = kWarm; t < kWarm + kTicks; ++t) c.feed(tickBytes(t), poseOfTick(t));
  REQUIRE(c.contactMask() == 0);
  c.endWhisk(reports, rays);
  CHECK(reports.empty());
  // The sample started at kWarm - kEvery (accumulating at the first endWhisk) and those started
  // at kWarm, ..., kWarm + 4 kEvery; the one started at kWarm + 5 kEvery is still accumulating
  // and goes to the next whisk.
  REQUIRE(rays.size() == 6 * defaultWhiskerArray().size());
  const std::vector<WhiskerMount> mounts = defaultWhiskerArray();
  for (std::size_t i = 0; i < 6; ++i) {
    const Pose2 p = poseOfTick(static_cast<std::uint32_t>(kWarm - kEvery + i * kEvery));
    for (std::size_t w = 0; w < mounts.size(); ++w) {
      const FreeRay& r = rays[i * mounts.size() + w];
      CHECK((r.a - p.toWorld(mounts[w].base)).norm() < 1e-12);
      CHECK((r.b - r.a).norm() == Approx(mounts[w].length));
    }
  }
  CHECK(c.counts().whisks == 2);
  rays.clear();
  c.endWhisk(reports, rays);  // nothing new sampled
  CHECK(rays.empty());
}

TEST_CASE("SensingChain: with negative evidence off it keeps no samples and gives no free rays",
          "[session]") {
  SensingChainOptions options = chainOptions();
  options.negative_evidence = false;
  auto chain = SensingChain::create(options);
  REQUIRE(chain);
  SensingChain& c = *chain.value();
  constexpr std::uint32_t kTicks = 40 * WhiskEvidence::kFreeEvery;
  for (std::uint32_t t = 0; t < kTicks; ++t) c.feed(tickBytes(t), poseOfTick(t));
  REQUIRE(c.calibrated());
  REQUIRE(c.contactMask() == 0);
  std::vector<ContactReport> reports;
  std::vector<FreeRay> rays;
  c.endWhisk(reports, rays);
  CHECK(rays.empty());
  CHECK(reports.empty());
  CHECK(c.counts().samples == kTicks);  // it still senses every sample
}

TEST_CASE("SensingChain: the simulator's whisk at a leg is reported within a whisk only",
          "[session]") {
  const Scene scene = oneTable();
  auto world = sim::World::build(scene);

  SECTION("within a whisk: reports at the pose of their peak, near the leg") {
    auto rig = rigAtLeg(*world);
    session::SensingChain& c = rig->chain();
    REQUIRE(c.calibrated());
    const int episodes = whisk(*rig, true);
    CHECK(episodes >= 1);
    CHECK(c.inWhisk());
    CHECK(c.reportedMask() != 0);
    std::vector<ContactReport> reports;
    std::vector<FreeRay> rays;
    c.endWhisk(reports, rays);
    CHECK_FALSE(c.inWhisk());
    CHECK(c.counts().episodes == static_cast<std::uint64_t>(episodes));
    CHECK(c.counts().roaming_episodes == 0);
    REQUIRE(!reports.empty());
    CHECK(c.counts().reports == static_cast<int>(reports.size()));
    CHECK(!rays.empty());
    const std::vector<WhiskerMount> mounts = defaultWhiskerArray();
    for (const ContactReport& r : reports) {
      // In place: every pose of the whisk is at the start position.
      CHECK(std::hypot(r.robot.x - 0.85, r.robot.y - 1.275) < 1e-9);
      const WhiskerMount& m = mounts.at(static_cast<std::size_t>(r.whisker));
      const double dir = r.robot.theta + m.bearing;
      const Vec2 at = r.robot.toWorld(m.base) + r.r * Vec2{std::cos(dir), std::sin(dir)};
      double d = 1e9;
      for (const OrientedRect& leg : scene.tables[0].legs()) {
        d = std::min(d, closestOnPerimeter(leg, at).distance);
      }
      CHECK(d < 0.06);  // the straight-whisker point; the bent whisker touched nearer
    }
  }
  SECTION("outside a whisk: counted as roaming, not reported") {
    auto rig = rigAtLeg(*world);
    session::SensingChain& c = rig->chain();
    const int episodes = whisk(*rig, false);
    CHECK(episodes >= 1);
    CHECK(c.reportedMask() == 0);
    std::vector<ContactReport> reports;
    std::vector<FreeRay> rays;
    c.endWhisk(reports, rays);
    CHECK(reports.empty());
    CHECK(c.counts().episodes == 0);
    CHECK(c.counts().roaming_episodes == static_cast<std::uint64_t>(episodes));
  }
}
