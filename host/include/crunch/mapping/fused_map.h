// The fused map: one best answer from the collation of independent per-pose MAP_t (eq. 27).
//
// The paper stops at the collation (Fig. 11-13). A table that is really there is inferred again
// and again from the poses that can touch it, while a misplaced rival (the T2 of Fig. 5) or a
// wall-induced phantom changes with the viewpoint. So: cluster the per-pose tables (centre within
// `radius`, angle within `angle` modulo pi), keep clusters that at least `min_support` poses
// agree on, average each cluster (circular mean of doubled angles), and where two kept tables
// overlap keep the better supported one (two tables cannot share space: eq. 25's constraint).
// A fused table's score is its support divided by the number of inferring poses within reach of
// it (robot centre within `reach` of its centre): the fraction of poses that could have seen it
// and did. See docs/BLACKBOARD.md.
#pragma once

#include <cmath>
#include <vector>

#include "crunch/mapping/map.h"

namespace crunch {

struct FuseOptions {
  double radius = 0.10;                // metres
  double angle = 10.0 * kPi / 180.0;  // radians, modulo pi
  int min_support = 3;                // per-pose MAPs that must agree
  double reach = 0.9;                 // metres: robot centres that could touch the table
  // The rooms model's tables differ in size: two agree only if their widths and their depths
  // (each written width >= depth) differ by at most `size` too, and a near-square pair (both
  // within `size` of square) compares angles modulo pi/2. The Mapper sets compare_sizes for
  // ObjectModel::kRooms; off, sizes are ignored (the paper's one size).
  bool compare_sizes = false;
  double size = 0.10;                 // metres
  // Two fused tables cannot overlap (the better supported stays), but tables pushed together
  // touch, and each fitted side is off by millimetres (the scene table's size errors): they
  // clash only when one reaches more than clash_depth into the other (tablesClash).
  double clash_depth = 0.02;          // metres

  // radius and reach above 0 and at most 10 m, angle above 0 and at most pi, min_support
  // 1..1e6, size above 0 and at most 10 m, clash_depth 0..0.5 m. okStatus(), or an Error naming
  // the first bad field.
  Status validate() const;
};

std::vector<MapTable> fuseTables(const std::vector<PoseMap>& per_pose, const FuseOptions& opt);

// True if two table poses agree within `radius` and `angle` (modulo pi).
bool tablesAgree(const Pose2& a, const Pose2& b, const FuseOptions& opt);
// The same for map tables: their sizes too when opt.compare_sizes.
bool tablesAgree(const MapTable& a, const MapTable& b, const FuseOptions& opt);
// Whether two fused tables cannot both stand: their footprints, each shrunk by half of
// opt.clash_depth on every side, overlap.
bool tablesClash(const MapTable& a, const MapTable& b, const FuseOptions& opt);
// Two tables cannot both stand: of `best_first` (most probable first), each table that clashes
// with one kept before it is dropped (eq. 25). The vote and the marginal map both end so.
std::vector<MapTable> withoutClashes(const std::vector<MapTable>& best_first, const FuseOptions& opt);
// Whether a table is square within `tolerance` (its angle then means modulo pi/2).
inline bool nearSquare(const MapTable& t, double tolerance) {
  return std::abs(t.width - t.depth) <= tolerance;
}

// Sets each table's score from its support: support divided by the inferring poses within
// `reach` of it, capped at 1 (0 when none is within reach).
void scoreBySupport(std::vector<MapTable>& tables, const std::vector<PoseMap>& per_pose,
                    const FuseOptions& opt);

}  // namespace crunch
