// Taking a BlackboardSnapshot (map_render.h, paper Figs. 3-4) from a live Blackboard during a
// mapping run: `crunchhost --sim --snapshot K [--snapshot-temperature I]`.
//
// captureSnapshot copies what the picture needs (working memory, live tables and legs, the
// model's sizes) out of the blackboard. SnapshotRecorder installs the hooks of MappingOptions
// (after_pose, and SamplerOptions::after_temperature for a temperature) that copy the blackboard
// once: at pose K (0-based, in the run's order of reachable poses) after the chosen temperature
// (0 the hottest, beta = 1 ... schedule_steps - 1 the coldest; Fig. 4 is a hot one) or, without
// one, at the end of the annealing (the coldest: its live tables are MAP_t, eq. 27). A pose that
// sensed nothing new does not anneal: without a temperature its snapshot shows the blackboard as
// the last annealing left it; with one there is no snapshot.
//
// Ownership: the hooks share the recorder's state (shared_ptr), so the recorder may be moved and
// the hooks outlive it safely. Thread-safety: one run at a time, as the hooks are called.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "crunch/blackboard/blackboard.h"
#include "crunch/mapping/mapping_options.h"
#include "crunch/render/map_render.h"

namespace crunch {

// The blackboard as a picture's plain data. `at_end`: the annealing is over, so the live tables
// are MAP_t and are drawn bold (legs: those attached to a live table).
BlackboardSnapshot captureSnapshot(const Blackboard& board, int pose_index, const Pose2& robot,
                                   const std::vector<WhiskerMount>& whiskers, std::string title,
                                   bool at_end);

class SnapshotRecorder {
 public:
  // Pose K and, optionally, temperature I; `poses` the run's reachable poses (copied); `whiskers`
  // drawn with the robot.
  SnapshotRecorder(int pose, std::optional<int> temperature, std::vector<Pose2> poses,
                   std::vector<WhiskerMount> whiskers);
  // Sets options.after_pose (and options.sampler.after_temperature with a temperature),
  // replacing what was there. Reads the sampler settings for the title from `options`.
  void install(MappingOptions& options) const;
  // The snapshot, once taken.
  const std::optional<BlackboardSnapshot>& snapshot() const;

 private:
  struct State;
  std::shared_ptr<State> state_;
};

}  // namespace crunch
