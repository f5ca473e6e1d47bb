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

// The real table written width >= depth (turned a quarter when its depth is the longer side).
TableSpec canonical(const TableSpec& t) {
  TableSpec c = t;
  if (c.depth > c.width) {
    std::swap(c.width, c.depth);
    c.pose.theta += kPi / 2;
  }
  return c;
}

bool judgesSize(const MatchTolerance& tol) { return std::isfinite(tol.size); }

// Orientation error with sizes: modulo pi/2 when both are square within the tolerance.
double sizedAngleError(const MapTable& mapped, const TableSpec& truth, double tol_size) {
  const TableSpec c = canonical(truth);
  const bool square = std::abs(mapped.width - mapped.depth) <= tol_size &&
                      std::abs(c.width - c.depth) <= tol_size;
  return std::abs(wrapPeriod(mapped.pose.theta - c.pose.theta, square ? kPi / 2 : kPi));
}

bool contains(const TableSpec& t, const Vec2& p) {
  const Vec2 q = t.pose.toLocal(p);
  return std::abs(q.x()) <= 0.5 * t.width && std::abs(q.y()) <= 0.5 * t.depth;
}
}  // namespace

MatchTolerance matchToleranceFor(const ModelParams& model) {
  MatchTolerance tol;
  if (model.sized()) tol.size = 0.05;
  return tol;
}

bool tableMatches(const MapTable& mapped, const TableSpec& truth, const MatchTolerance& tol) {
  if (!judgesSize(tol))
    return centreDistance(mapped, truth) <= tol.position && angleError(mapped, truth) <= tol.angle;
  const TableSpec c = canonical(truth);
  return centreDistance(mapped, truth) <= tol.position &&
         sizedAngleError(mapped, truth, tol.size) <= tol.angle &&
         std::abs(mapped.width - c.width) <= tol.size &&
         std::abs(mapped.depth - c.depth) <= tol.size && std::abs(mapped.leg - c.leg) <= tol.size;
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
    const MapTable& m = map.tables[p.fused];
    const TableSpec c = canonical(scene.tables[p.truth]);
    angle_sum += judgesSize(tol) ? sizedAngleError(m, scene.tables[p.truth], tol.size)
                                 : angleError(m, scene.tables[p.truth]);
    const double ew = std::abs(m.width - c.width), ed = std::abs(m.depth - c.depth),
                 el = std::abs(m.leg - c.leg);
    ev.mean_width_error += ew;
    ev.mean_depth_error += ed;
    ev.mean_leg_error += el;
    ev.max_width_error = std::max(ev.max_width_error, ew);
    ev.max_depth_error = std::max(ev.max_depth_error, ed);
    ev.max_leg_error = std::max(ev.max_leg_error, el);
  }
  if (ev.matched > 0) {
    ev.mean_width_error /= ev.matched;
    ev.mean_depth_error /= ev.matched;
    ev.mean_leg_error /= ev.matched;
  }
  for (const TableSpec& truth : scene.tables) {
    int inside = 0;
    for (const MapTable& m : map.tables) inside += contains(truth, m.pose.position());
    ev.split_objects += inside >= 2;
  }
  for (const MapTable& m : map.tables) {
    const TableSpec top{m.pose, m.width, m.depth, m.leg};
    int inside = 0;
    for (const TableSpec& truth : scene.tables) inside += contains(top, truth.pose.position());
    ev.merged_objects += inside >= 2;
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

namespace {
constexpr double kWallContact = 0.02;
constexpr double kWallCoverDistance = 0.05;
constexpr double kWallCoverAngle = 10.0 * kPi / 180.0;
constexpr double kWallSample = 0.01;

double segAngle(const Vec2& a, const Vec2& b) { return std::atan2(b.y() - a.y(), b.x() - a.x()); }

// Calls f(point) at the centres of the ~1 cm pieces of a..b; returns the piece length.
template <typename F>
double forSamples(const Vec2& a, const Vec2& b, F&& f) {
  const double len = (b - a).norm();
  const int n = std::max(1, static_cast<int>(std::ceil(len / kWallSample)));
  for (int k = 0; k < n; ++k) f(Vec2(a + (b - a) * ((k + 0.5) / n)));
  return len / n;
}

bool nearSegment(const Vec2& p, double angle, const Vec2& a, const Vec2& b) {
  return distanceToSegment(p, a, b) <= kWallCoverDistance &&
         std::abs(wrapPeriod(segAngle(a, b) - angle, kPi)) <= kWallCoverAngle;
}
}  // namespace

WallEvaluation evaluateWalls(const Map& map, const Scene& scene) {
  WallEvaluation ev;
  ev.evaluated = true;
  ev.mapped_walls = static_cast<int>(map.walls.size());
  const std::vector<WallSpec> all = scene.allWalls();
  // allWalls(): the boundary's four and then the interior ones (scene.h); identify the interior
  // ones by value so the order does not matter.
  const auto interior = [&](const WallSpec& w) {
    return std::any_of(scene.walls.begin(), scene.walls.end(), [&](const WallSpec& x) {
      return (x.a - w.a).norm() < 1e-12 && (x.b - w.b).norm() < 1e-12;
    });
  };
  double b_touched = 0, b_covered = 0, i_touched = 0, i_touched_cov = 0, i_len = 0, i_cov = 0;
  for (const WallSpec& w : all) {
    const bool inner = interior(w);
    std::vector<Vec2> contacts;
    for (const Shapelet& s : map.shapelets)
      if (distanceToSegment({s.x, s.y}, w.a, w.b) <= kWallContact) contacts.push_back({s.x, s.y});
    const double ang = segAngle(w.a, w.b);
    const double piece = forSamples(w.a, w.b, [](const Vec2&) {});
    forSamples(w.a, w.b, [&](const Vec2& p) {
      const bool touched = std::any_of(contacts.begin(), contacts.end(), [&](const Vec2& c) {
        return (c - p).norm() <= kWallContact;
      });
      const bool covered = std::any_of(map.walls.begin(), map.walls.end(), [&](const MapWall& m) {
        return nearSegment(p, ang, m.a, m.b);
      });
      if (inner) {
        i_len += piece;
        i_cov += covered ? piece : 0.0;
        if (touched) {
          i_touched += piece;
          i_touched_cov += covered ? piece : 0.0;
        }
      } else if (touched) {
        b_touched += piece;
        b_covered += covered ? piece : 0.0;
      }
    });
  }
  for (const MapWall& m : map.walls) {
    ev.mapped_length += (m.b - m.a).norm();
    const double ang = segAngle(m.a, m.b);
    const double piece = forSamples(m.a, m.b, [](const Vec2&) {});
    forSamples(m.a, m.b, [&](const Vec2& p) {
      const bool real = std::any_of(all.begin(), all.end(), [&](const WallSpec& w) {
        return nearSegment(p, ang, w.a, w.b);
      });
      if (!real) ev.false_length += piece;
    });
  }
  ev.boundary_touched = b_touched;
  ev.boundary_coverage = b_touched > 0 ? b_covered / b_touched : 1.0;
  ev.interior_length = i_len;
  ev.interior_found = i_len > 0 ? i_cov / i_len : 1.0;
  ev.interior_touched = i_touched;
  ev.interior_touched_coverage = i_touched > 0 ? i_touched_cov / i_touched : 1.0;
  return ev;
}

}  // namespace crunch
