#include "crunch/mapping/global_chain.h"

#include <utility>

#include "crunch/mapping/identified_tables.h"
#include "crunch/mapping/mapper.h"

namespace crunch {

namespace {

// Sets the global inference's streams apart from the per-pose sampler's (Mapper: seed ^
// 0xB1ACB0A2D) and drawSamples' (seed ^ 0x5A3B1E5).
constexpr uint64_t kGlobalStreams = 0x6C0BA1C4A145ull;

// The sampler's options of a chain; under kMarginal its sweeps' tables are appended to `samples`.
SamplerOptions chainSampler(const MappingOptions& options, std::vector<ObjectSample>& samples,
                            int& count) {
  SamplerOptions so = globalSamplerOptions(options);
  if (options.chain_fusion != ChainFusion::kMarginal) return so;
  const int first = so.schedule_steps - options.marginal_steps;
  const ModelParams model = options.model;
  so.after_sweep = [&samples, &count, first, model](int step, int, double,
                                                     const Blackboard& board) {
    if (step < first) return;
    for (int32_t id = 0; id < board.tableExtent(); ++id) {
      const TableHyp& t = board.table(id);
      if (!t.alive) continue;
      // Each table at its own size under kRooms, written width >= depth as the map writes it.
      const MapTable m = model.sized() ? sizedTable(t) : modelTable(t.pose, model);
      samples.push_back({count, m.pose, {m.width, m.depth, m.leg}});
    }
    ++count;
  };
  return so;
}

}  // namespace

std::vector<Rng> globalChainStreams(uint64_t seed, int n) {
  std::vector<Rng> streams;
  Rng r(seed ^ kGlobalStreams);
  for (int c = 0; c < n; ++c) {
    streams.push_back(r);
    r.jump();
  }
  return streams;
}

SamplerOptions globalSamplerOptions(const MappingOptions& options) {
  SamplerOptions so = options.sampler;
  so.sweeps_per_temperature = options.global_sweeps;
  so.prime_explained = options.global_prime_explained;
  // Pictures of a pose's annealing part-way: not of the global chains, which may run at once.
  so.after_temperature = nullptr;
  so.after_sweep = nullptr;
  return so;
}

GlobalChain::GlobalChain(std::span<const Shapelet> run, const FreeSpaceGrid* free,
                         const MappingOptions& options, Rng stream)
    : options_(options),
      rng_(stream),
      board_(options.model, static_cast<int>(run.size()), 4 * run.size() + 64),
      sampler_(board_, chainSampler(options_, samples_, sample_count_), rng_) {
  for (const Shapelet& s : run) board_.pushShapelet(s);
  board_.setFreeSpace(free);
}

void GlobalChain::anneal() { sampler_.anneal(); }

ChainResult GlobalChain::result() {
  ChainResult r;
  if (options_.model.walled()) {
    // A table whose size or place the evidence leaves open is not one the map can report.
    identifiedTablesOf(board_, options_.fuse.size, r.tables);
  } else {
    std::vector<Pose2> found;
    sampler_.mapTables(found);
    for (const Pose2& p : found) r.tables.push_back(modelTable(p, options_.model));
  }
  if (options_.model.walled()) sampler_.mapWalls(r.walls);
  r.samples = samples_;
  r.sample_count = sample_count_;
  r.proposals = sampler_.stats().proposals;
  r.moves = sampler_.stats().by_move;
  r.live_tables = board_.liveTables();
  r.live_legs = board_.liveLegs();
  return r;
}

}  // namespace crunch
