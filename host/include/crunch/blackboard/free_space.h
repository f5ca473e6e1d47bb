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
// Memory (issue 16): bounded by where the whiskers swept, not by the arena's area. The cells
// are stored in tiles of 64 x 64 (0.64 m a side at 1 cm), each 24 KB (3 x 2 bytes per cell: the
// counts and two window levels), made when a ray first raises a cell or window in it; a tile
// no ray reached is read as zeros from one shared, never-written tile. The directory costs 8
// bytes per tile of the arena: 200 KB for the largest arena a scene may have (200 x 200 m,
// scene.h's kMaxArenaSide). So an empty 160 m arena costs 0.1 MB instead of 1.5 GB, and a
// robot that sweeps a 2 m wide corridor through it pays for the corridor's tiles only.
// Thread-safety: const methods may run concurrently (they read only); addRay() must not run
// beside any other call. Allocation: the constructor (the directory) and addRay() (a tile the
// first time a ray reaches it); queries never allocate, so the sampler's sweep does not.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
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
  // The robot's body moved from a to b (a disc of `radius` swept along the segment; a == b: it
  // stood there): every cell whose centre lies within `radius` of the segment gains `passes`
  // passes (saturating). A leg there would have stopped the body, so the mapper charges it
  // like a whisker's full pass cap (mapper.h, addBodySweep). Counted as one ray.
  void addSweep(const Vec2& a, const Vec2& b, double radius, int passes);

  // The room's walls bound [lo, hi] (the robot's known region: its edges are walls): no leg
  // stands beyond them, so maxInSquare() answers 65535 (saturated, as certain as any sweep) for
  // a core whose centre lies outside, inside the grid or not. count() is unchanged (a wall's
  // term reads both its sides, and a wall at the room's edge has nothing swept behind it).
  // Counted as one ray (the cached terms change).
  void setRoom(const Vec2& lo, const Vec2& hi);

  // The readers need maxInSquare() only up to `cap` (the blackboard charges at most
  // free_pass_cap passes): from here on the window planes hold each maximum clamped to `cap`,
  // so a cell past it raises no window (the ray upkeep's cost, issue 15), and
  // min(maxInSquare(), cap) is unchanged for every square. count() and countAt() stay exact.
  // Before the first ray (windows raised earlier keep their values, which are never lower).
  void setWindowCap(int cap);

  // Passes through the cell containing p.
  int count(const Vec2& p) const;

  // The most passes through any cell whose centre lies in the square `side` x `side` at `pose`
  // shrunk by `margin` on every side (its core: a ray grazing the outline does not count).
  // A core of half-side h = side / 2 - margin <= 0 is its centre point: count(pose.position()).
  int maxInSquare(const Pose2& pose, double side, double margin) const;
  // Whether any ray passed through a cell the axis-aligned box [p - reach, p + reach]^2
  // touches (outside the room, when one is set, always true: the room's bounds are evidence
  // too; false for a non-finite p). The rooms model's catalog asks it of a table's corners: the
  // evidence fixes a side's length only where whiskers came near both of its legs (params.h).
  bool sweptNear(const Vec2& p, double reach) const;

  double cell() const { return cell_; }
  long long rays() const { return rays_; }

  // The grid's layout: the corner of cell (0, 0), the number of cells along x and y, and the
  // passes through cell (ix, iy) (0 outside the grid). Cell (ix, iy) has its centre at
  // origin() + ((ix + 0.5) cell, (iy + 0.5) cell).
  const Vec2& origin() const { return lo_; }
  int cellsX() const { return nx_; }
  int cellsY() const { return ny_; }
  int countAt(int ix, int iy) const;
  // The smallest box of cells [x0, x1] x [y0, y1] holding every cell a ray passed through;
  // false when there is none. Reads only the tiles made (the map file's free_space, issue 17).
  bool sweptBounds(int& x0, int& y0, int& x1, int& y1) const;
  // Bytes held by the tiles made so far (the directory not counted).
  size_t tileBytes() const { return owned_.size() * sizeof(Tile); }

 private:
  // Window sides 2^1 .. 2^kLevels cells.
  static constexpr int kLevels = 2;
  // A tile is kTile x kTile cells: plane 0 the counts; plane j (1..kLevels) at a cell holds the
  // largest count in the 2^j x 2^j cells from it towards +x +y (clipped at the grid's edge).
  static constexpr int kTileBits = 6;
  static constexpr int kTile = 1 << kTileBits;
  static constexpr size_t kPlane = static_cast<size_t>(kTile) * kTile;
  struct Tile {
    uint16_t v[(kLevels + 1) * kPlane];
  };
  static const Tile kZeroTile;

  bool index(const Vec2& p, int& ix, int& iy) const;
  // The cells [x0, x1] x [y0, y1] the box [lo, hi] touches, clamped to the grid; false when
  // none.
  bool cellBox(const Vec2& lo, const Vec2& hi, int& x0, int& y0, int& x1, int& y1) const;
  // Whether a room is set and p lies outside it (setRoom).
  bool outsideRoom(double x, double y) const {
    return room_ &&
           !(x >= room_lo_.x() && x <= room_hi_.x() && y >= room_lo_.y() && y <= room_hi_.y());
  }
  size_t tileOf(int ix, int iy) const {
    return static_cast<size_t>(iy >> kTileBits) * static_cast<size_t>(tiles_x_) +
           static_cast<size_t>(ix >> kTileBits);
  }
  static size_t inTile(int plane, int ix, int iy) {
    return static_cast<size_t>(plane) * kPlane +
           static_cast<size_t>(((iy & (kTile - 1)) << kTileBits) | (ix & (kTile - 1)));
  }
  // Plane `plane` (0 counts, j windows of side 2^j) at cell (ix, iy), inside the grid.
  uint16_t value(int plane, int ix, int iy) const { return tiles_[tileOf(ix, iy)][inTile(plane, ix, iy)]; }
  // The same, writable: makes the cell's tile if no ray reached it yet.
  uint16_t& slot(int plane, int ix, int iy);
  // Cell (ix, iy) now holds v: raises every window containing it to at least v.
  void raise(int ix, int iy, uint16_t v);
  // The largest count in the cells [x0, x1] x [y0, y1] (inside the grid, not empty).
  int boxMax(int x0, int y0, int x1, int y1) const;
  // The exact maximum over the core's cells of the box [x0, x1] x [y0, y1], visiting rows;
  // stops early on reaching `upper`, the box's maximum.
  int scanCore(const Pose2& pose, double h, int x0, int y0, int x1, int y1, int upper) const;

  Vec2 lo_;
  double cell_;
  bool room_ = false;
  uint16_t window_cap_ = std::numeric_limits<uint16_t>::max();
  Vec2 room_lo_{0, 0}, room_hi_{0, 0};
  int nx_ = 0, ny_ = 0;
  int tiles_x_ = 0;
  // tiles_[tileOf(ix, iy)]: the cell's tile, or the shared zero tile if no ray reached it.
  std::vector<const uint16_t*> tiles_;
  // The tiles made so far (tiles_ points into them).
  std::vector<std::unique_ptr<Tile>> owned_;
  long long rays_ = 0;
};

}  // namespace crunch
