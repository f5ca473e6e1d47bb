// Progress of the simulator modes on a terminal: a bar (with the time left where runs are long)
// on one stream, or with `json` one JSON object per line ({"event":"progress",...}).
#pragma once

#include <chrono>
#include <cstddef>
#include <iosfwd>
#include <string>

#include "crunch_sim/training.h"

namespace crunch::app {

// "5s", "3m05s", "1h02m"; "?" when not finite or negative.
std::string formatDuration(double seconds);

// --sim: poses mapped (MappingOptions::progress). JSON every 20 poses and at the end.
class PoseProgress {
 public:
  PoseProgress(std::ostream& os, bool json) : os_(os), json_(json) {}
  void operator()(int done, int total);

 private:
  std::ostream& os_;
  bool json_;
  int last_ = -1;
};

// sweep: runs done, elapsed and left (elapsed per run times the runs left). Not thread-safe: the
// caller serialises calls (runSweepPoints does).
class RunProgress {
 public:
  RunProgress(std::ostream& os, bool json, std::size_t total);
  void operator()(std::size_t done);

 private:
  std::ostream& os_;
  bool json_;
  std::size_t total_;
  std::chrono::steady_clock::time_point t0_;
};

// train: whisks done, the phase, elapsed and left, from the wall time per whisk so far.
class WhiskProgress {
 public:
  WhiskProgress(std::ostream& os, bool json);
  void operator()(const sim::TrainingProgress& p);
  double elapsed() const;

 private:
  std::ostream& os_;
  bool json_;
  std::chrono::steady_clock::time_point t0_;
};

}  // namespace crunch::app
