#include "crunch/exploration/draw_completion.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "crunch/core/geometry.h"

namespace crunch::exploration {

namespace {

OrientedRect topOf(const MapTable& t) { return {t.pose, t.width, t.depth}; }

// One proposal from the prior: a table with `leg` at corner k, axes along the leg's faces.
MapTable propose(const MapLeg& leg, const ModelParams& model, Rng& rng) {
  MapTable t;
  if (model.sized()) {
    // The mixture (1 - w) U + w N of ModelParams: with weight catalog_weight the catalog's size,
    // each side Gaussian about it (catalog_sigma); else uniform over the prior's region
    // {min <= shorter <= max_short, longer <= max_long} (the square [min, max_long]^2 cut by the
    // shorter side's bound; rejection inside it is uniform). Which way round the catalog's top
    // lies is the placement's (j below).
    if (rng.uniform() < model.catalog_weight) {
      t.width = rng.normal(model.table_width, model.catalog_sigma);
      t.depth = rng.normal(model.table_depth, model.catalog_sigma);
    } else {
      do {
        t.width = rng.uniform(model.size_min_side, model.size_max_long);
        t.depth = rng.uniform(model.size_min_side, model.size_max_long);
      } while (std::min(t.width, t.depth) > model.size_max_short);
    }
    t.leg = leg.side;
  } else {
    t.width = model.table_width;
    t.depth = model.table_depth;
    t.leg = model.leg_side;
  }
  const int j = static_cast<int>(rng.uniform() * 2.0) & 1;
  const int k = static_cast<int>(rng.uniform() * 4.0) & 3;
  const double theta = leg.pose.theta + 0.5 * kPi * j;
  const Vec2 off = ModelParams::cornerOffset(k, t.width, t.depth, t.leg);
  const double c = std::cos(theta), s = std::sin(theta);
  t.pose = Pose2{leg.pose.x - (c * off.x() - s * off.y()), leg.pose.y - (s * off.x() + c * off.y()),
                 wrapHalfTurn(theta)};
  return t;
}

bool admissible(const MapTable& t, const MapLeg& leg, const MapSample& draw,
                const KnownSpace& known, const ModelParams& model) {
  if (model.sized() && !std::isfinite(model.logSizePrior(t.width, t.depth, t.leg))) return false;
  const double c = std::cos(t.pose.theta), s = std::sin(t.pose.theta);
  for (int i = 0; i < 4; ++i) {
    const Vec2 q = t.pose.toWorld(ModelParams::cornerOffset(i, t.width, t.depth, t.leg), c, s);
    if ((q - leg.pose.position()).norm() < 0.5 * t.leg) continue;  // the orphan itself
    if (known.outside(q) || known.at(q) == KnownSpace::Cell::kFree) return false;
  }
  const OrientedRect top = topOf(t);
  for (const MapTable& other : draw.tables)
    if (overlaps(top, topOf(other))) return false;
  return true;
}

}  // namespace

int completeOrphanLegs(MapSample& draw, const KnownSpace& known, const ModelParams& model,
                       Rng& rng, int tries) {
  int completed = 0;
  for (size_t i = 0; i < draw.legs.size();) {
    const MapLeg leg = draw.legs[i];
    bool done = false;
    for (int n = 0; n < tries && !done; ++n) {
      const MapTable t = propose(leg, model, rng);
      if (!admissible(t, leg, draw, known, model)) continue;
      draw.tables.push_back(t);
      done = true;
    }
    if (done) {
      draw.legs.erase(draw.legs.begin() + static_cast<std::ptrdiff_t>(i));
      ++completed;
    } else {
      ++i;
    }
  }
  return completed;
}

int mergeRepeats(MapSample& draw, const FuseOptions& fuse) {
  const size_t before = draw.tables.size() + draw.legs.size();
  draw.tables = withoutClashes(draw.tables, fuse);
  const auto onTableLeg = [&](const MapLeg& leg) {
    for (const MapTable& t : draw.tables) {
      const double c = std::cos(t.pose.theta), s = std::sin(t.pose.theta);
      const double near = std::max(leg.side, t.leg);
      for (int i = 0; i < 4; ++i) {
        const Vec2 q = t.pose.toWorld(ModelParams::cornerOffset(i, t.width, t.depth, t.leg), c, s);
        if ((q - leg.pose.position()).squaredNorm() < near * near) return true;
      }
    }
    return false;
  };
  draw.legs.erase(std::remove_if(draw.legs.begin(), draw.legs.end(), onTableLeg), draw.legs.end());
  return static_cast<int>(before - draw.tables.size() - draw.legs.size());
}

}  // namespace crunch::exploration
