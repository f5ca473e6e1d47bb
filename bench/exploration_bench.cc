// Google Benchmark targets for the exploration policies' decision time (issue 14: infogain
// <= 50 ms per whisk on one core). Results and how to run them: docs/BENCHMARKS.md
// ("Exploration: decision time").
//
// The state is the default arena mid-run: the first 80 reachable poses of its 10x10x4 grid
// (the bottom two rows of positions) sensed by RaySensorModel with realistic noise, fed to a
// Mapper and a KnownSpace (free rays, contacts, the body), then 16 posterior draws
// (Mapper::drawSamples, beta = 1/7.5, 4 sweeps apart). Built once, not timed.
//   BM_InfogainDecision   one InfogainPolicy::next: candidates (0.10 m lattice x 8 headings
//                         over reachable cells + leg-aimed poses), 16 predictions each, MI.
//   BM_InfogainDecisionTablePrior  the same with InfogainOptions::table_prior on.
//   BM_HiddenLegWeights   hiddenLegWeights over the KnownSpace (part of every infogain decision).
//   BM_EntropyDecision    one EntropyPolicy::next (paper §2.9) on the same state.
//   BM_DistanceField      the baseline in the same run: the one Dijkstra search every
//                         decision needs before any policy scores (the loop builds it).
#include <benchmark/benchmark.h>

#include <memory>
#include <vector>

#include "crunch/exploration/entropy_policy.h"
#include "crunch/exploration/infogain_policy.h"
#include "crunch/mapping/mapper.h"
#include "crunch/scene/scene.h"
#include "crunch_sim/ray_sensor.h"
#include "crunch_sim/world.h"

namespace {

using namespace crunch;
using namespace crunch::exploration;

struct MidRun {
  Scene scene = defaultArena();
  std::vector<WhiskerMount> mounts = defaultWhiskerArray();
  KnownSpace known{{0.0, 0.0}, {4.0, 4.0}, 0.05};
  PlannerOptions planner;
  ModelParams model;
  std::vector<MapSample> samples;
  Pose2 robot;
  int whisks = 0;
  std::unique_ptr<Costmap> costmap;
  std::unique_ptr<DistanceField> travel;

  MidRun() {
    const auto world = sim::World::build(scene);
    sim::RaySensorModel sensor(*world, mounts, NoiseRegime::realistic(), {});
    MappingOptions mo;
    mo.seed = 1;
    Mapper mapper(mounts, {0.0, 0.0}, {4.0, 4.0}, mo);
    Rng rng(1);
    int skipped = 0;
    const std::vector<Pose2> poses = world->reachablePoses(scene.poses, &skipped);
    std::vector<ContactReport> reports;
    std::vector<FreeRay> rays;
    for (size_t i = 0; i < poses.size() && i < 80; ++i) {
      reports.clear();
      rays.clear();
      sensor.sense(poses[i], rng, reports);
      sensor.freeRays(rays);
      mapper.addPose(poses[i], reports, rays);
      known.markBody(poses[i].position(), kRobotRadius);
      for (const FreeRay& r : rays) known.markFreeRay(r);
      for (const ContactReport& r : reports)
        known.markContact(mounts[static_cast<size_t>(r.whisker)].pointAt(r.robot, r.r));
      robot = poses[i];
      ++whisks;
    }
    mapper.drawSamples(16, 1.0 / 7.5, 4, samples);
    costmap = std::make_unique<Costmap>(known, planner);
    travel = std::make_unique<DistanceField>(*costmap, robot.position());
  }
  ExploreState state() const {
    return ExploreState{robot, known, *costmap, *travel, samples, mounts, model, {}, whisks, 0.0};
  }
};

MidRun& midRun() {
  static MidRun m;
  return m;
}

void BM_InfogainDecision(benchmark::State& st) {
  MidRun& m = midRun();
  const ExploreState s = m.state();
  size_t candidates = 0;
  double score = 0.0;
  for (auto _ : st) {
    Rng rng(1);  // every iteration the same decision (the draws' orphans completed alike)
    InfogainPolicy p(PolicyOptions{});
    const Decision d = p.next(s, rng);
    candidates = p.lastCandidates().size();
    score = d.score;
    benchmark::DoNotOptimize(d);
  }
  st.counters["candidates"] = static_cast<double>(candidates);
  st.counters["draws"] = static_cast<double>(m.samples.size());
  st.counters["bits_per_m"] = score;
}
BENCHMARK(BM_InfogainDecision)->Unit(benchmark::kMillisecond);

// The same decision with each unswept cell weighted by the tables that could hide there
// (InfogainOptions::table_prior on).
void BM_InfogainDecisionTablePrior(benchmark::State& st) {
  MidRun& m = midRun();
  const ExploreState s = m.state();
  InfogainOptions io;
  io.table_prior = true;
  double score = 0.0;
  for (auto _ : st) {
    Rng rng(1);
    InfogainPolicy p(PolicyOptions{}, io);
    const Decision d = p.next(s, rng);
    score = d.score;
    benchmark::DoNotOptimize(d);
  }
  st.counters["bits_per_m"] = score;
}
BENCHMARK(BM_InfogainDecisionTablePrior)->Unit(benchmark::kMillisecond);

// hiddenLegWeights alone on the mid-run KnownSpace (the model's configurations built once per
// call, as a decision does).
void BM_HiddenLegWeights(benchmark::State& st) {
  MidRun& m = midRun();
  std::vector<float> w;
  for (auto _ : st) {
    hiddenLegWeights(m.known, hiddenTableOffsets(m.model, m.known.cell()), w);
    benchmark::DoNotOptimize(w.data());
  }
}
BENCHMARK(BM_HiddenLegWeights)->Unit(benchmark::kMillisecond);

void BM_EntropyDecision(benchmark::State& st) {
  MidRun& m = midRun();
  const ExploreState s = m.state();
  Rng rng(1);
  for (auto _ : st) {
    EntropyPolicy p(PolicyOptions{});
    benchmark::DoNotOptimize(p.next(s, rng));
  }
}
BENCHMARK(BM_EntropyDecision)->Unit(benchmark::kMillisecond);

void BM_DistanceField(benchmark::State& st) {
  MidRun& m = midRun();
  for (auto _ : st) {
    DistanceField f(*m.costmap, m.robot.position());
    benchmark::DoNotOptimize(f.to(m.robot.position()));
  }
}
BENCHMARK(BM_DistanceField)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
