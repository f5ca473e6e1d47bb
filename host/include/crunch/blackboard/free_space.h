// Negative evidence (the paper's future work, §4: "the observed absence of shapelets on
// non-contacting whiskers"). A whisker that swept through a place without bending says nothing
// stands there. FreeSpaceGrid counts, per 1 cm cell, the whisker samples that passed through it
// untouched; the blackboard charges a hypothesised leg (or a table's corner, where its leg must
// stand) log(p_miss) for each such pass through its core (blackboard.h).
#pragma once

#include <cstdint>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/robot/shapelet.h"  // FreeRay

namespace crunch {

class FreeSpaceGrid {
 public:
  // Covers [lo, hi] with square cells of side `cell` metres; points outside count 0.
  FreeSpaceGrid(const Vec2& lo, const Vec2& hi, double cell = 0.01);

  // Counts one pass through every cell the segment crosses (each cell once per ray).
  void addRay(const FreeRay& ray);

  // Passes through the cell containing p.
  int count(const Vec2& p) const;

  // The most passes through any cell whose centre lies in the square `side` x `side` at `pose`
  // shrunk by `margin` on every side (its core: a ray grazing the outline does not count).
  int maxInSquare(const Pose2& pose, double side, double margin) const;

  double cell() const { return cell_; }
  long long rays() const { return rays_; }

 private:
  bool index(const Vec2& p, int& ix, int& iy) const;
  Vec2 lo_;
  double cell_;
  int nx_ = 0, ny_ = 0;
  std::vector<uint16_t> counts_;
  long long rays_ = 0;
};

}  // namespace crunch
