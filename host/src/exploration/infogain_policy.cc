#include "crunch/exploration/infogain_policy.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <tuple>

#include "crunch/exploration/draw_completion.h"

namespace crunch::exploration {

double binaryEntropyBits(double p) {
  if (!(p > 0.0) || !(p < 1.0)) return 0.0;
  return -(p * std::log2(p) + (1.0 - p) * std::log2(1.0 - p));
}

double unknownOutcomeBits(double lambda, double area, double resolution) {
  // Nothing (1 - p), or a first touch at one of K = A / resolution^2 places equally likely
  // (p / K each): H = H_b(p) + p log2 K. Monotone in A while p <= 1/2; beyond, capped there
  // (an upper bound suffices for the branch and bound, and p > 1/2 needs > 0.7 / lambda m^2).
  const double p = std::min(0.5, 1.0 - std::exp(-lambda * area));
  const double k = std::max(1.0, area / (resolution * resolution));
  return binaryEntropyBits(p) + p * std::log2(k);
}

HiddenTableOffsets hiddenTableOffsets(const ModelParams& model, double cell) {
  struct Size {
    double width, depth, weight;
  };
  std::vector<Size> sizes;
  double leg = model.leg_side;
  if (!model.sized()) {
    sizes.push_back({model.table_width, model.table_depth, 1.0});
  } else {
    leg = 0.5 * (model.leg_min + model.leg_max);
    std::vector<Size> uniform;
    const int nl = 4, ns = 2;
    for (int i = 0; i < nl; ++i) {
      const double l = model.size_min_side + (model.size_max_long - model.size_min_side) * (i + 0.5) / nl;
      for (int j = 0; j < ns; ++j) {
        const double s = model.size_min_side + (model.size_max_short - model.size_min_side) * (j + 0.5) / ns;
        if (s <= l) uniform.push_back({l, s, 0.0});
      }
    }
    const double wc = model.catalog_weight;
    for (Size& u : uniform) u.weight = (1.0 - wc) / static_cast<double>(uniform.size());
    sizes = uniform;
    if (wc > 0.0) sizes.push_back({model.table_width, model.table_depth, wc});
  }
  HiddenTableOffsets out;
  const int headings = 12;
  for (const Size& z : sizes) {
    // From the leg at corner (+x, +y): the others at (-2hx, 0), (-2hx, -2hy), (0, -2hy); the
    // mirror image (y -> -y) is the leg at corner (+x, -y).
    const double hx = 0.5 * (z.width - leg), hy = 0.5 * (z.depth - leg);
    for (int mirror = 0; mirror < 2; ++mirror) {
      const double sy = mirror ? 1.0 : -1.0;
      const Vec2 rel[3] = {{-2.0 * hx, 0.0}, {-2.0 * hx, sy * 2.0 * hy}, {0.0, sy * 2.0 * hy}};
      for (int h = 0; h < headings; ++h) {
        const double a = 2.0 * kPi * h / headings, c = std::cos(a), s = std::sin(a);
        for (const Vec2& r : rel) {
          out.dx.push_back(static_cast<int>(std::lround((c * r.x() - s * r.y()) / cell)));
          out.dy.push_back(static_cast<int>(std::lround((s * r.x() + c * r.y()) / cell)));
        }
        out.weight.push_back(z.weight / (2.0 * headings));
      }
    }
  }
  return out;
}

void hiddenLegWeights(const KnownSpace& k, const HiddenTableOffsets& o, std::vector<float>& out) {
  const int nx = k.nx(), ny = k.ny();
  out.assign(static_cast<size_t>(nx * ny), 0.0f);
  // The unknown cells on a grid padded by the largest offset (the pad is outside the region:
  // not unknown), so each look-up is one load at a fixed stride.
  int pad = 0;
  for (size_t q = 0; q < o.dx.size(); ++q) pad = std::max({pad, std::abs(o.dx[q]), std::abs(o.dy[q])});
  const int stride = nx + 2 * pad;
  std::vector<std::uint8_t> unknown(static_cast<size_t>(stride * (ny + 2 * pad)), 0);
  for (int iy = 0; iy < ny; ++iy)
    for (int ix = 0; ix < nx; ++ix)
      unknown[static_cast<size_t>((iy + pad) * stride + ix + pad)] = k.at(ix, iy) == KnownSpace::Cell::kUnknown;
  std::vector<std::ptrdiff_t> step(o.dx.size());
  for (size_t q = 0; q < step.size(); ++q) step[q] = static_cast<std::ptrdiff_t>(o.dy[q]) * stride + o.dx[q];
  const size_t configs = o.weight.size();
  for (int iy = 0; iy < ny; ++iy)
    for (int ix = 0; ix < nx; ++ix) {
      const std::uint8_t* at = unknown.data() + (iy + pad) * stride + ix + pad;
      if (!*at) continue;
      double w = 0.0;
      for (size_t c = 0; c < configs; ++c)
        if (at[step[3 * c]] & at[step[3 * c + 1]] & at[step[3 * c + 2]]) w += o.weight[c];
      out[static_cast<size_t>(iy * nx + ix)] = static_cast<float>(w);
    }
}

InfogainPolicy::InfogainPolicy(const PolicyOptions& options, const InfogainOptions& infogain)
    : options_(options), io_(infogain), predictor_(defaultWhiskerArray(), infogain.prediction) {}

bool InfogainPolicy::whiskedBefore(const Pose2& pose) const {
  // The same whisk again repeats its outcome at the sensor's resolution: nothing new.
  const double tol = 2.0 * io_.prediction.resolution;
  const auto same = [&](const Pose2& w, double d) {
    return std::hypot(w.x - pose.x, w.y - pose.y) <= d &&
           std::abs(wrapPi(w.theta - pose.theta)) <= io_.prediction.amplitude / 2;
  };
  // The loop would not move for a goal this close to where it stands: the same whisk again.
  if (just_whisked_ && same(*just_whisked_, std::max(tol, arrival_tol_))) return true;
  return std::any_of(whisked_.begin(), whisked_.end(), [&](const Pose2& w) { return same(w, tol); });
}

void InfogainPolicy::prepare(const ExploreState& state) {
  if (predictor_.mounts().size() != state.mounts.size() ||
      !std::equal(state.mounts.begin(), state.mounts.end(), predictor_.mounts().begin(),
                  [](const WhiskerMount& a, const WhiskerMount& b) {
                    return a.base == b.base && a.bearing == b.bearing && a.length == b.length;
                  })) {
    predictor_ = WhiskPredictor(state.mounts, io_.prediction);
  }
  obstacles_.resize(state.samples.size());
  outcomes_.resize(state.samples.size());
  double legs = 0.0;
  // The region's edges are walls the robot knows (outside the region counts as blocked): they
  // stop every draw's whiskers alike, and a draw's wall lying along one (both ends within
  // 2 resolutions of the edge's line) is that edge, not news - so it is replaced by the edge,
  // and disagreement about how far along the edge the blackboard has extended it carries no
  // information about the map.
  const Vec2 lo = state.known.lo(), hi = state.known.hi();
  const MapWall edges[4] = {{lo, {hi.x(), lo.y()}, 1.0},
                            {{hi.x(), lo.y()}, hi, 1.0},
                            {hi, {lo.x(), hi.y()}, 1.0},
                            {{lo.x(), hi.y()}, lo, 1.0}};
  const double tol = 2.0 * io_.prediction.resolution;
  auto alongEdge = [&](const MapWall& w) {
    const bool x0 = std::abs(w.a.x() - lo.x()) < tol && std::abs(w.b.x() - lo.x()) < tol;
    const bool x1 = std::abs(w.a.x() - hi.x()) < tol && std::abs(w.b.x() - hi.x()) < tol;
    const bool y0 = std::abs(w.a.y() - lo.y()) < tol && std::abs(w.b.y() - lo.y()) < tol;
    const bool y1 = std::abs(w.a.y() - hi.y()) < tol && std::abs(w.b.y() - hi.y()) < tol;
    return x0 || x1 || y0 || y1;
  };
  for (size_t i = 0; i < state.samples.size(); ++i) {
    obstacles_[i].assign(state.samples[i], edges);
    std::vector<MapWall>& walls = obstacles_[i].walls;
    walls.erase(std::remove_if(walls.begin(), walls.end() - 4, alongEdge), walls.end() - 4);
    legs += static_cast<double>(obstacles_[i].legs.size());
  }
  if (!state.samples.empty()) legs /= static_cast<double>(state.samples.size());
  reportClasses(state);
  const KnownSpace& k = state.known;
  // Each unknown cell counts 1, or its hidden weight with table_prior.
  int known_cells = 0;
  hidden_.assign(static_cast<size_t>(k.nx() * k.ny()), 0.0f);
  for (int iy = 0; iy < k.ny(); ++iy)
    for (int ix = 0; ix < k.nx(); ++ix) {
      const bool unknown = k.at(ix, iy) == KnownSpace::Cell::kUnknown;
      known_cells += !unknown;
      hidden_[static_cast<size_t>(iy * k.nx() + ix)] = unknown ? 1.0f : 0.0f;
    }
  const double known_m2 = known_cells * k.cell() * k.cell();
  lambda_ = (io_.prior_legs + legs) / (io_.prior_area_m2 + known_m2);
  if (io_.table_prior) hiddenLegWeights(k, hiddenTableOffsets(state.model, k.cell()), hidden_);
  // The hidden weights' summed-area table, for hiddenNear.
  const int sx = k.nx() + 1;
  hidden_sat_.assign(static_cast<size_t>(sx * (k.ny() + 1)), 0.0);
  for (int iy = 0; iy < k.ny(); ++iy)
    for (int ix = 0; ix < k.nx(); ++ix)
      hidden_sat_[static_cast<size_t>((iy + 1) * sx + ix + 1)] =
          hidden_[static_cast<size_t>(iy * k.nx() + ix)] + hidden_sat_[static_cast<size_t>(iy * sx + ix + 1)] +
          hidden_sat_[static_cast<size_t>((iy + 1) * sx + ix)] - hidden_sat_[static_cast<size_t>(iy * sx + ix)];
  stamp_.assign(static_cast<size_t>(k.nx() * k.ny()), 0);
  stamp_now_ = 0;
  path_stamp_.assign(static_cast<size_t>(k.nx() * k.ny()), 0);
  path_stamp_now_ = 0;
  rmin_ = std::numeric_limits<double>::infinity();
  rmax_ = 0.0;
  for (const WhiskerMount& m : predictor_.mounts()) {
    rmin_ = std::min(rmin_, m.base.norm());
    rmax_ = std::max(rmax_, (m.base + m.length * m.direction()).norm());
  }
  const double rmin = rmin_, rmax = rmax_;
  // Every cell a whisk's rays can count holds a ray sample inside one whisker's sector (its
  // bearing +- the amplitude, its base to its tip), so the cell lies within a cell diagonal d of
  // the union of the sectors: the cells are at most that grown union's area over a cell's,
  // area + perimeter d + pi d^2 (Steiner's bound for the union of the merged angular spans
  // between rmin and rmax; merging less only loosens it).
  const double c = k.cell(), d = c * std::sqrt(2.0);
  std::vector<std::pair<double, double>> spans;
  for (const WhiskerMount& m : predictor_.mounts())
    spans.push_back({m.bearing - io_.prediction.amplitude, m.bearing + io_.prediction.amplitude});
  std::sort(spans.begin(), spans.end());
  double area = 0.0, perimeter = 0.0;
  for (size_t i = 0; i < spans.size();) {
    double a0 = spans[i].first, a1 = spans[i].second;
    for (++i; i < spans.size() && spans[i].first <= a1; ++i) a1 = std::max(a1, spans[i].second);
    const double span = std::min(a1 - a0, 2.0 * kPi);
    area += 0.5 * span * (rmax * rmax - rmin * rmin);
    perimeter += 2.0 * (rmax - rmin) + span * (rmin + rmax);
  }
  ring_cells_max_ = (area + perimeter * d + kPi * d * d) / (c * c);
  sweepBand(state);
}

void InfogainPolicy::sweepBand(const ExploreState& state) {
  const KnownSpace& k = state.known;
  const int nx = k.nx(), ny = k.ny();
  band_.assign(static_cast<size_t>(nx * ny), 0.0);
  if (!io_.path_sweep) return;
  // The body's disc in cell offsets (cell centres within the radius, as markBody marks), and
  // for each of the 8 steps (dx, dy) its leading edge: the offsets o with o + (dx, dy) outside
  // the disc, i.e. the cells a step from a parent to its child newly covers.
  const double radius = state.costmap.options().robot_radius;
  const int rc = static_cast<int>(std::ceil(radius / k.cell())) + 1;
  auto inDisc = [&](int dx, int dy) { return std::hypot(dx, dy) * k.cell() <= radius; };
  disc_dx_.clear();
  disc_dy_.clear();
  for (int dy = -rc; dy <= rc; ++dy)
    for (int dx = -rc; dx <= rc; ++dx)
      if (inDisc(dx, dy)) {
        disc_dx_.push_back(dx);
        disc_dy_.push_back(dy);
      }
  edge_begin_.assign(10, 0);
  edge_dx_.clear();
  edge_dy_.clear();
  for (int s = 0; s < 9; ++s) {  // step (dx, dy) = (s % 3 - 1, s / 3 - 1)
    edge_begin_[static_cast<size_t>(s)] = static_cast<int>(edge_dx_.size());
    const int sx = s % 3 - 1, sy = s / 3 - 1;
    for (size_t q = 0; q < disc_dx_.size(); ++q)
      if (!inDisc(disc_dx_[q] + sx, disc_dy_[q] + sy)) {
        edge_dx_.push_back(disc_dx_[q]);
        edge_dy_.push_back(disc_dy_[q]);
      }
  }
  edge_begin_[9] = static_cast<int>(edge_dx_.size());
  // An unknown cell counts its hidden weight (1 without table_prior), as the whisk's do.
  auto unknown = [&](int x, int y) {
    return x >= 0 && y >= 0 && x < nx && y < ny ? static_cast<double>(hidden_[static_cast<size_t>(y * nx + x)]) : 0.0;
  };
  // Parents before children: the tree's cells in order of their cost.
  std::vector<int> order;
  for (int i = 0; i < nx * ny; ++i)
    if (std::isfinite(state.travel.cost(i))) order.push_back(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return state.travel.cost(a) < state.travel.cost(b) || (state.travel.cost(a) == state.travel.cost(b) && a < b);
  });
  for (const int i : order) {
    const int x = i % nx, y = i / nx;
    const int p = state.travel.parent(i);
    double n = 0.0;
    if (p < 0) {
      for (size_t q = 0; q < disc_dx_.size(); ++q) n += unknown(x + disc_dx_[q], y + disc_dy_[q]);
    } else {
      n = band_[static_cast<size_t>(p)];
      const int s = (x - p % nx + 1) + 3 * (y - p / nx + 1);
      for (int q = edge_begin_[static_cast<size_t>(s)]; q < edge_begin_[static_cast<size_t>(s) + 1]; ++q)
        n += unknown(x + edge_dx_[static_cast<size_t>(q)], y + edge_dy_[static_cast<size_t>(q)]);
    }
    band_[static_cast<size_t>(i)] = n;
  }
}

double InfogainPolicy::bandAt(const ExploreState& state, const Vec2& p) const {
  int ix, iy;
  if (!state.known.index(p, ix, iy)) return 0;
  return band_[static_cast<size_t>(iy * state.known.nx() + ix)];
}

void InfogainPolicy::stampPathEnd(const ExploreState& state, const Vec2& position) {
  ++path_stamp_now_;
  const KnownSpace& k = state.known;
  int cx, cy;
  if (!io_.path_sweep || !k.index(position, cx, cy)) return;
  const int nx = k.nx(), ny = k.ny();
  const double reach = rmax_ + state.costmap.options().robot_radius + k.cell();
  double back = 0.0;
  for (int j = cy * nx + cx; j >= 0 && back <= reach;) {
    const int x = j % nx, y = j / nx;
    for (size_t q = 0; q < disc_dx_.size(); ++q) {
      const int ix = x + disc_dx_[q], iy = y + disc_dy_[q];
      if (ix >= 0 && iy >= 0 && ix < nx && iy < ny) path_stamp_[static_cast<size_t>(iy * nx + ix)] = path_stamp_now_;
    }
    const int p = state.travel.parent(j);
    if (p >= 0) back += k.cell() * ((p % nx != x && p / nx != y) ? std::sqrt(2.0) : 1.0);
    j = p;
  }
}

void InfogainPolicy::gather(const Vec2& position) {
  const size_t n = obstacles_.size();
  near_legs_.clear();
  near_walls_.clear();
  leg_begin_.assign(n + 1, 0);
  wall_begin_.assign(n + 1, 0);
  uniq_.assign(n, 0);
  any_near_ = false;
  for (size_t i = 0; i < n; ++i) {
    leg_begin_[i] = static_cast<int>(near_legs_.size());
    wall_begin_[i] = static_cast<int>(near_walls_.size());
    predictor_.nearReach(position, obstacles_[i], near_legs_, near_walls_);
    leg_begin_[i + 1] = static_cast<int>(near_legs_.size());
    wall_begin_[i + 1] = static_cast<int>(near_walls_.size());
    any_near_ = any_near_ || leg_begin_[i + 1] > leg_begin_[i] || wall_begin_[i + 1] > wall_begin_[i];
  }
  // Draws whose objects within reach are the same geometry predict the same outcome: predict
  // once per distinct set (a chain's draws often differ only far away).
  auto same = [&](size_t a, size_t b) {
    const int na = leg_begin_[a + 1] - leg_begin_[a], nb = leg_begin_[b + 1] - leg_begin_[b];
    const int wa = wall_begin_[a + 1] - wall_begin_[a], wb = wall_begin_[b + 1] - wall_begin_[b];
    if (na != nb || wa != wb) return false;
    for (int k = 0; k < na; ++k) {
      const OrientedRect& x = obstacles_[a].legs[static_cast<size_t>(near_legs_[static_cast<size_t>(leg_begin_[a] + k)])];
      const OrientedRect& y = obstacles_[b].legs[static_cast<size_t>(near_legs_[static_cast<size_t>(leg_begin_[b] + k)])];
      if (x.pose.x != y.pose.x || x.pose.y != y.pose.y || x.pose.theta != y.pose.theta ||
          x.size_x != y.size_x || x.size_y != y.size_y)
        return false;
    }
    for (int k = 0; k < wa; ++k) {
      const MapWall& x = obstacles_[a].walls[static_cast<size_t>(near_walls_[static_cast<size_t>(wall_begin_[a] + k)])];
      const MapWall& y = obstacles_[b].walls[static_cast<size_t>(near_walls_[static_cast<size_t>(wall_begin_[b] + k)])];
      if (x.a != y.a || x.b != y.b) return false;
    }
    return true;
  };
  for (size_t i = 0; i < n; ++i) {
    uniq_[i] = static_cast<int>(i);
    for (size_t j = 0; j < i; ++j)
      if (uniq_[j] == static_cast<int>(j) && same(i, j)) {
        uniq_[i] = static_cast<int>(j);
        break;
      }
  }
}

FuseOptions InfogainPolicy::reportTolerance(const ModelParams& model) const {
  FuseOptions tol = io_.report;
  tol.compare_sizes = model.sized();
  return tol;
}

void InfogainPolicy::reportClasses(const ExploreState& state) {
  // Greedy classes, as the outcomes' (a draw joins the first class whose first draw reports the
  // same map). Without report_level every draw is its own class.
  const size_t n = state.samples.size();
  report_of_.assign(n, 0);
  report_count_.clear();
  std::vector<std::vector<MapTable>> tables(n);
  const FuseOptions tol = reportTolerance(state.model);
  if (io_.report_level)
    for (size_t i = 0; i < n; ++i) tables[i] = withoutClashes(state.samples[i].tables, tol);
  std::vector<size_t> first;
  for (size_t i = 0; i < n; ++i) {
    size_t c = first.size();
    if (io_.report_level)
      for (c = 0; c < first.size(); ++c)
        if (sameReportedMap(tables[first[c]], obstacles_[first[c]].walls, tables[i],
                            obstacles_[i].walls, tol))
          break;
    if (c == first.size()) {
      first.push_back(i);
      report_count_.push_back(0);
    }
    ++report_count_[c];
    report_of_[i] = static_cast<int>(c);
  }
  report_bits_ = 0.0;
  for (const int k : report_count_) {
    const double p = k / static_cast<double>(n);
    report_bits_ -= p * std::log2(p);
  }
}

bool sameReportedMap(std::span<const MapTable> a_tables, std::span<const MapWall> a_walls,
                     std::span<const MapTable> b_tables, std::span<const MapWall> b_walls,
                     const FuseOptions& tol) {
  if (a_tables.size() != b_tables.size() || a_walls.size() != b_walls.size()) return false;
  std::vector<char> used(std::max(b_tables.size(), b_walls.size()), 0);
  for (const MapTable& t : a_tables) {
    size_t m = 0;
    while (m < b_tables.size() && (used[m] || !tablesAgree(t, b_tables[m], tol))) ++m;
    if (m == b_tables.size()) return false;
    used[m] = 1;
  }
  std::fill(used.begin(), used.end(), 0);
  const double r2 = tol.radius * tol.radius;
  const auto near = [r2](const Vec2& p, const Vec2& q) { return (p - q).squaredNorm() <= r2; };
  for (const MapWall& w : a_walls) {
    size_t m = 0;
    const auto same = [&](const MapWall& v) {
      return (near(w.a, v.a) && near(w.b, v.b)) || (near(w.a, v.b) && near(w.b, v.a));
    };
    while (m < b_walls.size() && (used[m] || !same(b_walls[m]))) ++m;
    if (m == b_walls.size()) return false;
    used[m] = 1;
  }
  return true;
}

double InfogainPolicy::sampleBits(const Pose2& pose) {
  // Requires gather(pose.position()).
  const size_t n = obstacles_.size();
  if (n < 2 || !any_near_) return 0.0;  // every draw predicts no touch: one outcome
  // Every draw has the same objects within reach: one outcome, whatever it is.
  if (std::all_of(uniq_.begin(), uniq_.end(), [](int u) { return u == 0; })) return 0.0;
  // Partition the draws by outcome (greedy: a draw joins the first class whose representative
  // it matches). H(Y) of the partition; H(Y | M) = 0 for a deterministic quantised prediction.
  cls_count_.assign(n, 0);
  cls_of_.assign(n, -1);
  std::vector<size_t>& rep = rep_scratch_;
  rep.clear();
  for (size_t i = 0; i < n; ++i) {
    const size_t u = static_cast<size_t>(uniq_[i]);
    if (u != i) {  // the same objects within reach as draw u: its outcome
      ++cls_count_[static_cast<size_t>(cls_of_[u])];
      cls_of_[i] = cls_of_[u];
      continue;
    }
    const std::span<const int> legs(near_legs_.data() + leg_begin_[i],
                                    static_cast<size_t>(leg_begin_[i + 1] - leg_begin_[i]));
    const std::span<const int> walls(near_walls_.data() + wall_begin_[i],
                                     static_cast<size_t>(wall_begin_[i + 1] - wall_begin_[i]));
    predictor_.predictNear(pose, obstacles_[i], legs, walls, outcomes_[i]);
    size_t c = 0;
    for (; c < rep.size(); ++c)
      if (sameOutcome(outcomes_[rep[c]], outcomes_[i], io_.prediction.resolution)) break;
    if (c == rep.size()) rep.push_back(i);
    ++cls_count_[c];
    cls_of_[i] = static_cast<int>(c);
  }
  double h = 0.0;
  if (!io_.report_level) {
    for (size_t c = 0; c < rep.size(); ++c) {
      const double p = static_cast<double>(cls_count_[c]) / static_cast<double>(n);
      h -= p * std::log2(p);
    }
    return h;
  }
  // I(Y; R) from the joint counts of outcome class and report class.
  const size_t ny = rep.size(), nr = report_count_.size();
  joint_.assign(ny * nr, 0);
  for (size_t i = 0; i < n; ++i)
    ++joint_[static_cast<size_t>(cls_of_[i]) * nr + static_cast<size_t>(report_of_[i])];
  const double dn = static_cast<double>(n);
  for (size_t c = 0; c < ny; ++c)
    for (size_t r = 0; r < nr; ++r)
      if (const int j = joint_[c * nr + r]; j > 0)
        h += (j / dn) * std::log2(j * dn / (static_cast<double>(cls_count_[c]) * report_count_[r]));
  return std::max(0.0, h);
}

double InfogainPolicy::hiddenNear(const KnownSpace& k, const Vec2& p) const {
  // Every cell a whisk at p can count holds a ray sample within rmax_ of p: its index lies in
  // the square of cells covering p +- rmax_.
  const double c = k.cell();
  const int sx = k.nx() + 1;
  const int x0 = std::clamp(static_cast<int>(std::floor((p.x() - rmax_ - k.lo().x()) / c)), 0, k.nx());
  const int x1 = std::clamp(static_cast<int>(std::floor((p.x() + rmax_ - k.lo().x()) / c)) + 1, 0, k.nx());
  const int y0 = std::clamp(static_cast<int>(std::floor((p.y() - rmax_ - k.lo().y()) / c)), 0, k.ny());
  const int y1 = std::clamp(static_cast<int>(std::floor((p.y() + rmax_ - k.lo().y()) / c)) + 1, 0, k.ny());
  const auto at = [&](int x, int y) { return hidden_sat_[static_cast<size_t>(y * sx + x)]; };
  return std::max(0.0, at(x1, y1) - at(x0, y1) - at(x1, y0) + at(x0, y0));
}

double InfogainPolicy::positionBound(double cell, double band) const {
  // The draws' outcome classes are unions of the groups of draws with identical objects in
  // reach, so H(Y) is at most the entropy of those groups' sizes; the unswept area one heading
  // sweeps is at most the whole ring's, and H_b grows up to p = 1/2.
  double h = 0.0;
  if (any_near_) {
    const size_t n = uniq_.size();
    std::vector<int>& count = bound_scratch_;
    count.assign(n, 0);
    for (const int u : uniq_) ++count[static_cast<size_t>(u)];
    for (const int k : count)
      if (k > 0) h -= (k / static_cast<double>(n)) * std::log2(k / static_cast<double>(n));
    h = std::min(h, report_bits_);  // I(Y; R) <= H(R)
  }
  // unknownOutcomeBits grows with the area; each cell counts at most its hidden weight, once.
  double weighted = 0.0;
  for (const int q : ray_cells_) weighted += hidden_[static_cast<size_t>(q)];
  const double ring = std::min(weighted, ring_cells_max_);
  const double area = (ring + band) * cell * cell;
  return h + unknownOutcomeBits(lambda_, area, io_.prediction.resolution) + 1e-12;
}

void InfogainPolicy::march(const KnownSpace& k, const Vec2& position) {
  // Rays from the centre around the whole circle, half a cell apart at the whiskers' tips, each
  // marched outward half a cell at a time from the rim to the tip and stopped by the first
  // occupied cell (a whisker stops there): the unknown cells each ray would sweep. The default
  // whiskers point radially outward from the rim, so a whisker turned to angle a sweeps ray a.
  const double rmin = rmin_, rmax = rmax_;  // prepare()'s
  const double step = 0.5 * k.cell();
  n_rays_ = std::max(8, static_cast<int>(std::ceil(2.0 * kPi * rmax / step)));
  const int nr = std::max(1, static_cast<int>(std::ceil((rmax - rmin) / step)));
  ray_begin_.assign(static_cast<size_t>(n_rays_) + 1, 0);
  ray_cells_.clear();
  ray_radius_.clear();
  for (int j = 0; j < n_rays_; ++j) {
    ray_begin_[static_cast<size_t>(j)] = static_cast<int>(ray_cells_.size());
    const double a = 2.0 * kPi * j / n_rays_;
    const Vec2 dir{std::cos(a), std::sin(a)};
    for (int r = 0; r <= nr; ++r) {
      const double rad = rmin + (rmax - rmin) * r / nr;
      int ix, iy;
      if (!k.index(position + rad * dir, ix, iy)) break;
      const KnownSpace::Cell c = k.at(ix, iy);
      if (c == KnownSpace::Cell::kOccupied) break;
      if (c != KnownSpace::Cell::kUnknown) continue;
      ray_cells_.push_back(iy * k.nx() + ix);
      ray_radius_.push_back(rad);
    }
  }
  ray_begin_[static_cast<size_t>(n_rays_)] = static_cast<int>(ray_cells_.size());
}

double InfogainPolicy::unknownBits(const ExploreState& state, const Pose2& pose, double* area_m2) {
  // Requires march(state.known, pose.position()) and stampPathEnd(state, pose.position()).
  const double cell = state.known.cell();
  ++stamp_now_;
  double unknown = 0.0;
  const double amp = io_.prediction.amplitude;
  const double per_ray = 2.0 * kPi / n_rays_;
  for (const WhiskerMount& m : predictor_.mounts()) {
    const double r0 = m.base.norm() - 1e-9, r1 = (m.base + m.length * m.direction()).norm() + 1e-9;
    const double a = pose.theta + m.bearing;
    const int j0 = static_cast<int>(std::ceil((a - amp) / per_ray));
    const int j1 = static_cast<int>(std::floor((a + amp) / per_ray));
    for (int jj = j0; jj <= j1; ++jj) {
      const int j = ((jj % n_rays_) + n_rays_) % n_rays_;
      for (int q = ray_begin_[static_cast<size_t>(j)]; q < ray_begin_[static_cast<size_t>(j) + 1]; ++q) {
        const double rad = ray_radius_[static_cast<size_t>(q)];
        if (rad < r0 || rad > r1) continue;
        const size_t cq = static_cast<size_t>(ray_cells_[static_cast<size_t>(q)]);
        int& s = stamp_[cq];
        if (s == stamp_now_) continue;
        s = stamp_now_;
        if (path_stamp_[cq] == path_stamp_now_) continue;  // the drive sweeps it already
        unknown += hidden_[cq];
      }
    }
  }
  const double area = (unknown + bandAt(state, pose.position())) * cell * cell;
  if (area_m2) *area_m2 = area;
  return unknownOutcomeBits(lambda_, area, io_.prediction.resolution);
}

CandidateValue InfogainPolicy::value(const ExploreState& state, const Pose2& pose) {
  if (obstacles_.size() != state.samples.size() || stamp_.empty()) prepare(state);
  CandidateValue v;
  v.pose = pose;
  v.travel_m = state.travel.to(pose.position());
  if (!std::isfinite(v.travel_m) || whiskedBefore(pose)) return v;
  gather(pose.position());
  march(state.known, pose.position());
  stampPathEnd(state, pose.position());
  v.sample_bits = sampleBits(pose);
  v.unknown_bits = unknownBits(state, pose, &v.unknown_m2);
  v.score = (v.sample_bits + v.unknown_bits) / (v.travel_m + io_.whisk_cost_m);
  return v;
}

Decision InfogainPolicy::next(const ExploreState& given, Rng& rng) {
  just_whisked_.reset();
  if (given.whisks > whisks_seen_) {
    // The pose just whisked: the robot stands where its last whisk began. Without a new whisk
    // (a goal given up on the way) it stands where it stopped, which was not whisked.
    whisked_.push_back(given.robot);
    just_whisked_ = given.robot;
    // The last goal was whisked at, within the loop's tolerance of it (or, rarely, a touch on
    // the way was whisked and the goal then given up: it is dropped all the same).
    if (last_goal_) whisked_.push_back(*last_goal_);
  }
  whisks_seen_ = given.whisks;
  arrival_tol_ = given.arrival_tolerance;
  ExploreState state = given;
  if (io_.complete_orphans || io_.merge_repeats) {
    completed_.assign(given.samples.begin(), given.samples.end());
    const FuseOptions tol = reportTolerance(given.model);
    for (MapSample& draw : completed_) {
      if (io_.merge_repeats) mergeRepeats(draw, tol);
      if (io_.complete_orphans)
        completeOrphanLegs(draw, given.known, given.model, rng, io_.completion_tries);
    }
    state.samples = completed_;
  }
  prepare(state);
  values_.clear();
  std::vector<Pose2> candidates;
  const KnownSpace& k = state.known;
  const double step = options_.candidate_spacing;
  const int nh = options_.candidate_headings;
  const Vec2 lo = k.lo(), hi = k.hi();
  for (double y = lo.y() + 0.5 * step; y < hi.y(); y += step)
    for (double x = lo.x() + 0.5 * step; x < hi.x(); x += step) {
      const Vec2 p{x, y};
      if (!choosable(state, p)) continue;
      for (int h = 0; h < nh; ++h) candidates.push_back({x, y, wrapPi(2.0 * kPi * h / nh)});
    }
  // Fig. 7: the poses that would settle each leg of each draw.
  const size_t lattice = candidates.size();
  for (const WhiskObstacles& o : obstacles_)
    for (const OrientedRect& leg : o.legs)
      for (int d = 0; d < 8; ++d) {
        const double a = 2.0 * kPi * d / 8;
        const Vec2 p = leg.pose.position() - io_.aim_distance * Vec2{std::cos(a), std::sin(a)};
        if (!choosable(state, p)) continue;
        candidates.push_back({p.x(), p.y(), wrapPi(a)});
      }
  // Duplicates (draws agreeing on a leg) are scored once.
  auto key = [](const Pose2& q) {
    return std::make_tuple(std::lround(q.x / 0.01), std::lround(q.y / 0.01),
                           std::lround(wrapPi(q.theta) / 0.05));
  };
  std::sort(candidates.begin() + static_cast<std::ptrdiff_t>(lattice), candidates.end(),
            [&](const Pose2& a, const Pose2& b) { return key(a) < key(b); });
  candidates.erase(std::unique(candidates.begin() + static_cast<std::ptrdiff_t>(lattice),
                               candidates.end(),
                               [&](const Pose2& a, const Pose2& b) { return key(a) == key(b); }),
                   candidates.end());

  // Nearest first; a candidate is worth at most log2(draws) bits from the draws and
  // unknownOutcomeBits of the largest band plus a whole annulus from unswept space, so once
  // that bound over the travel falls below the best score no farther candidate can win (exact
  // branch and bound; the lattice's headings of one position stay together, the sort being
  // stable).
  std::vector<double> travel(candidates.size());
  for (size_t i = 0; i < candidates.size(); ++i) travel[i] = state.travel.to(candidates[i].position());
  std::vector<size_t> order(candidates.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return travel[a] < travel[b]; });
  const double draw_bits = obstacles_.size() > 1 ? std::min(report_bits_, std::log2(static_cast<double>(obstacles_.size()))) : 0.0;
  const double cell2 = state.known.cell() * state.known.cell();
  // A candidate's cheap bound: the draws' log2 N and the unswept term over its band and at most
  // the hidden weight near it (or the ring's cell count, if smaller). Suffix maxima over the
  // travel order bound every candidate from there on.
  std::vector<double> cheap(candidates.size());
  for (size_t i = 0; i < candidates.size(); ++i) {
    const Vec2 p = candidates[i].position();
    const double near = std::min(ring_cells_max_, hiddenNear(state.known, p));
    cheap[i] = draw_bits + unknownOutcomeBits(lambda_, (bandAt(state, p) + near) * cell2, io_.prediction.resolution) + 1e-12;
  }
  std::vector<double> beyond(order.size() + 1, 0.0);
  for (size_t j = order.size(); j-- > 0;) beyond[j] = std::max(beyond[j + 1], cheap[order[j]]);
  Decision d;
  int best = -1;
  Vec2 gathered{std::numeric_limits<double>::quiet_NaN(), 0.0};
  double position_bound = 0.0;
  for (size_t j = 0; j < order.size(); ++j) {
    const size_t ci = order[j];
    const Pose2& c = candidates[ci];
    if (best >= 0 && beyond[j] / (travel[ci] + io_.whisk_cost_m) <= values_[static_cast<size_t>(best)].score)
      break;
    CandidateValue v;
    v.pose = c;
    v.travel_m = travel[ci];
    if (std::isfinite(v.travel_m) && !whiskedBefore(c)) {
      const double band = bandAt(state, c.position());
      // A cheap bound first, before the draws are gathered.
      if (best >= 0 && cheap[ci] / (v.travel_m + io_.whisk_cost_m) <=
                           values_[static_cast<size_t>(best)].score) {
        values_.push_back(v);
        continue;
      }
      if (!(c.position() == gathered)) {  // the lattice's headings share a position
        gather(c.position());
        march(state.known, c.position());
        stampPathEnd(state, c.position());
        gathered = c.position();
        position_bound = positionBound(state.known.cell(), band);
      }
      // No heading here can beat the best: skip the predictions (exact, see positionBound).
      if (best >= 0 && position_bound / (v.travel_m + io_.whisk_cost_m) <=
                           values_[static_cast<size_t>(best)].score) {
        values_.push_back(v);
        continue;
      }
      v.sample_bits = sampleBits(c);
      v.unknown_bits = unknownBits(state, c, &v.unknown_m2);
      v.score = (v.sample_bits + v.unknown_bits) / (v.travel_m + io_.whisk_cost_m);
    }
    values_.push_back(v);
    if (best < 0 || values_.back().score > values_[static_cast<size_t>(best)].score)
      best = static_cast<int>(values_.size()) - 1;
  }
  if (best < 0) {
    d.why = "no reachable whisk pose";
    return d;
  }
  const CandidateValue& b = values_[static_cast<size_t>(best)];
  if (!(b.score > options_.min_bits_per_metre) || b.score <= 1e-9) {
    d.why = "no candidate worth its travel";
    d.score = b.score;
    return d;
  }
  d.goal = b.pose;
  d.score = b.score;
  last_goal_ = d.goal;
  return d;
}

std::unique_ptr<ExplorePolicy> makeInfogainPolicy(const PolicyOptions& options) {
  return std::make_unique<InfogainPolicy>(options);
}

}  // namespace crunch::exploration
