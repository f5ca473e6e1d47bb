#include "crunch_sim/sweep_run.h"

#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <mutex>
#include <string>
#include <thread>

#include "crunch/core/parallel.h"
#include "crunch_sim/sim_run.h"

namespace crunch::sim {

namespace {

long peakRssKib() {
  rusage u{};
  if (getrusage(RUSAGE_SELF, &u) != 0) return -1;
  return u.ru_maxrss;  // Linux: KiB
}

// Every World query of the process: this ODE build keeps its collision scratch global
// (world.h), and each World reuses its own scratch geoms.
std::mutex g_world_mutex;

// The run's curve in the sweep's own type (mapping cannot include exploration.h).
std::vector<SweepCurvePoint> sweepCurve(const exploration::ExplorationReport& report) {
  std::vector<SweepCurvePoint> curve;
  curve.reserve(report.curve.size());
  for (const exploration::CurvePoint& c : report.curve)
    curve.push_back({c.travel_m, c.whisks, c.recall, c.precision, c.f1});
  return curve;
}

SweepRow runPoint(const SweepGrid& g, const std::vector<SimScene>& scenes, size_t index,
                  const SweepShard& shard, int threads) {
  const auto t0 = std::chrono::steady_clock::now();
  const SweepPoint p = g.pointAt(index);
  SimRunOptions o;
  o.sensor = SensorKind::kGaussian;
  o.noise = g.noises[p.noise];
  o.seed = p.seed;
  o.mapping = g.mappingOptions(p);
  o.mapping.threads = threads;  // never changes the row (global_chain.h)
  // The grid's fusion as given (vote unless --chain-fusion): the gaussian sensor's default.
  o.chain_fusion_given = true;
  o.global_chains_given = true;
  o.world_mutex = &g_world_mutex;
  auto explore = sweepExploreOptions(g, p.explore);
  if (!explore) throw std::runtime_error(explore.error().message);  // validated before
  o.explore = explore.value();
  auto run = runSimulation(scenes[p.scene], o);
  if (!run) throw std::runtime_error(run.error().message);  // the grid validated every point
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  SweepRow row = sweepRow(g, index, shard, run.value().map.stats, run.value().evaluation, wall,
                          peakRssKib());
  if (o.explore) {
    if (!run.value().exploration)
      throw std::runtime_error("--explore " + p.explore + ": the run reported no exploration");
    const exploration::ExplorationReport& ex = *run.value().exploration;
    row.travel_m = ex.travel_m;
    row.whisks = ex.whisks;
    row.curve = sweepCurve(ex);
  }
  return row;
}

}  // namespace

Result<std::optional<exploration::ExploreOptions>> sweepExploreOptions(const SweepGrid& g,
                                                                       const std::string& explore) {
  if (explore == "none") return std::optional<exploration::ExploreOptions>{};
  auto kind = exploration::explorePolicyByName(explore);
  if (!kind) return kind.error();
  exploration::ExploreOptions e;
  e.policy = kind.value();
  e.travel_budget_m = g.travel_budget_m;
  e.whisk_budget = g.whisk_budget;
  if (Status s = e.validate(); !s) return s.error();
  return std::optional<exploration::ExploreOptions>{e};
}

Status validateSweepExplore(const SweepGrid& g) {
  for (const std::string& e : g.explores)
    if (auto o = sweepExploreOptions(g, e); !o) return o.error();
  return okStatus();
}

Result<SweepRunResult> runSweepPoints(const SweepGrid& g, const SweepShard& shard, int jobs,
                                      const std::function<void(size_t, size_t)>& progress) {
  if (Status s = validateSweepExplore(g); !s) return s.error();
  std::vector<SimScene> scenes;
  for (const SweepScene& s : g.scenes) scenes.push_back(SimScene::build(s.scene));
  std::vector<size_t> indices;
  for (size_t i = 0; i < g.size(); ++i)
    if (shard.holds(i)) indices.push_back(i);
  jobs = std::max(1, std::min<int>(resolveThreads(jobs),
                                    static_cast<int>(std::max<size_t>(1, indices.size()))));
  // The cores the jobs leave idle go to each run's global chains.
  const int run_threads = std::max(1, hardwareThreads() / jobs);

  SweepRunResult result;
  result.jobs = jobs;
  result.rows.resize(indices.size());
  std::atomic<size_t> next{0};
  std::mutex done_mutex;
  size_t done = 0;
  std::string failure;
  auto worker = [&] {
    for (;;) {
      const size_t k = next.fetch_add(1);
      if (k >= indices.size()) return;
      SweepRow row;
      std::string what;
      try {
        row = runPoint(g, scenes, indices[k], shard, run_threads);
      } catch (const std::exception& e) {
        what = e.what();
      }
      std::lock_guard<std::mutex> lock(done_mutex);
      if (!what.empty() && failure.empty())
        failure = "grid point " + std::to_string(indices[k]) + ": " + what;
      result.rows[k] = std::move(row);
      if (progress) progress(++done, indices.size());
    }
  };
  std::vector<std::thread> threads;
  for (int t = 1; t < jobs; ++t) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();
  if (!failure.empty()) return Error{failure};
  return result;
}

}  // namespace crunch::sim
