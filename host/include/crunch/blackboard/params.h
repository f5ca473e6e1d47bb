// Parameters of the hierarchical table -> leg -> shapelet model (paper §2.6, §3.3).
// Defaults are the paper's; where the paper is ambiguous the choice is documented here and in
// docs/BLACKBOARD.md, and every value is an option.
#pragma once

#include <string>

#include "crunch/core/geometry.h"
#include "crunch/core/result.h"

namespace crunch {

// Two walls meet at a junction (a corner, a T) only at an angle of at least this (modulo pi):
// the midpoint between collinear (one wall) and perpendicular (a room's corner).
inline constexpr double kWallJunctionAngle = kPi / 4;

// Whether the end `e` of a wall along `angle` meets the wall a..b: a..b passes within `radius`
// of it at a junction's angle. The one definition of a joined end, for the log joint
// (ModelParams::p_wall_end_free) and the fused map (wall_fusion.h).
inline bool wallEndMeets(const Vec2& e, double angle, const Vec2& a, const Vec2& b,
                         double radius) {
  return distanceToSegment(e, a, b) <= radius &&
         lineAngleDiff(std::atan2(b.y() - a.y(), b.x() - a.x()), angle) >= kWallJunctionAngle;
}

// What the blackboard can believe a room holds (`--model`, issue 13).
enum class ObjectModel {
  // The paper's: one table size (table_width x table_depth, leg_side legs), no walls, the
  // paper's acceptance. Keeps the paper's figures reproducible.
  kPaper,
  // The paper's one table size, and walls as line segments (docs/BLACKBOARD.md "Walls").
  kWalls,
  // Walls, and four-legged objects of any size within the prior's range (chairs to desks;
  // docs/BLACKBOARD.md "Tables of any size").
  kRooms,
};

// "paper" | "walls" | "rooms"; an Error naming the choices otherwise.
Result<ObjectModel> objectModelByName(const std::string& name);
const char* objectModelName(ObjectModel m);

struct ModelParams {
  ObjectModel objects = ObjectModel::kPaper;
  // Null priors (eqs. 7, 13, 14). Densities, not normalised.
  double c_T = 0.4;
  double c_L = 0.1;
  double c_S = 0.05;
  // Scale of the causal densities p(L|T) = alpha_L exp(-Delta_TL) (eq. 9) and
  // p(S|L) = alpha_S exp(-Delta_LS) (eq. 11). The paper does not give them; 1 makes a perfectly
  // placed child 1/c times likelier under its parent than under the null prior.
  double alpha_L = 1.0;
  double alpha_S = 1.0;
  // Penalty factors (eqs. 24-26): missing legs, same-type overlap, two legs at one corner.
  double eps_a = 0.3;
  double eps_b = 0.1;
  double eps_c = 0.1;
  // Spreads of eqs. 10 and 12. The paper's sigma_r = 0.2 is read in units of the leg side
  // (0.05 m), the unit that also maps its sensor-noise figures (0.1, 0.5) onto the architecture's
  // 5 mm / 25 mm regimes: sigma_r = 0.2 * 0.05 m = 0.01 m. See docs/BLACKBOARD.md.
  double sigma_r_leg = 0.01;           // leg centre vs table corner, metres (eq. 10)
  double sigma_theta_leg = kPi / 32;   // leg vs table angle (eq. 10)
  double sigma_r_shapelet = 0.01;      // shapelet vs leg perimeter, metres (eq. 12)
  double sigma_theta_shapelet = kPi / 32;  // shapelet vs leg side angle (eq. 12)
  double sigma_w = 0.01;               // leg side vs table's leg side (eq. 10)
  // delta^3 of eq. 28: the probability mass of one hypothesis is delta3 * density.
  double delta3 = 0.4;
  // The one table model of §2.8: fixed size, all hypotheses share it.
  double table_width = 0.80;
  double table_depth = 0.50;
  double leg_side = 0.05;
  // The size prior of the rooms model (ObjectModel::kRooms, issue 13): a four-legged object's
  // top is uniform over the sides in [size_min_side, size_max_long] with the shorter side at most
  // size_max_short (chairs and stools ~0.3-0.6 m up to desks ~2.0 x 1.0 m), its leg side uniform
  // in [leg_min, leg_max], mixed with the catalog below (docs/BLACKBOARD.md "Tables of any size",
  // "The catalog"). Unused under kPaper, where every table is table_width x table_depth.
  double size_min_side = 0.30;
  double size_max_long = 2.00;
  double size_max_short = 1.00;
  double leg_min = 0.02;
  double leg_max = 0.08;
  // Charge a free size its Occam factor (logSizePrior). Off by default: with the paper's
  // unnormalised constants (c_L, alpha_L) the factor, about exp(-7.5), outweighs what a fully
  // seen four-legged table gains (about exp(+2.6); docs/BLACKBOARD.md), so no table survives.
  bool size_occam = false;
  // The catalog (issue 13, "a prior over typical sizes"): the one table this model already knows
  // (table_width x table_depth, the paper's) as a class inside the rooms model's range. With
  // weight catalog_weight the size prior is the mixture (1 - w) U + w N, N a Gaussian of sd
  // catalog_sigma on each side of the top about the catalog's (a maker's tolerance, not a fit),
  // U the uniform above; the leg side stays uniform under both. A table of the catalog's size
  // then earns the prior density its fixed size deserves, log(w N / U) ~ +8 nats at 5 mm, which
  // a free size cannot: "model no more than a scene needs". 0 turns it off.
  double catalog_weight = 0.5;
  double catalog_sigma = 0.005;
  // Count the catalog's term only over the sides the evidence fixes (Blackboard::tableSizeTerm):
  // a side is fixed where contacts in working memory, or whisker passes (with negative
  // evidence), lie within a leg's link radius of both ends of one of its edges; the others are
  // integrated out (logCatalogFactor). On for the maps, which are the cold end of an anneal and
  // keep a density without its volume; the exploring robot's posterior draws (beta = 1, where
  // the full density is right) turn it off (Mapper's sample board). docs/BLACKBOARD.md "The
  // catalog over the sides the evidence fixes".
  bool catalog_fixed_sides = true;
  // Eq. 30: a parent or child farther than this many sigmas is treated as unrelated
  // (its density is below exp(-link_sigmas^2 / 1) ~ 1e-16 of the peak).
  double link_sigmas = 6.0;
  // Negative evidence (free_space.h; used only when a FreeSpaceGrid is attached): a leg, or a
  // table's corner, through whose core an untouched whisker passed is charged log(p_miss) per
  // pass, counting at most free_pass_cap passes (neighbouring samples of one whisk are not
  // independent looks). The core is the leg square shrunk by free_margin on every side, so a
  // whisker grazing a real leg's outline does not count against it.
  double p_miss = 0.05;
  int free_pass_cap = 2;
  double free_margin = 0.015;

  // Walls (walled(): objects kWalls or kRooms; docs/BLACKBOARD.md "Walls"). A wall W has the null prior
  // c_W (its presence odds as a table's: eq. 28 with c_W) and costs wall_cost_per_m per metre
  // of its length in the log joint, so a wall must be paid for by the shapelets it explains:
  // "model no more than a scene needs". It causes a shapelet with the kernel
  // alpha_W exp(-Delta_WS), Delta_WS = (d / sigma_r_shapelet)^2 + (angle / sigma_theta_shapelet)^2,
  // d the shapelet's distance to the segment and angle between phi and the segment modulo pi
  // (eq. 12's style; a point shapelet has the distance term only), and cannot cause one sensed
  // from behind it (its whisker base on the solid side). A wall's solid: the band
  // wall_solid_depth deep behind its surface (the least thickness of a wall, less than the
  // simulator's 2 cm). A leg or a table top whose centre is behind the surface and whose
  // footprint reaches into the band is charged log eps_b (eq. 25's style: two things cannot
  // share space).
  double c_W = 0.4;
  double alpha_W = 1.0;
  double wall_cost_per_m = 2.0;
  double wall_solid_depth = 0.015;
  // Shortest wall a move may make.
  double wall_min_length = 0.05;
  // Walls end at walls (docs/BLACKBOARD.md "Walls end at walls"): of a room's wall ends, a
  // fraction p_wall_end_free are free (a door jamb, the end of a partition); the others meet
  // another wall at a corner or a T. Each free end adds log(p / (1 - p)) to the log joint, a
  // joined end 0. An end is joined when another live wall's segment passes within
  // wallLinkRadius() of it at an angle of at least kWallJunctionAngle (collinear pieces are one
  // wall, not a junction). 0.5 makes an end's state cost nothing (the walls before this term).
  double p_wall_end_free = 0.2;

  // The ranges: priors c_*, alpha_* and delta3 positive (at most 1e6); penalties eps_* in
  // (0, 1]; spreads positive, at most 1 m or pi rad (sigma_w at most 1 m); the table 0.05..10 m
  // each way with a leg side above 0 and below half its shorter side; link_sigmas 1..20;
  // p_miss in (0, 1]; free_pass_cap 0..1000; free_margin 0..leg_side/2; the size prior
  // 0.05 <= size_min_side <= size_max_short <= size_max_long <= 10 m and
  // 0 < leg_min <= leg_max < size_min_side / 2 (four legs fit under the smallest top) (a leg
  // thinner than 2 free_margin has its centre point as its core); c_W, alpha_W as the other
  // priors; wall_cost_per_m 0..1e3; wall_min_length 0.001..1 m; wall_solid_depth in (0, 1] m;
  // p_wall_end_free in (0, 0.5]; catalog_weight in [0, 1), catalog_sigma in (0, 0.5] m.
  // okStatus(), or an Error naming the first bad field.
  Status validate() const;

  bool sized() const { return objects == ObjectModel::kRooms; }
  // Eq. 12 per face (kWalls, kRooms): Delta_LS of an oriented shapelet is the least over the
  // leg's four faces of (distance to the face's segment / sigma_r_shapelet)^2 + (angle to the
  // face / sigma_theta_shapelet)^2, so a contact near a corner is compared with the face its
  // line fits, not with whichever face is a millimetre nearer. kPaper keeps the reading of its
  // figures: the angle of the nearest face (docs/BLACKBOARD.md "Which face a contact is on").
  bool perFaceKernel() const { return objects != ObjectModel::kPaper; }
  // Walls are hypotheses (kWalls, kRooms).
  bool walled() const { return objects != ObjectModel::kPaper; }
  // Offset of corner i's leg centre in the frame of a `width` x `depth` table with `leg` legs
  // (legs flush in the corners), corner order (+x+y, -x+y, -x-y, +x-y).
  static Vec2 cornerOffset(int i, double width, double depth, double leg) {
    const double hx = 0.5 * (width - leg), hy = 0.5 * (depth - leg);
    return {(i == 0 || i == 3) ? hx : -hx, (i < 2) ? hy : -hy};
  }
  // The same for the one size of the paper's model.
  Vec2 cornerOffset(int i) const { return cornerOffset(i, table_width, table_depth, leg_side); }
  // The largest leg side and table half-diagonal any hypothesis can have: the paper's one size,
  // or the size prior's bounds.
  double maxLegSide() const { return sized() ? leg_max : leg_side; }
  double maxTableCircumradius() const {
    return sized() ? 0.5 * std::hypot(size_max_long, size_max_short)
                   : 0.5 * std::hypot(table_width, table_depth);
  }
  // log of the size prior's mass at (width, depth, leg): the uniform prior's density times the
  // volume the evidence pins a size to (the Occam factor of a free size; params.cc), constant
  // inside the range, -infinity outside; plus, with the catalog, log((1 - w) + w N / U)
  // (logCatalogFactor). With size_occam a table of free size must explain more than one of
  // fixed size: with the defaults about three legs' worth of evidence (docs/BLACKBOARD.md).
  // width_fixed / depth_fixed: whether the evidence fixes that side (Blackboard::tableSizeTerm).
  double logSizePrior(double width, double depth, double leg, bool width_fixed = true,
                      bool depth_fixed = true) const;
  bool legSideAllowed(double side) const { return side >= leg_min && side <= leg_max; }
  // The catalog's term of logSizePrior alone (0 without a catalog): the ratio of the mixture's
  // marginal to the uniform's over the sides the evidence fixes, the others integrated out.
  // Both sides fixed: log((1 - w) + w N / U) (+8.2 nats at the catalog's size with the
  // defaults); one side fixed at the catalog's width or depth: +3.1 nats; none: 0 (a table
  // whose size nothing measures earns nothing for the size it was drawn with;
  // catalog_fixed_sides, docs/BLACKBOARD.md "The catalog over the sides the evidence fixes").
  double logCatalogFactor(double width, double depth, bool width_fixed = true,
                          bool depth_fixed = true) const;
  // Radius within which a shapelet can be caused by a leg (eq. 30).
  double shapeletLinkRadius() const {
    return 0.5 * maxLegSide() * std::sqrt(2.0) + link_sigmas * sigma_r_shapelet;
  }
  // Distance from a segment within which a shapelet can be caused by a wall (eq. 30).
  double wallLinkRadius() const { return link_sigmas * sigma_r_shapelet; }
  // A free wall end's term: log(p_wall_end_free / (1 - p_wall_end_free)), 0 at 0.5.
  double logFreeWallEnd() const { return std::log(p_wall_end_free / (1.0 - p_wall_end_free)); }
  // Radius within which a leg centre can belong to a table corner (eq. 30).
  double cornerLinkRadius() const { return link_sigmas * sigma_r_leg; }
};

}  // namespace crunch
