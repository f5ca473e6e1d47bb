#include "crunch/blackboard/params.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "crunch/core/range_check.h"

namespace crunch {

namespace {
// The size prior's (longer, shorter) region, counted once (w x d at theta is d x w at
// theta + pi/2): (max_short - min)(max_long - min) - (max_short - min)^2 / 2.
double sizeRegionArea(const ModelParams& p) {
  const double a = p.size_max_short - p.size_min_side, b = p.size_max_long - p.size_min_side;
  return std::max(a * b - 0.5 * a * a, 1e-12);
}
}  // namespace

Result<ObjectModel> objectModelByName(const std::string& name) {
  if (name == "paper") return ObjectModel::kPaper;
  if (name == "walls") return ObjectModel::kWalls;
  if (name == "rooms") return ObjectModel::kRooms;
  return Error{"model: unknown object model '" + name + "' (paper | walls | rooms)"};
}

const char* objectModelName(ObjectModel m) {
  switch (m) {
    case ObjectModel::kWalls: return "walls";
    case ObjectModel::kRooms: return "rooms";
    case ObjectModel::kPaper: break;
  }
  return "paper";
}

double ModelParams::logSizePrior(double width, double depth, double leg, bool width_fixed,
                                 bool depth_fixed) const {
  const double lo = std::min(width, depth), hi = std::max(width, depth);
  const bool ok = lo >= size_min_side && lo <= size_max_short && hi <= size_max_long &&
                  legSideAllowed(leg) && 2.0 * leg < lo;
  if (!ok) return -std::numeric_limits<double>::infinity();
  const double catalog = logCatalogFactor(width, depth, width_fixed, depth_fixed);
  if (!size_occam) return catalog;
  // The Occam factor of a free size (Laplace's approximation of the marginal over it): the
  // posterior's volume over the prior's. Width and depth are each measured by two legs' centres
  // (sd sqrt(2) sigma_r_leg each, eq. 10): volume (sqrt(2 pi) sqrt(2) sigma_r_leg)^2; the leg
  // side by eq. 10's leg-width term: sqrt(2 pi) sigma_w. The prior's (width, depth) region
  // {min_side <= shorter <= max_short, longer <= max_long} is counted once (w x d at theta is
  // d x w at theta + pi/2), area (max_short - min)(max_long - min) - (max_short - min)^2 / 2.
  const double area = sizeRegionArea(*this);
  const double wd = 2.0 * kPi * 2.0 * sigma_r_leg * sigma_r_leg;
  const double lv = std::sqrt(2.0 * kPi) * sigma_w;
  return catalog + std::log(wd / area) +
         std::log(std::min(1.0, lv / std::max(leg_max - leg_min, 1e-12)));
}

double ModelParams::logCatalogFactor(double width, double depth, bool width_fixed,
                                     bool depth_fixed) const {
  if (catalog_weight <= 0.0 || !(width_fixed || depth_fixed)) return 0.0;
  // The mixture's marginal over the uniform's along the sides the evidence fixes, the others
  // integrated out (over a likelihood flat in a side, both priors integrate to one):
  // (1 - w) + w N / U. Both are over the (longer, shorter) sides, the region counted once as in
  // the Occam factor above (w x d at theta is d x w at theta + pi/2), so 1 / U is that region's
  // area A; in (width, depth) the region is mirrored (area 2 A) and the catalog is N's two
  // mirror images at half weight each.
  const double c_hi = std::max(table_width, table_depth), c_lo = std::min(table_width, table_depth);
  const double area = sizeRegionArea(*this);
  const double s2 = catalog_sigma * catalog_sigma;
  double n_over_u;
  if (width_fixed && depth_fixed) {
    const double lo = std::min(width, depth), hi = std::max(width, depth);
    const double z = ((hi - c_hi) * (hi - c_hi) + (lo - c_lo) * (lo - c_lo)) / (2.0 * s2);
    n_over_u = area * std::exp(-z) / (2.0 * kPi * s2);
  } else {
    // One side x fixed, the other integrated out: the catalog's marginal density at x is the
    // mean of two 1-D Gaussians (x is its longer or its shorter side); the uniform's is the
    // length of the other side's range at x over 2 A.
    const double x = width_fixed ? width : depth;
    const double a = (x - c_hi) * (x - c_hi) / (2.0 * s2), b = (x - c_lo) * (x - c_lo) / (2.0 * s2);
    const double n = 0.5 * (std::exp(-a) + std::exp(-b)) / std::sqrt(2.0 * kPi * s2);
    const double other = x <= size_max_short ? size_max_long - size_min_side
                                             : size_max_short - size_min_side;
    n_over_u = n * 2.0 * area / std::max(other, 1e-12);
  }
  return std::log((1.0 - catalog_weight) + catalog_weight * n_over_u);
}

Status ModelParams::validate() const {
  const Status checks[] = {
      checkAbove("c_T", c_T, 0.0, 1e6),
      checkAbove("c_L", c_L, 0.0, 1e6),
      checkAbove("c_S", c_S, 0.0, 1e6),
      checkAbove("alpha_L", alpha_L, 0.0, 1e6),
      checkAbove("alpha_S", alpha_S, 0.0, 1e6),
      checkAbove("eps_a", eps_a, 0.0, 1.0),
      checkAbove("eps_b", eps_b, 0.0, 1.0),
      checkAbove("eps_c", eps_c, 0.0, 1.0),
      checkAbove("sigma_r_leg", sigma_r_leg, 0.0, 1.0),
      checkAbove("sigma_theta_leg", sigma_theta_leg, 0.0, kPi),
      checkAbove("sigma_r_shapelet", sigma_r_shapelet, 0.0, 1.0),
      checkAbove("sigma_theta_shapelet", sigma_theta_shapelet, 0.0, kPi),
      checkAbove("sigma_w", sigma_w, 0.0, 1.0),
      checkAbove("delta3", delta3, 0.0, 1e6),
      checkRange("table_width", table_width, 0.05, 10.0),
      checkRange("table_depth", table_depth, 0.05, 10.0),
      checkAbove("leg_side", leg_side, 0.0, 0.5 * std::min(table_width, table_depth)),
      checkRange("link_sigmas", link_sigmas, 1.0, 20.0),
      checkAbove("p_miss", p_miss, 0.0, 1.0),
      checkCount("free_pass_cap", free_pass_cap, 0, 1000),
      checkRange("free_margin", free_margin, 0.0, 0.5 * leg_side),
      checkRange("size_min_side", size_min_side, 0.05, 10.0),
      checkRange("size_max_short", size_max_short, size_min_side, 10.0),
      checkRange("size_max_long", size_max_long, size_max_short, 10.0),
      checkAbove("leg_min", leg_min, 0.0, 0.5 * size_min_side),
      checkRange("leg_max", leg_max, leg_min, 0.5 * size_min_side),
      checkAbove("c_W", c_W, 0.0, 1e6),
      checkAbove("alpha_W", alpha_W, 0.0, 1e6),
      checkRange("wall_cost_per_m", wall_cost_per_m, 0.0, 1e3),
      checkRange("wall_min_length", wall_min_length, 0.001, 1.0),
      checkAbove("wall_solid_depth", wall_solid_depth, 0.0, 1.0),
      checkAbove("p_wall_end_free", p_wall_end_free, 0.0, 0.5),
      checkRange("catalog_weight", catalog_weight, 0.0, std::nextafter(1.0, 0.0)),
      checkAbove("catalog_sigma", catalog_sigma, 0.0, 0.5)};
  for (const Status& s : checks) {
    if (!s) return s;
  }
  return okStatus();
}

}  // namespace crunch
