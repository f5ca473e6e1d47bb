// Google Benchmark for FreeSpaceGrid (crunch/blackboard/free_space.h, issue 15): the negative-
// evidence look-up the sampler makes for every leg and table term, against the brute-force scan
// it replaced (test/blackboard/free_space_scan.h) in the same run. Results: docs/BENCHMARKS.md.
//
// The grid: every free ray of the default arena's 320 reachable poses, sensed by RaySensorModel
// with realistic noise, in a grid over the arena (built once, not timed). The queries, 4096 per
// iteration, drawn once:
//   legs     leg cores near the scene's real legs (centre within 5 cm, any angle): where the
//            sampler's births and moves put them, at the edge of swept space;
//   uniform  anywhere in the arena, any angle.
// Arg: leg side in mm (50: the paper's leg, core 2 cm; 80: the rooms model's largest, core 5 cm);
// margin 15 mm (ModelParams::free_margin).
//   BM_MaxInSquareScan  the reference scan (the baseline)
//   BM_MaxInSquare      the look-up
//   BM_AddRay           every ray of the run into a fresh grid (the grid's construction is
//                       BM_GridConstruct, in the same run, to subtract)
#include <benchmark/benchmark.h>

#include <vector>

#include "blackboard/free_space_scan.h"
#include "crunch/blackboard/free_space.h"
#include "crunch/core/rng.h"
#include "crunch/scene/scene.h"
#include "crunch_sim/ray_sensor.h"
#include "crunch_sim/world.h"

namespace {

using namespace crunch;

constexpr double kMargin = 0.015;
constexpr int kQueries = 4096;

struct Run {
  Scene scene = defaultArena();
  Vec2 lo{-0.1, -0.1}, hi{4.1, 4.1};
  std::vector<FreeRay> rays;
  FreeSpaceGrid grid{lo, hi};
  std::vector<Pose2> legs_queries, uniform_queries;

  Run() {
    const auto world = sim::World::build(scene);
    const std::vector<WhiskerMount> mounts = defaultWhiskerArray();
    sim::RaySensorModel sensor(*world, mounts, NoiseRegime::realistic(), {});
    Rng rng(1);
    int skipped = 0;
    std::vector<ContactReport> reports;
    for (const Pose2& p : world->reachablePoses(scene.poses, &skipped)) {
      reports.clear();
      sensor.sense(p, rng, reports);
      sensor.freeRays(rays);
    }
    for (const FreeRay& r : rays) grid.addRay(r);
    Rng q(2);
    std::vector<Vec2> leg_centres;
    for (const TableSpec& t : scene.tables)
      for (const OrientedRect& l : t.legs()) leg_centres.push_back(l.pose.position());
    for (int i = 0; i < kQueries; ++i) {
      const Vec2 c = leg_centres[q.below(static_cast<uint32_t>(leg_centres.size()))];
      legs_queries.push_back(
          {c.x() + q.uniform(-0.05, 0.05), c.y() + q.uniform(-0.05, 0.05), q.uniform(-kPi, kPi)});
      uniform_queries.push_back(
          {q.uniform(0.0, scene.width), q.uniform(0.0, scene.depth), q.uniform(-kPi, kPi)});
    }
  }
};

const Run& run() {
  static const Run r;
  return r;
}

template <bool kScan>
void query(benchmark::State& state, const std::vector<Pose2>& poses) {
  const FreeSpaceGrid& g = run().grid;
  const double side = 1e-3 * static_cast<double>(state.range(0));
  long long sum = 0, nonzero = 0;
  for (auto _ : state) {
    for (const Pose2& p : poses) {
      const int m = kScan ? test::scanMaxInSquare(g, p, side, kMargin)
                          : g.maxInSquare(p, side, kMargin);
      sum += m;
      nonzero += m > 0;
    }
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<long long>(poses.size()));
  state.counters["nonzero_frac"] =
      static_cast<double>(nonzero) / static_cast<double>(state.iterations() * poses.size());
}

void BM_MaxInSquareScan_legs(benchmark::State& s) { query<true>(s, run().legs_queries); }
void BM_MaxInSquare_legs(benchmark::State& s) { query<false>(s, run().legs_queries); }
void BM_MaxInSquareScan_uniform(benchmark::State& s) { query<true>(s, run().uniform_queries); }
void BM_MaxInSquare_uniform(benchmark::State& s) { query<false>(s, run().uniform_queries); }
BENCHMARK(BM_MaxInSquareScan_legs)->ArgName("side_mm")->Arg(50)->Arg(80);
BENCHMARK(BM_MaxInSquare_legs)->ArgName("side_mm")->Arg(50)->Arg(80);
BENCHMARK(BM_MaxInSquareScan_uniform)->ArgName("side_mm")->Arg(50)->Arg(80);
BENCHMARK(BM_MaxInSquare_uniform)->ArgName("side_mm")->Arg(50)->Arg(80);

void BM_GridConstruct(benchmark::State& state) {
  const Run& r = run();
  for (auto _ : state) {
    FreeSpaceGrid g(r.lo, r.hi);
    benchmark::DoNotOptimize(g.rays());
  }
}
BENCHMARK(BM_GridConstruct)->Unit(benchmark::kMicrosecond);

void BM_AddRay(benchmark::State& state) {
  const Run& r = run();
  for (auto _ : state) {
    FreeSpaceGrid g(r.lo, r.hi);
    for (const FreeRay& ray : r.rays) g.addRay(ray);
    benchmark::DoNotOptimize(g.rays());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<long long>(r.rays.size()));
  state.counters["rays"] = static_cast<double>(r.rays.size());
}
BENCHMARK(BM_AddRay)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
