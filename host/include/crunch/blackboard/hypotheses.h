// Hypothesis records of the blackboard: tables and legs (paper eqs. 7-8). Shapelets are the
// observations (robot/shapelet.h). Plain data, owned by the Blackboard's pools.
#pragma once

#include <array>
#include <cstdint>

#include "crunch/core/geometry.h"

namespace crunch {

inline constexpr int32_t kNone = -1;
// A table keeps at most this many child legs. Four is the model; more are heavily penalised by
// eps_c (two legs at one corner) and never part of a MAP, so the bound costs nothing real.
inline constexpr int kMaxChildren = 8;

struct TableHyp {
  Pose2 pose;
  bool alive = false;
  uint8_t n_children = 0;
  std::array<int32_t, kMaxChildren> children{};
  std::array<uint8_t, 4> corner_count{};  // children at each corner

  // Missing legs m of eq. 24: corners no child occupies.
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
};

}  // namespace crunch
