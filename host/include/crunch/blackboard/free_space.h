// Negative evidence (the paper's future work, §4: "the observed absence of shapelets on
// non-contacting whiskers"). A whisker that swept through a place without bending says nothing
// stands there. FreeSpaceGrid counts, per 1 cm cell, the whisker samples that passed through it
// untouched; the blackboard charges a hypothesised leg (or a table's corner, where its leg must
// stand) log(p_miss) for each such pass through its core (blackboard.h).
//
// The look-up (issue 15). maxInSquare() runs inside every leg and table term of the sampler, so
// it must not scan cells. Beside the counts the grid keeps, for window sides 2 and 4 cells, the
// maximum count of the square window starting at each cell (a 2-D sparse table over squares).
// Counts only grow, so a ray updates those maxima by raising them (addRay: at most 20 windows
// per cell the ray crosses, see raise()) and they stay exact at all times. (A third level, 8
// cells, would serve cores wider than 6 cm in 4 look-ups instead of 9 but cost 64 more windows
// per cell in addRay: in the default run that was more than it saved.)
// A query then reads, in four look-ups each:
//   - the maximum over the axis-aligned box of the cells the reference scan would visit: an
//     upper bound, exact when it is 0 (the common case: 93 % of the default run's queries);
//   - the maximum over the axis-aligned box inscribed in the turned core: a lower bound.
// When the two agree that is the answer. Only when they differ (a core on the edge of swept
// space) are the box's rows visited, each only over the cells the core's outline can reach,
// with cos/sin computed once per query (a 2 cm core's box is 3-4 cells, so that row walk is
// short; the old scan took cos and sin for every cell). The answer is exactly the brute-force scan's, cell for
// cell (the candidate cells are the analytic ones widened by 1 nm and each is then tested with
// the scan's own arithmetic; test/blackboard/free_space_test.cc checks it against the scan,
// which is kept as the reference in test/blackboard/free_space_scan.h).
//
// Memory: 3 x 2 bytes per cell (the counts and two window levels): 1 MB for the 4 x 4 m arena,
// 24 MB for a 20 x 20 m floor.
// Thread-safety: const methods may run concurrently (they read only); addRay() must not run
// beside any other call. Allocation: the constructor only; addRay() and queries never allocate.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/robot/shapelet.h"  // FreeRay

namespace crunch {

class FreeSpaceGrid {
 public:
  // Covers [lo, hi] with square cells of side `cell` metres; points outside count 0.
  FreeSpaceGrid(const Vec2& lo, const Vec2& hi, double cell = 0.01);

  // Counts one pass through every cell the segment crosses (each cell once per ray); counts
  // saturate at 65535.
  void addRay(const FreeRay& ray);

  // Passes through the cell containing p.
  int count(const Vec2& p) const;

  // The most passes through any cell whose centre lies in the square `side` x `side` at `pose`
  // shrunk by `margin` on every side (its core: a ray grazing the outline does not count).
  // A core of half-side h = side / 2 - margin <= 0 is its centre point: count(pose.position()).
  int maxInSquare(const Pose2& pose, double side, double margin) const;

  double cell() const { return cell_; }
  long long rays() const { return rays_; }

  // The grid's layout: the corner of cell (0, 0), the number of cells along x and y, and the
  // passes through cell (ix, iy) (0 outside the grid). Cell (ix, iy) has its centre at
  // origin() + ((ix + 0.5) cell, (iy + 0.5) cell).
  const Vec2& origin() const { return lo_; }
  int cellsX() const { return nx_; }
  int cellsY() const { return ny_; }
  int countAt(int ix, int iy) const;

 private:
  // Window sides 2^1 .. 2^kLevels cells.
  static constexpr int kLevels = 2;

  bool index(const Vec2& p, int& ix, int& iy) const;
  size_t at(int ix, int iy) const {
    return static_cast<size_t>(iy) * static_cast<size_t>(nx_) + static_cast<size_t>(ix);
  }
  // Cell (ix, iy) now holds v: raises every window containing it to at least v.
  void raise(int ix, int iy, uint16_t v);
  // The largest count in the cells [x0, x1] x [y0, y1] (inside the grid, not empty).
  int boxMax(int x0, int y0, int x1, int y1) const;
  // The exact maximum over the core's cells of the box [x0, x1] x [y0, y1], visiting rows;
  // stops early on reaching `upper`, the box's maximum.
  int scanCore(const Pose2& pose, double h, int x0, int y0, int x1, int y1, int upper) const;

  Vec2 lo_;
  double cell_;
  int nx_ = 0, ny_ = 0;
  std::vector<uint16_t> counts_;
  // windows_[j - 1][at(ix, iy)]: the largest count in the 2^j x 2^j cells from (ix, iy) towards
  // +x +y (clipped at the grid's edge).
  std::array<std::vector<uint16_t>, kLevels> windows_;
  long long rays_ = 0;
};

}  // namespace crunch
