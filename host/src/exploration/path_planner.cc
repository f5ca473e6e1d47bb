#include "crunch/exploration/path_planner.h"

#include <algorithm>
#include <cmath>
#include <queue>
#include <string>

namespace crunch::exploration {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kDx[8] = {1, -1, 0, 0, 1, 1, -1, -1};
constexpr int kDy[8] = {0, 0, 1, -1, 1, -1, 1, -1};

// Ordered by metres inside the inflation first, then by cost plus heuristic (lexicographic).
struct Node {
  double inside;
  double f;
  int index;
  bool operator>(const Node& o) const {
    if (inside != o.inside) return inside > o.inside;
    return f > o.f || (f == o.f && index > o.index);
  }
};

// A* (heuristic on) or Dijkstra (off) from `from` over the costmap, on states (cell, phase).
// A start inside the inflation (Costmap::inflated) begins escaping: it may step into any cell
// that is not occupied, and is out once it reaches a cell the inflation does not cover. From
// then on, and from a start outside, only passable cells (not Costmap::blocked) may be
// entered. Paths are compared lexicographically: fewest metres driven out of blocked cells
// first, then least cost. So a start inside leaves by its shortest way out and plans from
// there; by cost alone the whole zone joined to the start was a free corridor, and a robot
// squeezed between a leg and a wall planned along the leg's halo and through the wall's
// untouched stretch, bumping there on every goal (l_room, docs/EXPLORATION.md "Leaving the
// inflation"). The escape follows the inflation, not the passable cells: a robot standing on
// its own trail (passable) inside a chair's inflation would otherwise be held to the trail's
// cells. The first key is 0 from a start outside, so nothing changes there. The heuristic is on
// the cost (0 on the first key: consistent as any constant is).
struct SearchResult {
  int start = -1;                 // the start's state, or -1
  std::vector<double> inside;     // per state: metres driven out of blocked cells
  std::vector<double> cost;       // per state
  std::vector<int> parent;        // per state: the state before it, -1 for none
  int best(int cell) const {      // the cell's lexicographically least state, or -1
    const int a = 2 * cell, b = a + 1;
    const bool ra = std::isfinite(cost[a]), rb = std::isfinite(cost[b]);
    if (!ra && !rb) return -1;
    if (!rb) return a;
    if (!ra) return b;
    return (inside[a] < inside[b] || (inside[a] == inside[b] && cost[a] <= cost[b])) ? a : b;
  }
};

SearchResult search(const Costmap& cm, const Vec2& from, int goal) {
  const KnownSpace& k = cm.known();
  const int nx = k.nx(), ny = k.ny();
  const std::size_t n_cells = static_cast<std::size_t>(nx) * ny;
  SearchResult r;
  r.inside.assign(2 * n_cells, kInf);
  r.cost.assign(2 * n_cells, kInf);
  r.parent.assign(2 * n_cells, -1);
  int sx, sy;
  if (!k.index(from, sx, sy)) return r;
  const int start_cell = sy * nx + sx;
  const double c = k.cell();
  const int gx = goal >= 0 ? goal % nx : 0, gy = goal >= 0 ? goal / nx : 0;
  const auto h = [&](int x, int y) {
    if (goal < 0) return 0.0;
    const double dx = std::abs(x - gx), dy = std::abs(y - gy);
    return c * (std::max(dx, dy) + (std::sqrt(2.0) - 1.0) * std::min(dx, dy));  // octile
  };
  // Per-cell rate (unknown_cost in unknown cells, 1 in free ones) and flags, read once: the
  // inner loop then touches plain arrays. A step is charged half at each end's rate.
  std::vector<float> rate(n_cells);
  std::vector<std::uint8_t> flags(n_cells);  // bit 0: blocked, bit 1: occupied, bit 2: inflated
  for (int y = 0; y < ny; ++y) {
    for (int x = 0; x < nx; ++x) {
      const int i = y * nx + x;
      const KnownSpace::Cell cell_state = k.at(x, y);
      rate[i] = cell_state == KnownSpace::Cell::kUnknown ? static_cast<float>(cm.options().unknown_cost) : 1.0f;
      flags[i] = static_cast<std::uint8_t>((cm.blocked(x, y) ? 1 : 0) |
                                           (cell_state == KnownSpace::Cell::kOccupied ? 2 : 0) |
                                           (cm.inflated(x, y) ? 4 : 0));
    }
  }
  const auto blockedAt = [&](int x, int y) {
    return x < 0 || y < 0 || x >= nx || y >= ny || (flags[y * nx + x] & 1);
  };
  // Phase 0: escaping the inflation; phase 1: out (or never in).
  r.start = 2 * start_cell + ((flags[start_cell] & 4) ? 0 : 1);
  std::priority_queue<Node, std::vector<Node>, std::greater<Node>> open;
  r.cost[r.start] = 0.0;
  r.inside[r.start] = 0.0;
  open.push({0.0, h(sx, sy), r.start});
  while (!open.empty()) {
    const Node n = open.top();
    open.pop();
    const int cell = n.index / 2, phase = n.index % 2;
    const int x = cell % nx, y = cell / nx;
    if (n.inside > r.inside[n.index] || (n.inside == r.inside[n.index] &&
                                         n.f > r.cost[n.index] + h(x, y) + 1e-12)) {
      continue;  // stale entry
    }
    if (cell == goal) break;
    const bool escaping = phase == 0;
    const bool here_blocked = flags[cell] & 1;
    for (int d = 0; d < 8; ++d) {
      const int jx = x + kDx[d], jy = y + kDy[d];
      if (jx < 0 || jy < 0 || jx >= nx || jy >= ny) continue;
      const int j = jy * nx + jx;
      // Never through an obstacle itself; out of the escape, never into a blocked cell.
      if (flags[j] & 2) continue;
      if ((flags[j] & 1) && !escaping) continue;
      // No corner cutting: a diagonal step needs both side cells passable, unless the robot's
      // centre drove through both cells (its trail crosses cell corners: KnownSpace::markVisited
      // marks the cells a segment crosses, which are 8-connected).
      if (d >= 4 && !escaping && !(k.visited(x, y) && k.visited(jx, jy)) &&
          (blockedAt(x + kDx[d], y) || blockedAt(x, y + kDy[d]))) {
        continue;
      }
      const double step = d >= 4 ? c * std::sqrt(2.0) : c;
      const int to = 2 * j + ((escaping && (flags[j] & 4)) ? 0 : 1);
      const double nd = r.cost[n.index] + 0.5 * step * (double(rate[cell]) + double(rate[j]));
      const double ni = r.inside[n.index] + (here_blocked ? step : 0.0);
      if (ni < r.inside[to] || (ni == r.inside[to] && nd < r.cost[to])) {
        r.inside[to] = ni;
        r.cost[to] = nd;
        r.parent[to] = n.index;
        open.push({ni, nd + h(jx, jy), to});
      }
    }
  }
  return r;
}

// True if the straight segment a-b crosses no blocked cell (sampled at a quarter cell).
bool lineOfSight(const Costmap& cm, const Vec2& a, const Vec2& b) {
  const Vec2 d = b - a;
  const int n = static_cast<int>(std::ceil(d.norm() / (0.25 * cm.known().cell()))) + 1;
  for (int k = 0; k <= n; ++k) {
    if (cm.blocked(a + d * (static_cast<double>(k) / n))) return false;
  }
  return true;
}

}  // namespace

Status PlannerOptions::validate() const {
  if (!std::isfinite(robot_radius) || robot_radius <= 0) {
    return Error{"planner robot_radius " + std::to_string(robot_radius) + ": must be above 0"};
  }
  if (!std::isfinite(margin) || margin < 0) {
    return Error{"planner margin " + std::to_string(margin) + ": must be 0 or more"};
  }
  if (!std::isfinite(unknown_cost) || unknown_cost < 1) {
    return Error{"planner unknown_cost " + std::to_string(unknown_cost) + ": must be 1 or more"};
  }
  return okStatus();
}

Costmap::Costmap(const KnownSpace& known, const PlannerOptions& options)
    : known_(known), options_(options) {
  const int nx = known.nx(), ny = known.ny();
  const double c = known.cell();
  blocked_.assign(static_cast<std::size_t>(nx) * ny, 0);
  const double r = options.robot_radius + options.margin;
  // Minkowski inflation: a cell is blocked when its centre is within r of an occupied cell's
  // centre, or within r of the region's edge (the robot is told the room's extent: its walls).
  const int k = static_cast<int>(std::ceil(r / c));
  std::vector<std::pair<int, int>> disc;
  for (int dy = -k; dy <= k; ++dy) {
    for (int dx = -k; dx <= k; ++dx) {
      if (std::hypot(dx * c, dy * c) <= r) disc.emplace_back(dx, dy);
    }
  }
  // The inflation of the bumps alone (a bump is an occupied cell), for the trail below.
  std::vector<std::uint8_t> near_bump(blocked_.size(), 0);
  for (int y = 0; y < ny; ++y) {
    for (int x = 0; x < nx; ++x) {
      const Vec2 p = known.centre(x, y);
      const Vec2 lo = known.lo(), hi = known.hi();
      if (p.x() - lo.x() < r || hi.x() - p.x() < r || p.y() - lo.y() < r || hi.y() - p.y() < r) {
        blocked_[y * nx + x] = 1;
      }
      if (known.at(x, y) != KnownSpace::Cell::kOccupied) continue;
      const bool bump = known.bumped(x, y);
      for (const auto& [dx, dy] : disc) {
        const int jx = x + dx, jy = y + dy;
        if (jx < 0 || jy < 0 || jx >= nx || jy >= ny) continue;
        blocked_[jy * nx + jx] = 1;
        if (bump) near_bump[jy * nx + jx] = 1;
      }
    }
  }
  inflated_ = blocked_;
  // Where the robot has been it fits: a cell its centre drove through is passable though the
  // inflation covers it (an obstacle found after it passed, with less than the margin to
  // spare), unless within the inflation of a bump (where the rim touched: a path there would
  // touch again) or itself occupied.
  for (int y = 0; y < ny; ++y) {
    for (int x = 0; x < nx; ++x) {
      const int i = y * nx + x;
      if (blocked_[i] && known.visited(x, y) && !near_bump[i] &&
          known.at(x, y) != KnownSpace::Cell::kOccupied) {
        blocked_[i] = 0;
      }
    }
  }
}

bool Costmap::blocked(int ix, int iy) const {
  if (ix < 0 || iy < 0 || ix >= known_.nx() || iy >= known_.ny()) return true;
  return blocked_[iy * known_.nx() + ix] != 0;
}

bool Costmap::inflated(int ix, int iy) const {
  if (ix < 0 || iy < 0 || ix >= known_.nx() || iy >= known_.ny()) return true;
  return inflated_[iy * known_.nx() + ix] != 0;
}

bool Costmap::blocked(const Vec2& p) const {
  int ix, iy;
  if (!known_.index(p, ix, iy)) return true;
  return blocked(ix, iy);
}

std::optional<PathPlan> planPath(const Costmap& costmap, const Vec2& from, const Vec2& to) {
  const KnownSpace& k = costmap.known();
  int gx, gy;
  if (!k.index(to, gx, gy) || costmap.blocked(gx, gy)) return std::nullopt;
  const int goal = gy * k.nx() + gx;
  const SearchResult r = search(costmap, from, goal);
  const int end = r.start < 0 ? -1 : r.best(goal);
  if (end < 0) return std::nullopt;
  std::vector<int> cells;
  for (int i = end; i != r.start; i = r.parent[i]) cells.push_back(i / 2);
  std::reverse(cells.begin(), cells.end());
  PathPlan plan;
  plan.cost = r.cost[end];
  const auto at = [&](int i) { return k.centre(i % k.nx(), i / k.nx()); };
  // Line-of-sight shortening (the "string pulling" of grid paths): from each anchor, go straight
  // to the farthest later cell it sees over the inflated grid. While the start is inside an
  // inflated obstacle the raw cells are kept until the path leaves it.
  std::vector<Vec2> pts;
  std::size_t i = 0;
  Vec2 anchor = from;
  while (i < cells.size() && costmap.blocked(at(cells[i]))) {
    pts.push_back(at(cells[i]));
    anchor = pts.back();
    ++i;
  }
  while (i < cells.size()) {
    std::size_t best = i;
    for (std::size_t j = cells.size(); j-- > i;) {
      const Vec2 target = j + 1 == cells.size() ? to : at(cells[j]);
      if (lineOfSight(costmap, anchor, target)) {
        best = j;
        break;
      }
    }
    anchor = best + 1 == cells.size() ? to : at(cells[best]);
    pts.push_back(anchor);
    i = best + 1;
  }
  if (pts.empty()) pts.push_back(to);  // already in the goal's cell
  pts.back() = to;
  Vec2 prev = from;
  for (const Vec2& p : pts) {
    plan.length += (p - prev).norm();
    prev = p;
  }
  plan.waypoints = std::move(pts);
  return plan;
}

DistanceField::DistanceField(const Costmap& costmap, const Vec2& from) : costmap_(costmap) {
  const std::size_t n = static_cast<std::size_t>(costmap.known().nx()) * costmap.known().ny();
  dist_.assign(n, kInf);
  parent_.assign(n, -1);
  const SearchResult r = search(costmap, from, -1);
  if (r.start < 0) return;
  // Each cell's least state; its parent is the cell of that state's parent (a cell reached in
  // both phases, a trail cell of the escape also reached from outside, keeps the better).
  for (std::size_t i = 0; i < n; ++i) {
    const int b = r.best(static_cast<int>(i));
    if (b < 0) continue;
    dist_[i] = r.cost[static_cast<std::size_t>(b)];
    if (r.parent[static_cast<std::size_t>(b)] >= 0) parent_[i] = r.parent[static_cast<std::size_t>(b)] / 2;
  }
}

double DistanceField::to(int ix, int iy) const {
  if (costmap_.blocked(ix, iy)) return kInf;
  return dist_[iy * costmap_.known().nx() + ix];
}

double DistanceField::to(const Vec2& p) const {
  int ix, iy;
  if (!costmap_.known().index(p, ix, iy)) return kInf;
  return to(ix, iy);
}

}  // namespace crunch::exploration
