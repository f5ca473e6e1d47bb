#include "crunch/mapping/evaluation.h"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace crunch {

namespace {
// Phantom tables this close to a wall are most likely the wall mistaken for a table edge.
constexpr double kNearWallDistance = 0.3;

double centreDistance(const MapTable& mapped, const TableSpec& truth) {
  return std::hypot(mapped.pose.x - truth.pose.x, mapped.pose.y - truth.pose.y);
}

// Orientation error modulo pi: a table turned half way round is the same table.
double angleError(const MapTable& mapped, const TableSpec& truth) {
  return std::abs(wrapPeriod(mapped.pose.theta - truth.pose.theta, kPi));
}
}  // namespace

bool tableMatches(const MapTable& mapped, const TableSpec& truth, const MatchTolerance& tol) {
  return centreDistance(mapped, truth) <= tol.position && angleError(mapped, truth) <= tol.angle;
}

Evaluation evaluate(const Map& map, const Scene& scene, const MatchTolerance& tol) {
  Evaluation ev;
  ev.true_tables = static_cast<int>(scene.tables.size());
  ev.fused_tables = static_cast<int>(map.tables.size());

  // Greedy one-to-one matching: closest matching pairs first. Ties break on the indices so the
  // result does not depend on the sort's stability.
  struct Pair {
    double distance;
    size_t fused, truth;
  };
  std::vector<Pair> pairs;
  for (size_t i = 0; i < map.tables.size(); ++i) {
    for (size_t j = 0; j < scene.tables.size(); ++j) {
      if (tableMatches(map.tables[i], scene.tables[j], tol)) {
        pairs.push_back({centreDistance(map.tables[i], scene.tables[j]), i, j});
      }
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) {
    return std::tie(a.distance, a.fused, a.truth) < std::tie(b.distance, b.fused, b.truth);
  });
  std::vector<bool> fused_used(map.tables.size(), false), truth_used(scene.tables.size(), false);
  double position_sum = 0.0, angle_sum = 0.0;
  for (const Pair& p : pairs) {
    if (fused_used[p.fused] || truth_used[p.truth]) continue;
    fused_used[p.fused] = truth_used[p.truth] = true;
    ++ev.matched;
    position_sum += p.distance;
    angle_sum += angleError(map.tables[p.fused], scene.tables[p.truth]);
  }

  ev.precision = ev.fused_tables == 0 ? 1.0 : static_cast<double>(ev.matched) / ev.fused_tables;
  ev.recall = ev.true_tables == 0 ? 1.0 : static_cast<double>(ev.matched) / ev.true_tables;
  const double pr = ev.precision + ev.recall;
  ev.f1 = pr > 0.0 ? 2.0 * ev.precision * ev.recall / pr : 0.0;
  if (ev.matched > 0) {
    ev.mean_position_error = position_sum / ev.matched;
    ev.mean_angle_error = angle_sum / ev.matched;
  }

  // Per-pose MAPs are judged individually: each table either matches some real table or not.
  int per_pose_matched = 0;
  for (const PoseMap& pm : map.per_pose) {
    for (const MapTable& t : pm.tables) {
      ++ev.per_pose_tables;
      const bool any =
          std::any_of(scene.tables.begin(), scene.tables.end(),
                      [&](const TableSpec& truth) { return tableMatches(t, truth, tol); });
      if (any) ++per_pose_matched;
    }
  }
  ev.per_pose_match_fraction =
      ev.per_pose_tables == 0 ? 0.0 : static_cast<double>(per_pose_matched) / ev.per_pose_tables;

  const std::vector<WallSpec> walls = scene.allWalls();
  for (size_t i = 0; i < map.tables.size(); ++i) {
    if (fused_used[i]) continue;
    const OrientedRect top{map.tables[i].pose, map.tables[i].width, map.tables[i].depth};
    const bool near_wall = std::any_of(walls.begin(), walls.end(), [&](const WallSpec& w) {
      return distanceRectSegment(top, w.a, w.b) <= kNearWallDistance;
    });
    ++(near_wall ? ev.phantoms_near_walls : ev.phantoms_elsewhere);
  }
  return ev;
}

}  // namespace crunch
