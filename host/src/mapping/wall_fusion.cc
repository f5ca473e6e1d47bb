#include "crunch/mapping/wall_fusion.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "crunch/blackboard/params.h"
#include "crunch/core/geometry.h"

namespace crunch {

namespace {
struct Member {
  int chain;
  Vec2 a, b;
  double length;
};

struct Group {
  Vec2 centre;  // a point of the line
  Vec2 dir;     // unit direction
  double weight = 0;
  double t0 = 0, t1 = 0;  // extent along the line
  std::vector<Member> members;

  void add(const Member& m) {
    Vec2 d = (m.b - m.a) / std::max(m.length, 1e-12);
    if (members.empty()) {
      centre = 0.5 * (m.a + m.b);
      dir = d;
      t0 = -0.5 * m.length;
      t1 = 0.5 * m.length;
    } else {
      if (d.dot(dir) < 0) d = -d;
      const double w = weight + m.length;
      Vec2 nd = weight * dir + m.length * d;
      nd /= nd.norm();
      const Vec2 nc = (weight * centre + m.length * 0.5 * (m.a + m.b)) / w;
      // Re-express the extent on the new line.
      const Vec2 e0 = centre + t0 * dir, e1 = centre + t1 * dir;
      centre = nc;
      dir = nd;
      t0 = std::min({(e0 - centre).dot(dir), (e1 - centre).dot(dir), (m.a - centre).dot(dir),
                     (m.b - centre).dot(dir)});
      t1 = std::max({(e0 - centre).dot(dir), (e1 - centre).dot(dir), (m.a - centre).dot(dir),
                     (m.b - centre).dot(dir)});
    }
    weight += m.length;
    members.push_back(m);
  }

  bool accepts(const Member& m, const WallFuseOptions& opt) const {
    const Vec2 d = (m.b - m.a) / std::max(m.length, 1e-12);
    if (std::abs(wrapPeriod(std::atan2(d.y(), d.x()) - std::atan2(dir.y(), dir.x()), kPi)) >
        opt.angle)
      return false;
    const auto across = [&](const Vec2& q) {
      const Vec2 v = q - centre;
      return std::abs(v.x() * dir.y() - v.y() * dir.x());
    };
    if (across(m.a) > opt.offset || across(m.b) > opt.offset) return false;
    const double ma = (m.a - centre).dot(dir), mb = (m.b - centre).dot(dir);
    return std::min(ma, mb) <= t1 + opt.gap && std::max(ma, mb) >= t0 - opt.gap;
  }
};

// Walls end at walls: each end of `walls` within `radius` of another wall's segment at a
// junction's angle moves along its own line to the two lines' crossing (the nearest such wall's,
// when there are several). Every move is computed from the walls as they came, so the order of
// the walls does not matter; an end is left where it is when the crossing lies more than
// 2 radius away (a shallow angle) or would leave the wall shorter than `radius`.
void meetAtJunctions(std::vector<MapWall>& walls, double radius) {
  const std::vector<MapWall> in = walls;
  for (size_t i = 0; i < in.size(); ++i) {
    const MapWall& w = in[i];
    const double len = (w.b - w.a).norm();
    if (len <= 0.0) continue;
    const Vec2 u = (w.b - w.a) / len;
    const double angle = std::atan2(u.y(), u.x());
    for (const bool at_b : {false, true}) {
      const Vec2 e = at_b ? w.b : w.a;
      double nearest = radius, s_at = 0.0;
      bool found = false;
      for (size_t j = 0; j < in.size(); ++j) {
        const Vec2 d = in[j].b - in[j].a;
        if (j == i || d.norm() <= 0.0 || !wallEndMeets(e, angle, in[j].a, in[j].b, nearest))
          continue;
        const double dist = distanceToSegment(e, in[j].a, in[j].b);
        if (found && dist == nearest) continue;
        nearest = dist;
        s_at = cross2d(in[j].a - w.a, d) / cross2d(u, d);  // along u from w.a to the crossing
        found = true;
      }
      if (!found) continue;
      const Vec2 p = w.a + s_at * u;
      const double kept = at_b ? s_at : len - s_at;
      if ((p - e).norm() > 2.0 * radius || kept < radius) continue;
      (at_b ? walls[i].b : walls[i].a) = p;
    }
  }
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}
}  // namespace

std::vector<MapWall> fuseWalls(const std::vector<std::vector<WallHyp>>& chains,
                               const WallFuseOptions& opt) {
  // Longest walls first: they fix the lines the shorter pieces join.
  std::vector<Member> all;
  for (size_t c = 0; c < chains.size(); ++c)
    for (const WallHyp& w : chains[c])
      if (w.length() > 0) all.push_back({static_cast<int>(c), w.a, w.b, w.length()});
  std::stable_sort(all.begin(), all.end(),
                   [](const Member& x, const Member& y) { return x.length > y.length; });
  std::vector<Group> groups;
  for (const Member& m : all) {
    auto it = std::find_if(groups.begin(), groups.end(),
                           [&](const Group& g) { return g.accepts(m, opt); });
    if (it == groups.end()) {
      groups.emplace_back();
      groups.back().add(m);
    } else {
      it->add(m);
    }
  }
  std::vector<MapWall> out;
  const double n_chains = std::max<double>(1.0, static_cast<double>(chains.size()));
  for (const Group& g : groups) {
    // Per chain: the extent of its pieces along the group's line.
    std::vector<double> lo, hi;
    for (size_t c = 0; c < chains.size(); ++c) {
      double a = 0, b = 0;
      bool any = false;
      for (const Member& m : g.members) {
        if (m.chain != static_cast<int>(c)) continue;
        const double ta = (m.a - g.centre).dot(g.dir), tb = (m.b - g.centre).dot(g.dir);
        a = any ? std::min({a, ta, tb}) : std::min(ta, tb);
        b = any ? std::max({b, ta, tb}) : std::max(ta, tb);
        any = true;
      }
      if (any) {
        lo.push_back(a);
        hi.push_back(b);
      }
    }
    const double score = static_cast<double>(lo.size()) / n_chains;
    if (score < opt.min_score) continue;
    MapWall w;
    w.a = g.centre + median(lo) * g.dir;
    w.b = g.centre + median(hi) * g.dir;
    w.score = score;
    out.push_back(w);
  }
  if (opt.junction > 0.0) meetAtJunctions(out, opt.junction);
  return out;
}

WallStraddle straddle(const OrientedRect& r, const Vec2& a, const Vec2& b) {
  WallStraddle out;
  const double len = (b - a).norm();
  if (len <= 0.0) return out;
  const Vec2 u = (b - a) / len, n{-u.y(), u.x()};
  // The footprint in the wall's frame (t along it, s to its left), clipped to 0 <= t <= len
  // (Sutherland-Hodgman against the two ends' half-planes).
  std::array<Vec2, 4> corners = r.corners();
  std::array<Vec2, 8> poly{}, next{};
  int count = 0;
  for (const Vec2& c : corners) poly[static_cast<size_t>(count++)] = {(c - a).dot(u), (c - a).dot(n)};
  const auto clip = [&](double sign, double bound) {  // keep sign * t <= sign * bound
    int m = 0;
    for (int i = 0; i < count; ++i) {
      const Vec2 p = poly[static_cast<size_t>(i)], q = poly[static_cast<size_t>((i + 1) % count)];
      const double dp = sign * (p.x() - bound), dq = sign * (q.x() - bound);
      if (dp <= 0.0) next[static_cast<size_t>(m++)] = p;
      if (dp * dq < 0.0)
        next[static_cast<size_t>(m++)] = p + (q - p) * (dp / (dp - dq));
    }
    count = m;
    poly = next;
  };
  clip(-1.0, 0.0);
  clip(1.0, len);
  for (int i = 0; i < count; ++i) {
    out.front = std::max(out.front, poly[static_cast<size_t>(i)].y());
    out.behind = std::max(out.behind, -poly[static_cast<size_t>(i)].y());
  }
  return out;
}

void keepOneWorld(std::vector<MapTable>& tables, std::vector<MapWall>& walls, double band) {
  std::vector<bool> drop_table(tables.size(), false), drop_wall(walls.size(), false);
  for (size_t i = 0; i < tables.size(); ++i) {
    const MapTable& t = tables[i];
    for (size_t j = 0; j < walls.size(); ++j) {
      const WallStraddle s = straddle({t.pose, t.width, t.depth}, walls[j].a, walls[j].b);
      if (std::min(s.front, s.behind) <= band) continue;
      if (walls[j].score >= t.score) drop_table[i] = true;
      else drop_wall[j] = true;
    }
  }
  size_t k = 0;
  for (size_t i = 0; i < tables.size(); ++i)
    if (!drop_table[i]) tables[k++] = tables[i];
  tables.resize(k);
  k = 0;
  for (size_t j = 0; j < walls.size(); ++j)
    if (!drop_wall[j]) walls[k++] = walls[j];
  walls.resize(k);
}

}  // namespace crunch
