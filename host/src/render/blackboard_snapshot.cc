#include "crunch/render/blackboard_snapshot.h"

#include <cstdio>

namespace crunch {

BlackboardSnapshot captureSnapshot(const Blackboard& board, int pose_index, const Pose2& robot,
                                   const std::vector<WhiskerMount>& whiskers, std::string title,
                                   bool at_end) {
  BlackboardSnapshot s;
  s.pose_index = pose_index;
  s.robot = robot;
  s.whiskers = whiskers;
  const ModelParams& m = board.params();
  s.table_width = m.table_width;
  s.table_depth = m.table_depth;
  s.leg_side = m.leg_side;
  for (int slot = 0; slot < board.workingMemoryCapacity(); ++slot)
    if (board.slotUsed(slot)) s.shapelets.push_back(board.shapelet(slot));
  for (int32_t id = 0; id < board.tableExtent(); ++id)
    if (board.table(id).alive) s.tables.push_back({board.table(id).pose, at_end});
  for (int32_t id = 0; id < board.legExtent(); ++id) {
    const LegHyp& l = board.leg(id);
    if (!l.alive) continue;
    const bool in_table = l.parent != kNone && board.table(l.parent).alive;
    s.legs.push_back({l.pose, l.side, in_table});
  }
  s.title = std::move(title);
  return s;
}

struct SnapshotRecorder::State {
  int pose = 0;
  std::optional<int> temperature;
  std::vector<Pose2> poses;
  std::vector<WhiskerMount> whiskers;
  int next_pose = 0;  // during an annealing: the pose after the last after_pose call
  std::optional<BlackboardSnapshot> snap;
};

SnapshotRecorder::SnapshotRecorder(int pose, std::optional<int> temperature,
                                   std::vector<Pose2> poses, std::vector<WhiskerMount> whiskers)
    : state_(std::make_shared<State>()) {
  state_->pose = pose;
  state_->temperature = temperature;
  state_->poses = std::move(poses);
  state_->whiskers = std::move(whiskers);
}

const std::optional<BlackboardSnapshot>& SnapshotRecorder::snapshot() const { return state_->snap; }

void SnapshotRecorder::install(MappingOptions& options) const {
  const std::shared_ptr<State> st = state_;
  const int steps = options.sampler.schedule_steps;
  const int sweeps = options.sampler.sweeps_per_temperature;
  const double log_top = options.sampler.schedule_log_top;
  auto take = [st, sweeps](int t, const Pose2& pose, const Blackboard& board, const char* when,
                           bool at_end) {
    char buf[240];
    std::snprintf(buf, sizeof buf, "pose %d (%.2f, %.2f, %.0f deg), %s, %d sweep(s) each |", t,
                  pose.x, pose.y, pose.theta * 180.0 / kPi, when, sweeps);
    st->snap = captureSnapshot(board, t, pose, st->whiskers, buf, at_end);
  };
  if (st->temperature) {
    options.after_pose = [st](int t, const Pose2&, bool, const Blackboard&) { st->next_pose = t + 1; };
    options.sampler.after_temperature = [st, take, steps](int i, double beta,
                                                          const Blackboard& board) {
      if (st->next_pose != st->pose || i != *st->temperature || st->snap) return;
      char when[120];
      std::snprintf(when, sizeof when, "after temperature %d of %d (0 hottest), beta = %.3g", i,
                    steps, beta);
      take(st->pose, st->poses[static_cast<std::size_t>(st->pose)], board, when, i == steps - 1);
    };
  } else {
    options.after_pose = [st, take, steps, log_top](int t, const Pose2& pose, bool annealed,
                                                    const Blackboard& board) {
      if (t != st->pose) return;
      char when[120];
      std::snprintf(when, sizeof when, "%s at T = exp(-%.1f), coldest of %d",
                    annealed ? "annealed" : "no new shapelet; as last annealed", log_top, steps);
      take(t, pose, board, when, true);
    };
  }
}

}  // namespace crunch
