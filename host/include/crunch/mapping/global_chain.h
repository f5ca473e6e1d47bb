// One chain of the global inference (Mapper::finish): the fused map as one inference over every
// shapelet of the run, the paper's future work of "longer-term memories of shapelets" (§4). A
// blackboard whose working memory holds every shapelet of the run and the negative evidence
// (free_space.h) is annealed with the sampler's schedule and MappingOptions::global_sweeps sweeps
// per temperature (Algorithm 1, acceptance of eq. 29); the chain's MAP (eq. 27) is its live tables
// and walls at the end, and under ChainFusion::kMarginal its tables after every sweep of the
// coldest marginal_steps temperatures are samples for posterior_marginals.h.
//
// Streams: chain c draws only from globalChainStreams(seed, n)[c], a generator of its own 2^128
// draws away from every other chain's (Rng::jump()). A chain's result therefore depends only on
// the shapelets, the negative evidence, the options, the seed and c: not on which thread runs it,
// when, or how many run beside it. Mapper::finish runs its chains on MappingOptions::threads
// threads and combines the results in chain order, so the map is the same for every thread count.
//
// Thread-safety: a GlobalChain owns its blackboard, sampler, stream and samples, and reads the
// shapelets and the free-space grid it was given (they must outlive it and not change while it
// anneals). Distinct chains may anneal() at the same time; one chain is used by one thread at a
// time. The options' per-pose hooks (SamplerOptions::after_temperature, after_sweep) are not
// called by a global chain.
//
// Allocation: the constructor sizes everything (pools for 4 hypotheses per shapelet + 64). After
// it, anneal() performs no heap allocation but, under kMarginal, the samples it appends
// (test/mapping/global_chain_alloc_test.cc counts, with the chains on two threads).
// Not copyable or movable (the sampler references the blackboard and the stream).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "crunch/blackboard/blackboard.h"
#include "crunch/blackboard/free_space.h"
#include "crunch/blackboard/sampler.h"
#include "crunch/core/rng.h"
#include "crunch/mapping/map.h"
#include "crunch/mapping/mapping_options.h"
#include "crunch/mapping/posterior_marginals.h"

namespace crunch {

// What one chain leaves for the fusion of the chains (mapper.cc).
struct ChainResult {
  std::vector<MapTable> tables;  // its MAP: live tables, each of its own size under kRooms
  std::vector<WallHyp> walls;    // its live walls (none unless ModelParams::walled())
  // kMarginal: its tables after each sampled sweep; ObjectSample::sample counts this chain's
  // samples from 0.
  std::vector<ObjectSample> samples;
  int sample_count = 0;
  long long proposals = 0;
  MoveCounts moves{};  // proposals and acceptances by move family
  int live_tables = 0;  // Blackboard::liveTables() at the end of the annealing
  int live_legs = 0;
};

// The streams of `n` chains: Rng(seed ^ a constant of the global inference) jumped 0, 1, ...,
// n - 1 times. Streams of a larger n begin with those of a smaller one.
std::vector<Rng> globalChainStreams(uint64_t seed, int n);

// The sampler's options for a global chain: options.sampler with global_sweeps sweeps per
// temperature and without the per-pose hooks.
SamplerOptions globalSamplerOptions(const MappingOptions& options);

class GlobalChain {
 public:
  // `run`: every shapelet of the run, in the run's order; `free`: the negative evidence, or null.
  GlobalChain(std::span<const Shapelet> run, const FreeSpaceGrid* free,
              const MappingOptions& options, Rng stream);
  GlobalChain(const GlobalChain&) = delete;
  GlobalChain& operator=(const GlobalChain&) = delete;

  // Runs the whole annealing schedule once (call once).
  void anneal();
  // The chain's result after anneal(). Allocates the tables and walls.
  ChainResult result();

 private:
  MappingOptions options_;
  Rng rng_;
  Blackboard board_;
  std::vector<ObjectSample> samples_;
  int sample_count_ = 0;
  Sampler sampler_;
};

}  // namespace crunch
