// Hypothesis records of the blackboard: tables and legs (paper eqs. 7-8), and walls (issue 13,
// --model rooms). Shapelets are the
// observations (robot/shapelet.h). Plain data, owned by the Blackboard's pools.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include "crunch/core/geometry.h"

namespace crunch {

inline constexpr int32_t kNone = -1;
// A table keeps at most this many child legs. Four is the model; more are heavily penalised by
// eps_c (two legs at one corner) and never part of a MAP, so the bound costs nothing real.
inline constexpr int kMaxChildren = 8;

struct TableHyp {
  Pose2 pose;
  // Its own size (issue 13): the top's width (along the pose's x axis) and depth, and its legs'
  // side. Under ObjectModel::kPaper always ModelParams' one size.
  double width = 0.80;
  double depth = 0.50;
  double leg = 0.05;
  bool alive = false;
  uint8_t n_children = 0;
  std::array<int32_t, kMaxChildren> children{};
  std::array<uint8_t, 4> corner_count{};  // children at each corner
  // cos and sin of pose.theta and the top's circumradius, as the Blackboard holding the record
  // set them with its pose and size (issue 15: no libm call per look). A record built or changed
  // elsewhere does not keep them; only the Blackboard's own energy code reads them.
  RectTrig trig;
  // The Blackboard's cache of this record's own terms of J (incremental energies, blackboard.h):
  // valid while own_gen equals the board's generation.
  double own = 0.0;
  uint64_t own_gen = 0;
  // Its negative evidence (the four corners' free terms) with the pose and sizes it was read
  // at: valid while free_gen equals the board's generation and they are this record's (a move
  // that leaves the table where it was reads no free space; blackboard.cc cachedTableFree).
  double free = 0.0;
  uint64_t free_gen = 0;
  Pose2 free_pose;
  double free_width = 0.0, free_depth = 0.0, free_leg = 0.0;

  // Missing legs m of eq. 24: corners no child occupies.
  // Offset of corner i's leg centre in the table frame (ModelParams::cornerOffset).
  Vec2 cornerOffset(int i) const {
    const double hx = 0.5 * (width - leg), hy = 0.5 * (depth - leg);
    return {(i == 0 || i == 3) ? hx : -hx, (i < 2) ? hy : -hy};
  }
  Vec2 corner(int i) const { return pose.toWorld(cornerOffset(i)); }

  int missingLegs() const {
    int m = 0;
    for (uint8_t c : corner_count) m += (c == 0);
    return m;
  }
};

struct LegHyp {
  Pose2 pose;       // centre and rotation; theta meaningful modulo pi/2
  double side = 0.05;
  int32_t parent = kNone;  // the table that caused it (eq. 8), or none (null prior, eq. 13)
  int8_t corner = -1;      // the parent's corner nearest this leg (the argmin of eq. 10)
  bool alive = false;
  // cos and sin of pose.theta and the square's circumradius, kept by the Blackboard as TableHyp's.
  RectTrig trig;
  // The Blackboard's cache of this record's own terms of J (incremental energies, blackboard.h):
  // valid while own_gen equals the board's generation.
  double own = 0.0;
  uint64_t own_gen = 0;
  // Its free term with the pose and side it was read at (as TableHyp::free).
  double free = 0.0;
  uint64_t free_gen = 0;
  Pose2 free_pose;
  double free_side = 0.0;
};

// A wall (--model walls or rooms only): the finite segment a..b of a flat surface, which causes the
// shapelets lying on it with their orientation along it (blackboard.h). A surface faces one way:
// its free side (where whiskers can be) is the left of a->b, the solid behind it the right; the
// two faces of a thin wall are two hypotheses. No parent: walls have only the null prior c_W and
// a cost per metre of length (params.h).
struct WallHyp {
  Vec2 a{0.0, 0.0}, b{0.0, 0.0};
  bool alive = false;
  // The Blackboard's cache of this record's own terms of J (its odds, length cost and negative
  // evidence; incremental energies, blackboard.h): valid while own_gen equals the board's
  // generation.
  double own = 0.0;
  uint64_t own_gen = 0;

  double length() const { return (b - a).norm(); }
  double angle() const { return std::atan2(b.y() - a.y(), b.x() - a.x()); }
  // Unit normal into the solid (the right of a->b); zero for a degenerate wall.
  Vec2 solidNormal() const {
    const double len = length();
    return len > 0 ? Vec2{(b.y() - a.y()) / len, -(b.x() - a.x()) / len} : Vec2{0.0, 0.0};
  }
};

}  // namespace crunch
