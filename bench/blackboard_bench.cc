// Google Benchmark targets for the blackboard sampler and the whole simulated mapping run.
// Results and how to run them: docs/BENCHMARKS.md.
//
//   BM_SweepThroughput   Metropolis-Hastings proposals per second: working memory 7 fed from a
//                        few synthetic tables, Sampler::sweep at a fixed beta. Second arg:
//                        1 = incremental energies (the default), 0 = the reference energy path
//                        (both sides of every move evaluated afresh; issue 15's baseline,
//                        measured in the same run).
//   BM_PoseAnneal        per-pose inference latency: push one pose's shapelets (2-4), then the
//                        full annealing schedule (Sampler::anneal, 16 temperatures).
//   BM_SweepScaling      cost per proposal against the number of live hypotheses N on a floor
//                        that grows with N at constant table density (the spatial hash's point).
//   BM_LegsNear          baseline for the above: one corner look-up through the board's leg
//                        hash, a brute-force scan of every leg, and a hash with 16x the buckets.
//   BM_WholeRun          the default 400-pose crunchhost --sim run (runMapping, realistic noise).
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <ctime>
#include <memory>
#include <vector>

#include "../test/blackboard/test_builders.h"
#include "crunch/blackboard/blackboard.h"
#include "crunch/blackboard/params.h"
#include "crunch/blackboard/sampler.h"
#include "crunch/blackboard/spatial_hash.h"
#include "crunch/core/rng.h"
#include "crunch/mapping/run_mapping.h"
#include "crunch/scene/scene.h"
#include "crunch_sim/ray_sensor.h"
#include "crunch_sim/world.h"

namespace {

using crunch::Blackboard;
using crunch::ModelParams;
using crunch::Pose2;
using crunch::Rng;
using crunch::Sampler;
using crunch::SamplerOptions;
using crunch::Shapelet;
using crunch::testing::LegOf;
using crunch::testing::TableShapelets;

// Shapelets off every corner of a few tables well apart, in the order a robot walking past
// them might sense them (table by table, corner by corner).
std::vector<Shapelet> fewTablesShapelets(const ModelParams& p) {
  const Pose2 tables[] = {{1.0, 1.0, 0.3}, {2.6, 1.2, 1.1}, {1.8, 2.8, 0.0}};
  std::vector<Shapelet> out;
  for (const Pose2& t : tables)
    for (const Shapelet& s : TableShapelets(t, p, {0, 1, 2, 3})) out.push_back(s);
  return out;
}

long long liveHypotheses(const Blackboard& bb) { return bb.liveTables() + bb.liveLegs(); }

double threadCpuNs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e9 * static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec);
}

// ---------------------------------------------------------------- 1. proposals per second

// Arg: log(beta) x 10. Every 16 sweeps (one schedule's worth) the next three shapelets enter
// working memory and the board is pruned, as a new pose would do; the sweeps are what is timed
// and counted, the push and prune are cheap and stay inside the timed region.
void BM_SweepThroughput(benchmark::State& state) {
  const double beta = std::exp(static_cast<double>(state.range(0)) / 10.0);
  const ModelParams p;
  const std::vector<Shapelet> feed = fewTablesShapelets(p);
  Blackboard bb(p, 7, 4096);
  Rng rng(1);
  SamplerOptions opt;
  opt.incremental_energy = state.range(1) != 0;
  Sampler sampler(bb, opt, rng);
  size_t next = 0;
  auto push = [&](int n) {
    for (int i = 0; i < n; ++i) bb.pushShapelet(feed[next++ % feed.size()]);
  };
  push(7);
  for (int i = 0; i < 64; ++i) sampler.sweep(beta);  // warm-up: pools and hash buckets grown
  sampler.prune();

  const long long before = sampler.stats().proposals;
  long long live_sum = 0;
  int64_t i = 0;
  for (auto _ : state) {
    if (++i % 16 == 0) {
      push(3);
      sampler.prune();
    }
    sampler.sweep(beta);
    live_sum += liveHypotheses(bb);
  }
  const long long proposals = sampler.stats().proposals - before;
  state.SetItemsProcessed(proposals);
  state.counters["proposals_per_sweep"] =
      benchmark::Counter(static_cast<double>(proposals), benchmark::Counter::kAvgIterations);
  state.counters["live_hyp"] =
      benchmark::Counter(static_cast<double>(live_sum), benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_SweepThroughput)
    ->ArgNames({"log_beta_x10", "incremental"})
    ->ArgsProduct({{0, 35, 75}, {1, 0}});

// ---------------------------------------------------------------- 2. per-pose latency

// Arg: shapelets per pose. One iteration = push that many shapelets and run the full schedule,
// what runMapping does at each pose that sensed something.
void BM_PoseAnneal(benchmark::State& state) {
  const int per_pose = static_cast<int>(state.range(0));
  const ModelParams p;
  const std::vector<Shapelet> feed = fewTablesShapelets(p);
  Blackboard bb(p, 7, 4096);
  Rng rng(1);
  Sampler sampler(bb, SamplerOptions{}, rng);
  size_t next = 0;
  auto push = [&]() {
    for (int i = 0; i < per_pose; ++i) bb.pushShapelet(feed[next++ % feed.size()]);
  };
  for (int i = 0; i < 8; ++i) {  // warm-up
    push();
    sampler.anneal();
  }
  const long long before = sampler.stats().proposals;
  for (auto _ : state) {
    push();
    sampler.anneal();
  }
  const long long proposals = sampler.stats().proposals - before;
  state.SetItemsProcessed(proposals);
  state.counters["proposals_per_pose"] =
      benchmark::Counter(static_cast<double>(proposals), benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_PoseAnneal)->ArgName("shapelets")->DenseRange(2, 4)->Unit(benchmark::kMicrosecond);

// ---------------------------------------------------------------- 3. scaling with N

// A floor of tables on a square grid 1.2 m apart (constant density, so the floor's area grows
// with N), each at a pseudo-random orientation, with its four legs and eight shapelets (two off
// each leg). Each table is 1 + 4 live hypotheses, so N hypotheses take N / 5 tables.
struct Floor {
  std::unique_ptr<Blackboard> bb;
  std::vector<Pose2> tables;
};

Floor buildFloor(int n_hypotheses) {
  constexpr double kSpacing = 1.2;
  const ModelParams p;
  const int n_tables = std::max(1, n_hypotheses / 5);
  const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n_tables))));
  Rng rng(42);
  Floor f;
  for (int k = 0; k < n_tables; ++k)
    f.tables.push_back({1.0 + kSpacing * (k % side), 1.0 + kSpacing * (k / side),
                        rng.uniform(0.0, crunch::kPi)});
  std::vector<Shapelet> shapelets;
  for (const Pose2& t : f.tables)
    for (const Shapelet& s : TableShapelets(t, p, {0, 1, 2, 3})) shapelets.push_back(s);
  // Working memory holds every shapelet, so pruning would keep every true hypothesis.
  f.bb = std::make_unique<Blackboard>(p, static_cast<int>(shapelets.size()),
                                      4 * static_cast<size_t>(n_hypotheses) + 64);
  for (const Shapelet& s : shapelets) f.bb->pushShapelet(s);
  for (const Pose2& t : f.tables) {
    const int32_t id = f.bb->addTable(t);
    for (int c = 0; c < 4; ++c) f.bb->addLeg(LegOf(t, p, c), id);
  }
  return f;
}

// Arg: N. One iteration = one sweep at beta = e^7.5 (the coldest temperature), which proposes
// once per shapelet (a new leg) and once per live hypothesis.
void BM_SweepScaling(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  Floor f = buildFloor(n);
  Rng rng(7);
  Sampler sampler(*f.bb, SamplerOptions{}, rng);
  const double beta = std::exp(7.5);
  sampler.sweep(beta);  // warm-up: grows the sampler's order buffer and the pools' free lists
  const long long live_start = liveHypotheses(*f.bb);
  const long long before = sampler.stats().proposals;
  double cpu_ns = 0.0, wall_ns = 0.0;
  for (auto _ : state) {
    const double c0 = threadCpuNs();
    const auto t0 = std::chrono::steady_clock::now();
    sampler.sweep(beta);
    wall_ns += std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count();
    cpu_ns += threadCpuNs() - c0;
  }
  const long long proposals = sampler.stats().proposals - before;
  const double per = proposals > 0 ? 1.0 / static_cast<double>(proposals) : 0.0;
  state.SetItemsProcessed(proposals);
  // CPU time of this thread (robust to a busy shared machine) and wall time.
  state.counters["ns_per_proposal"] = cpu_ns * per;
  state.counters["wall_ns_per_proposal"] = wall_ns * per;
  state.counters["live_hyp"] = static_cast<double>(live_start);
  state.counters["live_hyp_end"] = static_cast<double>(liveHypotheses(*f.bb));
  state.counters["shapelets"] = f.bb->shapeletCount();
}
BENCHMARK(BM_SweepScaling)
    ->ArgName("N")
    ->Arg(100)
    ->Arg(300)
    ->Arg(1000)
    ->Arg(3000)
    ->Arg(10000)
    ->Unit(benchmark::kMicrosecond);

// Arg 0: N; arg 1, how: 0 = through the board's leg hash (Blackboard::legsNear: a SpatialHash
// of 0.1 m cells and 2^12 buckets), 1 = brute-force scan of every leg, 2 = a standalone
// SpatialHash of the same cells but 2^16 buckets holding the same legs (what a bigger or growing
// table would buy). One iteration = the legs within the corner link radius of one true corner.
// "visited" counts the ids each query hands to its callback before the exact distance test.
void BM_LegsNear(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int how = static_cast<int>(state.range(1));
  const Floor f = buildFloor(n);
  const Blackboard& bb = *f.bb;
  const ModelParams& p = bb.params();
  const double r = p.cornerLinkRadius();
  std::vector<crunch::Vec2> corners;
  for (const Pose2& t : f.tables)
    for (int c = 0; c < 4; ++c) corners.push_back(t.toWorld(p.cornerOffset(c)));
  crunch::SpatialHash big(0.1, 16);
  for (int32_t id = 0; id < bb.legExtent(); ++id)
    if (bb.leg(id).alive) big.insert(id, bb.leg(id).pose.position());
  size_t k = 0;
  int64_t found = 0, visited = 0;
  for (auto _ : state) {
    const crunch::Vec2& q = corners[k];
    k = (k + 7919) % corners.size();
    int hits = 0, seen = 0;
    auto test = [&](int32_t id) {
      const crunch::LegHyp& l = bb.leg(id);
      ++seen;
      hits += l.alive && (l.pose.position() - q).squaredNorm() <= r * r;
    };
    if (how == 1) {
      for (int32_t id = 0; id < bb.legExtent(); ++id) test(id);
    } else if (how == 2) {
      big.query(q, r, test);
    } else {
      bb.legsNear(q, r, test);
    }
    benchmark::DoNotOptimize(hits);
    found += hits;
    visited += seen;
  }
  state.counters["hits"] =
      benchmark::Counter(static_cast<double>(found), benchmark::Counter::kAvgIterations);
  state.counters["visited"] =
      benchmark::Counter(static_cast<double>(visited), benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_LegsNear)
    ->ArgNames({"N", "how"})
    ->ArgsProduct({{100, 300, 1000, 3000, 10000}, {0, 1, 2}});

// ---------------------------------------------------------------- 4. the whole default run

// The default crunchhost --sim run without file output: default arena, realistic noise, default
// MappingOptions with seed 1 (400 poses, per-pose annealing, then the global fused map of
// 4 chains x 4 sweeps per temperature). Sensing (ODE ray casts) is inside the timed region, as it
// is inside runMapping.
void BM_WholeRun(benchmark::State& state) {
  const crunch::Scene scene = crunch::defaultArena();
  const auto world = crunch::sim::World::build(scene);
  int skipped = 0;
  const std::vector<Pose2> poses = world->reachablePoses(scene.poses, &skipped);
  crunch::sim::RaySensorModel sensor(*world, crunch::defaultWhiskerArray(),
                                     crunch::NoiseRegime::realistic(), {});
  crunch::MappingOptions mopt;
  mopt.seed = 1;
  crunch::MapStats stats;
  size_t fused = 0;
  for (auto _ : state) {
    const crunch::Map map = crunch::runMapping(sensor, poses, skipped, mopt).value();
    stats = map.stats;
    fused = map.tables.size();
    benchmark::DoNotOptimize(fused);
  }
  state.counters["poses"] = stats.poses;
  state.counters["skipped"] = stats.skipped_poses;
  state.counters["shapelets"] = stats.shapelets;
  state.counters["proposals"] = static_cast<double>(stats.proposals);
  state.counters["fused_tables"] = static_cast<double>(fused);
}
BENCHMARK(BM_WholeRun)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
