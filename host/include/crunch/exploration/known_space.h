// What the robot knows about the floor, for planning a path and for choosing where to whisk
// (paper §2.9; docs/EXPLORATION.md): a grid of square cells over the exploration region, each
//   kUnknown   nothing has passed through it yet;
//   kFree      a whisker swept through it without touching (a FreeRay) or the body stood on it;
//   kOccupied  a contact was located in it, a bumper hit it, or a leg or wall of the current
//              map covers it.
// Contacts and bumps are permanent (markContact, markBump); the map's obstacles are replaced
// each time the map changes (setMapObstacles), so a table the sampler drops stops blocking.
// Occupied wins over free: a cell both swept and touched is occupied.
// Apart from the three states, a cell records whether the robot's centre drove through it
// (markVisited) and whether a bump was marked in it (markBump): the planner keeps visited cells
// passable under the inflation except near a bump (path_planner.h, "where the robot has been").
//
// Units: metres, arena frame. Cells are indexed (ix, iy) from `lo`; points outside the region
// are outside() and count as blocked for the planner.
// Ownership: owns its cells. Thread-safety: none. Allocation: at construction and in
// setMapObstacles (the obstacle list); marking allocates nothing.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/mapping/map.h"
#include "crunch/robot/shapelet.h"  // FreeRay

namespace crunch::exploration {

class KnownSpace {
 public:
  enum class Cell : std::uint8_t { kUnknown, kFree, kOccupied };

  // Covers [lo, hi] with cells of side `cell` (> 0; asserted).
  KnownSpace(const Vec2& lo, const Vec2& hi, double cell = 0.05);

  // Every cell the segment crosses becomes free (unless occupied).
  void markFreeRay(const FreeRay& ray);
  // The body's disc (radius r) at `position` becomes free (unless occupied).
  void markBody(const Vec2& position, double radius);
  // A located contact point (a shapelet's position) or a bumper's hit point: occupied for good.
  void markContact(const Vec2& point);
  void markBump(const Vec2& point);
  // The robot's centre drove along the segment a..b: every cell it crosses is visited.
  void markVisited(const Vec2& a, const Vec2& b);
  bool visited(int ix, int iy) const;  // false outside the grid
  bool bumped(int ix, int iy) const;   // a bump was marked in the cell; false outside
  // The current map's legs (each table's four leg squares) and walls: occupied until the next
  // call replaces them.
  void setMapObstacles(std::span<const MapTable> tables, std::span<const MapWall> walls);

  Cell at(int ix, int iy) const;  // kOccupied outside the grid
  Cell at(const Vec2& p) const;
  bool outside(const Vec2& p) const;
  // A frontier cell: unknown, with a free 4-neighbour.
  bool frontier(int ix, int iy) const;

  int nx() const { return nx_; }
  int ny() const { return ny_; }
  double cell() const { return cell_; }
  const Vec2& lo() const { return lo_; }
  Vec2 hi() const { return lo_ + Vec2(nx_ * cell_, ny_ * cell_); }
  Vec2 centre(int ix, int iy) const { return lo_ + Vec2((ix + 0.5) * cell_, (iy + 0.5) * cell_); }
  // The cell holding p; false if outside.
  bool index(const Vec2& p, int& ix, int& iy) const;
  // Fraction of the region's cells that are not unknown.
  double knownFraction() const;

 private:
  Vec2 lo_;
  double cell_;
  int nx_ = 0, ny_ = 0;
  std::vector<std::uint8_t> swept_;    // 1: free by a ray or the body
  std::vector<std::uint8_t> touched_;  // 1: a contact or bump (permanent)
  std::vector<std::uint8_t> mapped_;   // 1: under the current map's legs and walls
  std::vector<std::uint8_t> visited_;  // 1: the robot's centre drove through it
  std::vector<std::uint8_t> bumped_;   // 1: a bump was marked in it
};

}  // namespace crunch::exploration
