#include "crunch/mapping/mapping_options.h"

#include <algorithm>
#include <cmath>

#include "crunch/core/range_check.h"

namespace crunch {

ModelParams defaultMappingModel() {
  ModelParams p;
  p.objects = ObjectModel::kWalls;
  return p;
}

Status MappingOptions::validate() const {
  const Status checks[] = {within("model", model.validate()),
                           within("sampler", sampler.validate()),
                           within("fuse", fuse.validate()),
                           checkCount("working_memory", working_memory, 1, 1000),
                           checkCount("global_sweeps", global_sweeps, 0, 1000),
                           checkCount("global_chains", global_chains, 1, 256),
                           checkRange("global_prime_explained", global_prime_explained, 0.0, 1.0),
                           checkCount("threads", threads, 0, 256),
                           checkCount("pool_steps", pool_steps, 1,
                                      std::max(1, sampler.schedule_steps)),
                           checkCount("marginal_steps", marginal_steps, 1,
                                      std::max(1, sampler.schedule_steps)),
                           checkRange("marginal_keep", marginal_keep, 0.0, 0.999999)};
  for (const Status& s : checks) {
    if (!s) return s;
  }
  if (room) {
    const auto& [lo, hi] = *room;
    if (!(std::isfinite(lo.x()) && std::isfinite(lo.y()) && std::isfinite(hi.x()) &&
          std::isfinite(hi.y()) && lo.x() < hi.x() && lo.y() < hi.y()))
      return Error{"room: its corners must be finite, the first below and left of the second"};
  }
  return okStatus();
}

Result<ChainFusion> chainFusionByName(const std::string& name) {
  if (name == "vote") return ChainFusion::kVote;
  if (name == "pool") return ChainFusion::kPool;
  if (name == "marginal") return ChainFusion::kMarginal;
  return Error{"chain_fusion: unknown fusion '" + name + "' (expected vote, pool or marginal)"};
}

const char* chainFusionName(ChainFusion f) {
  switch (f) {
    case ChainFusion::kPool: return "pool";
    case ChainFusion::kMarginal: return "marginal";
    case ChainFusion::kVote: break;
  }
  return "vote";
}

void useInPlaceWhiskFusion(MappingOptions& options, bool chain_fusion_given,
                           bool global_chains_given) {
  if (!chain_fusion_given) options.chain_fusion = ChainFusion::kPool;
  if (!global_chains_given) options.global_chains = kInPlaceGlobalChains;
}

}  // namespace crunch
