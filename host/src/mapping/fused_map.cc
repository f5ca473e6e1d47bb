#include "crunch/mapping/fused_map.h"

#include "crunch/core/range_check.h"

#include <algorithm>
#include <cmath>

namespace crunch {

Status FuseOptions::validate() const {
  const Status checks[] = {checkAbove("radius", radius, 0.0, 10.0),
                           checkAbove("angle", angle, 0.0, kPi),
                           checkCount("min_support", min_support, 1, 1000000),
                           checkAbove("reach", reach, 0.0, 10.0),
                           checkAbove("size", size, 0.0, 10.0),
                           checkRange("clash_depth", clash_depth, 0.0, 0.5)};
  for (const Status& s : checks) {
    if (!s) return s;
  }
  return okStatus();
}

namespace {
struct Item {
  Pose2 pose;
  bool used = false;
  MapTable table;  // with its size (compared when FuseOptions::compare_sizes)
};

// Mean pose of `members`; angles modulo pi averaged as doubled angles on the circle.
Pose2 meanPose(const std::vector<Item>& items, const std::vector<size_t>& members) {
  double x = 0, y = 0, c = 0, s = 0;
  for (size_t i : members) {
    x += items[i].pose.x;
    y += items[i].pose.y;
    c += std::cos(2 * items[i].pose.theta);
    s += std::sin(2 * items[i].pose.theta);
  }
  const double n = static_cast<double>(members.size());
  double th = 0.5 * std::atan2(s, c);
  if (th < 0) th += kPi;
  return {x / n, y / n, th};
}

// The mean of a cluster of sized tables: mean pose and sizes; a near-square cluster averages
// its angles modulo pi/2 (quadrupled angles), each member first turned to within pi/4 of it.
MapTable meanTable(const std::vector<Item>& items, const std::vector<size_t>& members,
                   const FuseOptions& opt) {
  MapTable t;
  t.pose = meanPose(items, members);
  double w = 0, d = 0, l = 0;
  for (size_t i : members) {
    w += items[i].table.width;
    d += items[i].table.depth;
    l += items[i].table.leg;
  }
  const double n = static_cast<double>(members.size());
  t.width = w / n;
  t.depth = d / n;
  t.leg = l / n;
  if (nearSquare(t, opt.size)) {
    double c = 0, s = 0;
    for (size_t i : members) {
      c += std::cos(4 * items[i].pose.theta);
      s += std::sin(4 * items[i].pose.theta);
    }
    t.pose.theta = wrapHalfTurn(0.25 * std::atan2(s, c));
  }
  return t;
}
}  // namespace

std::vector<MapTable> fuseTables(const std::vector<PoseMap>& per_pose, const FuseOptions& opt) {
  std::vector<Item> items;
  for (const PoseMap& pm : per_pose)
    for (const MapTable& t : pm.tables) items.push_back({t.pose, false, t});

  // Greedy: seed each cluster at the item with the most unused neighbours, take its neighbours,
  // re-centre once on their mean and take the neighbours of the mean.
  std::vector<MapTable> clusters;
  std::vector<size_t> members;
  for (;;) {
    size_t best = items.size();
    int best_count = 0;
    for (size_t i = 0; i < items.size(); ++i) {
      if (items[i].used) continue;
      int count = 0;
      for (const Item& o : items) count += (!o.used && tablesAgree(items[i].table, o.table, opt));
      if (count > best_count) {
        best_count = count;
        best = i;
      }
    }
    if (best == items.size() || best_count < opt.min_support) break;
    members.clear();
    for (size_t j = 0; j < items.size(); ++j)
      if (!items[j].used && tablesAgree(items[best].table, items[j].table, opt)) members.push_back(j);
    const MapTable centre = opt.compare_sizes ? meanTable(items, members, opt)
                                              : MapTable{meanPose(items, members)};
    std::vector<size_t> refined;
    for (size_t j = 0; j < items.size(); ++j)
      if (!items[j].used && tablesAgree(centre, items[j].table, opt)) refined.push_back(j);
    if (refined.size() >= members.size()) members = refined;
    for (size_t j : members) items[j].used = true;
    MapTable t;
    if (opt.compare_sizes) t = meanTable(items, members, opt);
    else t.pose = meanPose(items, members);
    t.support = static_cast<int>(members.size());
    clusters.push_back(t);
  }

  // Two tables cannot overlap: keep the better supported one (clusters come best first).
  std::vector<MapTable> fused = withoutClashes(clusters, opt);

  scoreBySupport(fused, per_pose, opt);
  return fused;
}

bool tablesAgree(const MapTable& a, const MapTable& b, const FuseOptions& opt) {
  if (!opt.compare_sizes) return tablesAgree(a.pose, b.pose, opt);
  if (std::abs(a.width - b.width) > opt.size || std::abs(a.depth - b.depth) > opt.size)
    return false;
  const double period = nearSquare(a, opt.size) && nearSquare(b, opt.size) ? kPi / 2 : kPi;
  return std::hypot(a.pose.x - b.pose.x, a.pose.y - b.pose.y) <= opt.radius &&
         std::abs(wrapPeriod(a.pose.theta - b.pose.theta, period)) <= opt.angle;
}

bool tablesClash(const MapTable& a, const MapTable& b, const FuseOptions& opt) {
  const double d = opt.clash_depth;
  const auto shrunk = [d](const MapTable& t) {
    return OrientedRect{t.pose, std::max(0.0, t.width - d), std::max(0.0, t.depth - d)};
  };
  return overlaps(shrunk(a), shrunk(b));
}

std::vector<MapTable> withoutClashes(const std::vector<MapTable>& best_first, const FuseOptions& opt) {
  std::vector<MapTable> kept;
  for (const MapTable& t : best_first)
    if (std::none_of(kept.begin(), kept.end(), [&](const MapTable& k) { return tablesClash(t, k, opt); }))
      kept.push_back(t);
  return kept;
}

bool tablesAgree(const Pose2& a, const Pose2& b, const FuseOptions& opt) {
  return std::hypot(a.x - b.x, a.y - b.y) <= opt.radius &&
         std::abs(wrapPeriod(a.theta - b.theta, kPi)) <= opt.angle;
}

void scoreBySupport(std::vector<MapTable>& tables, const std::vector<PoseMap>& per_pose,
                    const FuseOptions& opt) {
  for (MapTable& t : tables) {
    int within = 0;
    for (const PoseMap& pm : per_pose)
      within += std::hypot(pm.pose.x - t.pose.x, pm.pose.y - t.pose.y) <= opt.reach;
    t.score = within > 0 ? std::min(1.0, static_cast<double>(t.support) / within) : 0.0;
  }
}

}  // namespace crunch
