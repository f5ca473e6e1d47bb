// Getting to a chosen whisk pose: A* over the KnownSpace grid (8-connected, octile heuristic),
// the well-known grid planner of mobile robotics, on a configuration space built the usual way:
// every occupied cell is grown by the Create's radius plus a margin (Minkowski inflation), so
// the robot is a point on the grid. Unknown cells are traversable (the free-space assumption:
// plan optimistically, replan when a bump or a contact says otherwise) at a cost factor > 1, so
// known free space is preferred. The path is shortened by line-of-sight over the inflated grid.
// A start inside the inflation (the robot stands closer to an obstacle than planned: after a
// bump, or squeezed through a gap the margin closes) leaves it by its shortest way out: paths
// are compared by the metres they drive inside the inflation first, then by cost, so the zone
// is an exit, never a corridor to wherever is cheapest. Where the robot has been it fits: a cell
// its centre drove through (KnownSpace::markVisited) stays passable under the inflation, unless
// within the inflation of a bump or itself occupied, so a robot that drove under a chair before
// its legs were known leaves the way it came (the inflation closes the chair's gaps).
//
// DistanceField is the same search run as Dijkstra from the robot to every cell (one search per
// decision), so a policy scores hundreds of candidate poses by their path length at the cost of
// one search.
//
// Units: metres. Thread-safety: none. Allocation: in the calls (the search's open list and
// the result), never in a hot loop of the sampler.
#pragma once

#include <limits>
#include <optional>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/core/result.h"
#include "crunch/exploration/known_space.h"
#include "crunch/robot/whiskers.h"  // kRobotRadius

namespace crunch::exploration {

struct PlannerOptions {
  double robot_radius = kRobotRadius;  // the Create's
  double margin = 0.03;                // clearance beyond the radius, metres; >= 0
  double unknown_cost = 1.5;           // cost per metre through unknown cells, relative to free

  // robot_radius > 0, margin >= 0, unknown_cost >= 1 (all finite); an Error naming the field.
  Status validate() const;
};

// The configuration space: true where the robot's centre may not stand (inflated occupied
// cells and region edge, less the cells the robot drove through away from bumps).
class Costmap {
 public:
  Costmap(const KnownSpace& known, const PlannerOptions& options);
  bool blocked(int ix, int iy) const;  // true outside the grid
  // Within robot_radius + margin of an occupied cell or the region's edge, whether or not the
  // robot drove there (blocked() less the trail); true outside the grid.
  bool inflated(int ix, int iy) const;
  bool blocked(const Vec2& p) const;
  const KnownSpace& known() const { return known_; }
  const PlannerOptions& options() const { return options_; }

 private:
  const KnownSpace& known_;
  PlannerOptions options_;
  std::vector<std::uint8_t> blocked_;
  std::vector<std::uint8_t> inflated_;
};

struct PathPlan {
  std::vector<Vec2> waypoints;  // from the start (excluded) to the goal (included)
  double length = 0.0;          // metres along the waypoints
  // The search's cost-weighted length of the cell path before shortening (unknown cells count
  // unknown_cost per metre): what DistanceField::to(goal) gives for the same start.
  double cost = 0.0;
};

// The shortest path from `from` to `to` on the costmap, or nullopt when the goal is blocked or
// unreachable. A start inside an inflated obstacle (after a bump) leaves it by the shortest way
// out that crosses no occupied cell (of the paths with the fewest metres inside the inflation,
// the cheapest).
std::optional<PathPlan> planPath(const Costmap& costmap, const Vec2& from, const Vec2& to);

// Path cost from one start to every cell (Dijkstra on the same graph as planPath).
class DistanceField {
 public:
  DistanceField(const Costmap& costmap, const Vec2& from);
  // Metres (cost-weighted) to the cell holding p; infinity if blocked or unreachable.
  double to(const Vec2& p) const;
  double to(int ix, int iy) const;
  // The cell before cell `i` (iy * nx + ix) on its shortest path from the start; -1 for the
  // start and for cells not reached. Following them from any reached cell ends at the start
  // (each parent's path is less than its child's: metres out of blocked cells, then cost).
  // Parents cost less than their children, except at a cell reached both by the escape from an
  // inflated start and from outside (a trail cell), which keeps the path with fewer metres out
  // of blocked cells.
  int parent(int i) const { return parent_[static_cast<std::size_t>(i)]; }
  // The search's cost-weighted metres to cell `i` (infinity if not reached), without to()'s
  // blocked check (a start inside an inflated zone reaches blocked cells on its way out).
  double cost(int i) const { return dist_[static_cast<std::size_t>(i)]; }

 private:
  const Costmap& costmap_;
  std::vector<double> dist_;
  std::vector<int> parent_;
};

}  // namespace crunch::exploration
