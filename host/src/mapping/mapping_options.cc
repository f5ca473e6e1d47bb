#include "crunch/mapping/mapping_options.h"

#include <algorithm>

#include "crunch/core/range_check.h"

namespace crunch {

Status MappingOptions::validate() const {
  const Status checks[] = {within("model", model.validate()),
                           within("sampler", sampler.validate()),
                           within("fuse", fuse.validate()),
                           checkCount("working_memory", working_memory, 1, 1000),
                           checkCount("global_sweeps", global_sweeps, 0, 1000),
                           checkCount("global_chains", global_chains, 1, 256),
                           checkCount("pool_steps", pool_steps, 1,
                                      std::max(1, sampler.schedule_steps))};
  for (const Status& s : checks) {
    if (!s) return s;
  }
  return okStatus();
}

}  // namespace crunch
