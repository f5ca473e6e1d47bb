#include "crunch/exploration/entropy_policy.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include "crunch/exploration/whisk_prediction.h"

namespace crunch::exploration {
namespace {

double h2(double p) {
  if (!(p > 0.0) || !(p < 1.0)) return 0.0;
  return -(p * std::log2(p) + (1.0 - p) * std::log2(1.0 - p));
}

bool inside(const OrientedRect& r, const Vec2& p) {
  const Vec2 l = r.pose.toLocal(p);
  return std::abs(l.x()) <= 0.5 * r.size_x && std::abs(l.y()) <= 0.5 * r.size_y;
}

// Sets `bit` in the cells of `grid` whose centre is inside `r`.
void fill(FovealGrid& g, std::vector<std::uint64_t>& layer, const OrientedRect& r,
          std::uint64_t bit) {
  const double rad = r.circumradius();
  const Vec2 c = r.pose.position();
  const int x0 = std::max(0, static_cast<int>(std::floor((c.x() - rad - g.lo.x()) / g.cell)));
  const int x1 = std::min(g.n - 1, static_cast<int>(std::floor((c.x() + rad - g.lo.x()) / g.cell)));
  const int y0 = std::max(0, static_cast<int>(std::floor((c.y() - rad - g.lo.y()) / g.cell)));
  const int y1 = std::min(g.n - 1, static_cast<int>(std::floor((c.y() + rad - g.lo.y()) / g.cell)));
  for (int iy = y0; iy <= y1; ++iy)
    for (int ix = x0; ix <= x1; ++ix)
      if (inside(r, g.centre(ix, iy))) layer[static_cast<size_t>(iy * g.n + ix)] |= bit;
}

}  // namespace

FovealGrid rasteriseFovea(std::span<const MapSample> samples, const Vec2& centre,
                          const EntropyOptions& o) {
  FovealGrid g;
  g.cell = o.cell;
  g.n = std::max(1, static_cast<int>(std::lround(o.fovea_side / o.cell)));
  g.lo = centre - Vec2(0.5 * g.n * g.cell, 0.5 * g.n * g.cell);
  g.draws = static_cast<int>(std::min<size_t>(samples.size(), 64));
  g.table.assign(static_cast<size_t>(g.n * g.n), 0);
  g.leg.assign(static_cast<size_t>(g.n * g.n), 0);
  for (int s = 0; s < g.draws; ++s) {
    const std::uint64_t bit = std::uint64_t{1} << s;
    for (const MapTable& t : samples[static_cast<size_t>(s)].tables) {
      fill(g, g.table, OrientedRect{t.pose, t.width, t.depth}, bit);
      for (const OrientedRect& leg : legSquares(t)) {
        fill(g, g.leg, leg, bit);
        // A leg no wider than a cell may cover no cell centre: the cell holding its centre.
        const Vec2 c = leg.pose.position() - g.lo;
        const int ix = static_cast<int>(std::floor(c.x() / g.cell));
        const int iy = static_cast<int>(std::floor(c.y() / g.cell));
        if (ix >= 0 && iy >= 0 && ix < g.n && iy < g.n) g.leg[static_cast<size_t>(iy * g.n + ix)] |= bit;
      }
    }
  }
  return g;
}

double entropyDelta(const FovealGrid& g, int ax, int ay) {
  const std::uint64_t all = g.draws >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << g.draws) - 1;
  const std::uint64_t with = g.leg[static_cast<size_t>(ay * g.n + ax)] & all;
  const std::uint64_t without = ~with & all;
  const double n1 = std::popcount(with), n0 = std::popcount(without);
  double dh = 0.0;
  for (const std::uint64_t t : g.table) {
    const double p1 = (std::popcount(t & with) + 1.0) / (n1 + 2.0);     // eq. 34, b = leg
    const double p0 = (std::popcount(t & without) + 1.0) / (n0 + 2.0);  // eq. 34, b = no leg
    dh += h2(p1) - h2(p0);                                              // eq. 36
  }
  return dh;
}

EntropyPolicy::EntropyPolicy(const PolicyOptions& options, const EntropyOptions& entropy)
    : options_(options), eo_(entropy) {}

Decision EntropyPolicy::next(const ExploreState& state, Rng& rng) {
  grid_ = rasteriseFovea(state.samples, state.robot.position(), eo_);
  const int n = grid_.n;
  delta_.assign(static_cast<size_t>(n * n), std::numeric_limits<double>::quiet_NaN());
  std::vector<Pose2> pose(static_cast<size_t>(n * n));
  double best = -std::numeric_limits<double>::infinity();
  std::vector<int> ties;
  for (int iy = 0; iy < n; ++iy)
    for (int ix = 0; ix < n; ++ix) {
      const Vec2 c = grid_.centre(ix, iy);
      if (state.known.outside(c)) continue;
      // The whisk pose that reaches the cell soonest.
      double travel = std::numeric_limits<double>::infinity();
      for (int d = 0; d < 8; ++d) {
        const double a = 2.0 * kPi * d / 8;
        const Vec2 p = c - eo_.aim_distance * Vec2{std::cos(a), std::sin(a)};
        if (!choosable(state, p)) continue;
        const double t = state.travel.to(p);
        if (t < travel) {
          travel = t;
          pose[static_cast<size_t>(iy * n + ix)] = {p.x(), p.y(), wrapPi(a)};
        }
      }
      if (!std::isfinite(travel)) continue;
      const double dh = entropyDelta(grid_, ix, iy);
      delta_[static_cast<size_t>(iy * n + ix)] = dh;
      if (dh > best + 1e-12) {
        best = dh;
        ties.assign(1, iy * n + ix);
      } else if (dh >= best - 1e-12) {
        ties.push_back(iy * n + ix);
      }
    }
  Decision out;
  if (ties.empty()) {
    out.why = "no reachable whisk pose in the fovea";
    return out;
  }
  const int pick = ties[static_cast<size_t>(rng.below(static_cast<uint32_t>(ties.size())))];
  out.goal = pose[static_cast<size_t>(pick)];
  out.score = best;
  return out;
}

std::unique_ptr<ExplorePolicy> makeEntropyPolicy(const PolicyOptions& options) {
  return std::make_unique<EntropyPolicy>(options);
}

}  // namespace crunch::exploration
