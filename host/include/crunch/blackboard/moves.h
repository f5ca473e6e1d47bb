// The move families of the sampler and their counts (SamplerStats::by_move, MapStats::
// global_moves): where the proposals go and which are taken, for tuning the move mix
// (docs/BENCHMARKS.md "The move mix").
#pragma once

#include <array>
#include <cstddef>

namespace crunch {

// The families of the tempered sweep's moves (Sampler::sweep).
enum class MoveKind : int {
  kPrime,          // Q(pa(S)): a leg born behind a working-memory shapelet (primeLeg)
  kWallBirth,      // a data-driven wall birth at a shapelet (proposeWallBirth)
  kWall,           // any move of a live wall (wallMove: steps, ends, split, merge, death)
  kTableDeath,     // a table's death, with or without its legs
  kChild,          // a leg born at a table's empty corner (proposeChild)
  kTablePose,      // a table's pose step (jitterTable)
  kTableSize,      // the rooms model's size and leg-side steps of a table, and its split
  kLegDeath,       // a leg's death
  kParentChange,   // a leg's parent change (sampleParent)
  kLegPose,        // a leg's pose or side step
  kParentBirth,    // a table born under a leg (proposeParent, proposeParentSized)
  kReversible,     // any kernel of sweepReversible
  kCount
};

constexpr size_t kMoveKinds = static_cast<size_t>(MoveKind::kCount);

// The family's name in report.json ("prime", "wall_birth", ...).
constexpr const char* moveKindName(MoveKind k) {
  switch (k) {
    case MoveKind::kPrime: return "prime";
    case MoveKind::kWallBirth: return "wall_birth";
    case MoveKind::kWall: return "wall";
    case MoveKind::kTableDeath: return "table_death";
    case MoveKind::kChild: return "child";
    case MoveKind::kTablePose: return "table_pose";
    case MoveKind::kTableSize: return "table_size";
    case MoveKind::kLegDeath: return "leg_death";
    case MoveKind::kParentChange: return "parent_change";
    case MoveKind::kLegPose: return "leg_pose";
    case MoveKind::kParentBirth: return "parent_birth";
    case MoveKind::kReversible: return "reversible";
    case MoveKind::kCount: break;
  }
  return "?";
}

struct MoveCount {
  long long proposals = 0;
  long long accepted = 0;
};
using MoveCounts = std::array<MoveCount, kMoveKinds>;

inline void addMoveCounts(MoveCounts& into, const MoveCounts& from) {
  for (size_t k = 0; k < kMoveKinds; ++k) {
    into[k].proposals += from[k].proposals;
    into[k].accepted += from[k].accepted;
  }
}

}  // namespace crunch
