#include "sweep_merge.h"

#include <algorithm>
#include <ostream>

#include "crunch/mapping/sweep.h"

namespace crunch::app {

int runSweepMerge(const std::vector<std::string>& dirs, const std::string& out_dir,
                  std::ostream& out, std::ostream& err) {
  auto rows = mergeSweepShards(dirs);
  if (!rows) {
    err << "crunchhost sweep-merge: " << rows.error().message << "\n";
    return 2;
  }
  if (Status s = writeSweepFiles(rows.value(), out_dir); !s) {
    err << "crunchhost: " << s.error().message << "\n";
    return 1;
  }
  out << "merged " << dirs.size() << " shards of grid " << rows.value().front().grid << ": "
      << rows.value().size() << " rows; wrote " << out_dir << "/{sweep.csv,sweep.json"
      << (std::any_of(rows.value().begin(), rows.value().end(),
                      [](const SweepRow& r) { return r.explore != "none"; })
              ? ",curves.csv"
              : "")
      << "}\n";
  return 0;
}

}  // namespace crunch::app
