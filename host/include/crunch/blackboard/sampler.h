// The annealed, blackboard-inspired Metropolis-Hastings sampler of paper Algorithm 1 (§2.7).
//
// Each annealing step: every shapelet in working memory proposes a parent leg (priming); every
// hypothesis then proposes, by a uniform draw r, its death (r < r1), a parent change (r < r2),
// a child (r < r3) or a parent (otherwise); finally hypotheses linked to no shapelet, directly
// or through a common ancestor, are pruned. Slots that mean nothing for a type (a table has only
// the null parent; a leg's children are observations) propose a small pose move instead, so
// hypotheses can refine their pose rather than only die and be reborn (docs/BLACKBOARD.md).
// A move is accepted with the annealed Markov-blanket conditional of eq. 29, computed from the
// change of the log joint (blackboard.h).
//
// After warm-up a call to anneal() performs no heap allocation (test/blackboard counts them).
// Deterministic for a given Rng state. Not thread-safe.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "crunch/blackboard/blackboard.h"
#include "crunch/blackboard/moves.h"
#include "crunch/core/result.h"
#include "crunch/core/rng.h"

namespace crunch {

enum class Acceptance {
  kTempered,  // P(new)^b / (P(new)^b + P(old)^b): the annealed Gibbs conditional (default)
  kLiteral,   // P(new | mb)^b, eq. 29 read literally
  // Reversible-jump Metropolis-Hastings: min(1, exp(b * delta + log q_reverse - log q_forward)),
  // tempering only the target, over a move set in which every move has a reverse whose proposal
  // density is known (sweepReversible, docs/BLACKBOARD.md "Reversible-jump acceptance"). At
  // b = 1 the chain leaves the posterior exp(J) invariant (test/blackboard/detailed_balance_test).
  kReversibleJump,
};

// "paper" (kTempered) | "literal" | "rj"; an Error naming the choices otherwise.
Result<Acceptance> acceptanceByName(const std::string& name);
const char* acceptanceName(Acceptance a);

// Relative frequencies of the reversible-jump kernels (Acceptance::kReversibleJump); each step
// of a sweep draws one kernel with these weights, then its object uniformly.
struct ReversibleMoves {
  double leg_birth_death = 1.0;  // a working-memory slot: birth or death of an orphan leg
  double leg_jitter = 1.0;       // a leg: Gaussian pose step
  double leg_parent = 1.0;       // a leg: parent change (sampleParent's weights)
  double leg_table = 1.0;        // a leg: birth of a parent table, or death of its sole parent
  double table_jitter = 1.0;     // a table: Gaussian pose step, children carried half the time
  // Birth of a table at a smart placement of a leg (the paper's proposeParent weights), adopting
  // every orphan leg at its corners; or death of a table, orphaning its children.
  double table_birth_death = 1.0;
  // A whole four-legged object at once: birth of a table with a leg in a working-memory
  // shapelet's box and a leg or none at each other corner, or death of a table with all its
  // legs (rjTableGroup). Without it a table standing on a wall's contacts, its other corners
  // out where nothing was sensed, is a local maximum: killing the table alone or a leg alone
  // is uphill (docs/BLACKBOARD.md "Reversible-jump acceptance").
  double table_group = 1.0;
  // Walls (ModelParams::walled() only; 0 under the paper's model whatever these say): birth of
  // a wall drawn around the segment fitted to one working-memory shapelet's collinear
  // neighbours, or death of any wall; and a wall's symmetric pose steps (jitterWall, extendWall).
  double wall_birth_death = 1.0;
  double wall_jitter = 1.0;
  // The rooms model's sizes (ModelParams::sized() only; 0 otherwise): a symmetric step on a
  // table's width and depth (one corner fixed), on its leg side, or on a leg's side (rjSizeStep).
  double sizes = 1.0;
};

struct SamplerOptions {
  // Annealing schedule beta_i = exp(schedule_log_top - schedule_log_step * i), visited from
  // i = schedule_steps - 1 down to 0: the paper's beta_i = exp(7.5 - 0.5 i) run as a cooling,
  // from beta = 1 (the posterior itself) to beta = e^7.5 ~ 1808 (close to its mode).
  double schedule_log_top = 7.5;
  double schedule_log_step = 0.5;
  int schedule_steps = 16;
  int sweeps_per_temperature = 1;
  // Thresholds r1 < r2 < r3 of Algorithm 1.
  double r1 = 0.1;
  double r2 = 0.4;
  double r3 = 0.7;
  Acceptance acceptance = Acceptance::kTempered;
  // Q(pa(S)): a leg behind the touched surface, anywhere along a face, with this jitter.
  double prime_sigma_r = 0.003;
  double prime_sigma_theta = kPi / 64;
  // The chance a sweep primes a shapelet that the live hypotheses already explain at least as
  // well as clutter does (Blackboard::shapeletExplanation >= log 2); the others are primed at
  // every sweep. 1: every shapelet every sweep, Algorithm 1 as the paper has it (the per-pose
  // default). The global inference sets MappingOptions::global_prime_explained: there priming
  // is 80 % of the proposals, and an explained shapelet's is taken 1 time in 700-1000
  // (docs/BENCHMARKS.md "The move mix").
  double prime_explained = 1.0;
  // Pose moves.
  double jitter_sigma_r = 0.01;
  double jitter_sigma_theta = kPi / 90;
  // Q(pa(L)): weight each of the 8 table placements that put the leg at a corner by the legs
  // already near its other corners, and let the new table adopt those orphan legs in the same
  // move (the paper's "smart proposals", §4). Off: uniform over the 8 placements, no adoption.
  bool smart_parent = true;
  // Each leg near another corner of a placement adds this to its weight (base weight 1).
  double smart_parent_gain = 8.0;
  // With smart_parent, under the walls and rooms models (ModelParams::walled()): a table born
  // with adopted legs takes the pose that fits its corners to its legs in least squares
  // (fitRigid) instead of the proposer's corner and orientation, and turns its legs to its axes
  // (docs/BLACKBOARD.md "Tables fitted to their legs"). The paper's model keeps its proposal.
  bool fit_parent = true;
  // Under the rooms model (ModelParams::sized()), each sweep also proposes to split every table
  // at an orphan leg on its long side (splitTable). Off: measurement and tests only.
  bool split_tables = true;
  bool prune = true;
  // Incremental energies (Blackboard::energyBefore): a move evaluates the terms it changes once,
  // after the move, taking the before side from the cache. Off: both sides afresh (the reference
  // path; the same chain up to rounding, for benchmarks).
  bool incremental_energy = true;
  // Acceptance::kReversibleJump only (sweepReversible). Q(pa(S)) there is uniform over a box
  // in the shapelet's frame: along the face within half a leg side plus rj_box_margin, behind
  // it at half a leg side (up to half the diagonal for a point contact) give or take
  // rj_box_margin, turned within rj_box_theta of the face (any way for a point contact).
  ReversibleMoves rj_moves;
  double rj_box_margin = 0.01;
  double rj_box_theta = kPi / 16;
  // Steps per sweep: this many per working-memory shapelet a leg can cause.
  int rj_steps_per_shapelet = 4;
  // The reference measure of the reversible target: J (blackboard.h) is each hypothesis'
  // presence log-odds, P(H) = delta^3 p (eq. 28), i.e. a probability per pose cell; the
  // target's density over poses (x, y, theta) is exp(J) / rj_cell^n for n hypotheses.
  // Default: the model's leg-to-corner resolution, sigma_r_leg^2 * sigma_theta_leg
  // (0.01 m)^2 * pi/32 ~ 1e-5 m^2 rad. It sets what beta = 1 means; the cold end does not
  // depend on it.
  double rj_cell = 1e-5;
  // The same for a wall, whose pose is its two ends (a, b) in R^4: (sigma_r_leg^2)^2 =
  // (0.01 m)^4 = 1e-8 m^4, each end resolved as a leg's centre is.
  double rj_wall_cell = 1e-8;
  // Size moves of the rooms model (ModelParams::objects == kRooms; unused under kPaper):
  // Gaussian steps of a table's width and depth (one corner held fixed) and of leg sides.
  double resize_sigma = 0.03;
  double leg_side_sigma = 0.004;
  // The share of leg-side steps (legSide, tableLegSide) drawn afresh from the prior's range
  // instead of locally. A leg touched from outside has a conditional over its side that is flat
  // over most of the range, so a leg born too wide is many local steps from where its table needs
  // it: 0.5 maps thin-legged chairs (docs/BLACKBOARD.md "A leg's side, seen from outside"), but
  // the exploring robot's draws then disagree about every leg's inner faces and infogain spends
  // its travel re-touching legs, so it is off by default (0 draws no number for it).
  double side_prior_draws = 0.0;
  // Walls (ModelParams::walled(); wall_moves.cc). Each sweep, each oriented shapelet
  // no wall explains yet seeds a data-driven wall birth with this probability: a segment fitted
  // to the collinear shapelets around it (grown along the line while the next inlier is within
  // wall_grow_gap, or within wall_grow_gap_unseen when no free ray crossed the line in between:
  // docs/BLACKBOARD.md "Gaps no whisker crossed"). 1.5 m is the gap one contact pays for,
  // log(1 + alpha_W / c_S) / wall_cost_per_m = 3.04 / 2 with the defaults: a proposal's reach,
  // past which the energy would refuse the wall anyway. At most wall_grow_gap: off.
  double wall_birth_rate = 0.25;
  double wall_grow_gap = 0.5;
  double wall_grow_gap_unseen = 1.5;
  // Pose moves of a wall: perpendicular shift and turn about its middle; an end moved along it;
  // the gap a split cuts out at most; the reach within which merge finds a partner; how far
  // joinWallEnd carries an end (and a partner's end) to meet another wall. The two reaches
  // limit what is proposed, not what is kept: each lies past the gap the energy pays for with
  // the defaults (merge: (|logodds(delta^3 c_W)| + 2 |log free end|) / wall_cost_per_m =
  // (1.66 + 2.77) / 2 = 2.2 m; a corner's two ends: 2 |log free end| / wall_cost_per_m = 1.39 m),
  // so the energy, not the proposal, decides (docs/BLACKBOARD.md "Walls end at walls").
  double wall_jitter_r = 0.005;
  double wall_jitter_theta = kPi / 360;
  double wall_end_sigma = 0.05;
  double wall_split_gap = 0.3;
  double wall_merge_reach = 2.5;
  double wall_join_reach = 1.5;
  // Called by anneal() after each temperature (its sweeps and pruning) with the temperature's
  // place in the annealing, 0 = the hottest (beta_{schedule_steps-1}) ... schedule_steps - 1 =
  // the coldest, its beta, and the blackboard: for pictures of it part-way (paper Fig. 4).
  // Empty by default.
  std::function<void(int step, double beta, const Blackboard& board)> after_temperature;
  // Called by anneal() after every sweep (before the temperature's pruning) with the
  // temperature's place in the annealing (as after_temperature), the sweep's index within it
  // and the blackboard: for estimates from samples (mapping/posterior_marginals.h). Empty by
  // default.
  std::function<void(int step, int sweep, double beta, const Blackboard& board)> after_sweep;

  // The ranges: schedule_steps and sweeps_per_temperature 1..1000 (a run's time grows with
  // their product); schedule_log_top in [-50, 50] and schedule_log_step in [0, 10] (beta stays
  // a finite double); 0 <= r1 <= r2 <= r3 <= 1; proposal spreads 0..1 m and 0..pi rad;
  // smart_parent_gain 0..1e6; rj_moves' weights 0..1e6, not all 0; rj_box_margin (0, 1],
  // rj_box_theta (0, pi/4], rj_steps_per_shapelet 1..1000, rj_cell and rj_wall_cell (0, 1]; resize_sigma and
  // leg_side_sigma 0..1 m; side_prior_draws 0..1; wall_birth_rate 0..1; wall lengths 0..10 m
  // and angles 0..pi.
  // okStatus(), or an Error naming the first bad field.
  Status validate() const;
};

struct SamplerStats {
  long long proposals = 0;
  long long accepted = 0;
  // proposals and accepted split by the family of the move that made them.
  MoveCounts by_move{};
  // With setAudit(true): the largest |local change - brute-force change| of the log joint seen
  // over all moves. Tests use it to prove each move's Markov blanket is complete.
  double audit_max_error = 0.0;
  // With setAudit(true): the largest |cached - fresh| of any term the blackboard holds cached,
  // checked after every accepted move (Blackboard::cacheError).
  double audit_cache_max_error = 0.0;
};

class Sampler {
 public:
  Sampler(Blackboard& board, const SamplerOptions& options, Rng& rng);

  // Runs the whole annealing schedule on the blackboard's current working memory.
  void anneal();
  // The same schedule a sweep at a time, for a caller that cannot wait for all of it (the
  // robot's control loop): annealSweep(k) for k = 0 .. annealSweeps() - 1 in order is anneal(),
  // draw for draw (the temperature's pruning and hooks follow its last sweep).
  int annealSweeps() const {
    return static_cast<int>(betas_.size()) * opt_.sweeps_per_temperature;
  }
  void annealSweep(int k);
  // One pass of Algorithm 1's inner loop at inverse temperature beta (without pruning); under
  // Acceptance::kReversibleJump one sweep of sweepReversible instead.
  void sweep(double beta);
  // Under Acceptance::kReversibleJump, anneal() first removes legs that lie in no working-memory
  // shapelet's birth box and then tables left without a child: the reversible chain's state
  // space (every leg in some box, every table with a child). It never prunes after that.
  void enterReversibleSpace();
  // Removes hypotheses linked to no shapelet directly or via a common ancestor.
  void prune();

  // MAP_t (eq. 27): the live tables after annealing.
  void mapTables(std::vector<Pose2>& out) const;
  // The same with each table's size (the rooms model's tables differ in size).
  void mapTables(std::vector<TableHyp>& out) const;
  // The live walls after annealing (none under ObjectModel::kPaper).
  void mapWalls(std::vector<WallHyp>& out) const;

  const SamplerStats& stats() const { return stats_; }
  const std::vector<double>& schedule() const { return betas_; }
  // Checks every move's local energy change against totalEnergy() (slow: tests only).
  void setAudit(bool on) { audit_ = on; }

 private:
  struct Ref {
    bool is_table;
    int32_t id;
    bool is_wall = false;
  };
  void begin();
  bool decide(double delta, double beta);
  // Counts the decision; an accepted move's terms become the blackboard's cache.
  void accepted(bool ok);
  // Reversible jump: accept with min(1, exp(beta * delta + log_q_ratio)), log_q_ratio =
  // log q(reverse) - log q(forward) including Jacobians.
  bool decideRj(double delta, double beta, double log_q_ratio);
  // The sampler runs Acceptance::kReversibleJump.
  bool rj() const { return opt_.acceptance == Acceptance::kReversibleJump; }
  // ---- Reversible-jump moves (Acceptance::kReversibleJump) ----
  void sweepReversible(double beta);
  // The birth box of slot s: frame and extents; false if no leg can cause the shapelet.
  struct Box {
    Vec2 origin, along, in;
    double u, v0, v1;  // |along coordinate| <= u, v0 <= inward coordinate <= v1
    bool oriented;
    double phi;
    double volume;
  };
  bool boxOf(int slot, Box& b) const;
  bool inBox(const Box& b, const Pose2& pose) const;
  bool inSomeBox(const Pose2& pose) const;
  // How far from its shapelet a leg in the shapelet's box can stand (any box).
  double boxReach() const;
  // Orphan legs in box b: the count, and the k-th (k < count) in id order.
  int orphansInBox(const Box& b, int k, int32_t* kth) const;
  // A leg pose uniform in box b (the leg births' Q(pa(S)); density 1 / b.volume).
  Pose2 drawInBox(const Box& b);
  // A table of `shape`'s size at one of a leg's 8 corner placements (1/8) plus a Gaussian step
  // (jitter_sigma_r, jitter_sigma_theta): the table births through a leg; density
  // logTableBirthDensity.
  Pose2 drawPlacement(const Pose2& leg, const TableHyp& shape);
  // A new table's size (width, depth, leg): the model's one size, or under the rooms model
  // width and depth from the size prior (uniform over its region) and the leg side about
  // `leg_side` (drawSideNear; it may fall outside the prior: the caller refuses it). No random
  // number is drawn under the other models.
  TableHyp drawTableSize(double leg_side);
  // A new leg's side: the model's one side, or uniform over the prior's range (rooms).
  double drawLegSide();
  // Rooms: a side drawn from a normal of sigma_w (eq. 10's leg-width spread) about `side`; and
  // the log of that draw's density at `side` given `near`, against the prior's uniform
  // probability (0 under the other models, which draw nothing).
  double drawSideNear(double side);
  double logSideNearDensity(double side, double near) const;
  // A drawn size inside the rooms model's prior (always true under the other models).
  bool sizeAllowed(const TableHyp& shape) const;
  // A table born through a leg at `leg` of side `side` (rjLegTable's and rjTableGroup's
  // births): its size (drawTableSize), then one of the leg's placements (drawPlacement). False
  // when the size is outside the prior or the leg is off every corner (outside the state space).
  bool drawTableThrough(const Pose2& leg, double side, TableHyp& born);
  // `shape` (its size) at `pose`; `t` with another pose and size.
  static TableHyp shaped(const TableHyp& shape, const Pose2& pose);
  static TableHyp reshaped(const TableHyp& t, const Pose2& pose, double width, double depth,
                           double leg);
  // Every child of `table` (its children as the blackboard holds them) within cornerLinkRadius
  // of one of `table`'s corners: the reversible state space after a resize.
  bool childrenAtCorners(const TableHyp& table) const;
  // The rooms model's size kernel: resizeTable or tableLegSide on a random table, or legSide on
  // a random leg, each symmetric.
  void rjSizeStep(double beta);
  void rjLegBirthDeath(int slot, double beta);
  void rjJitterLeg(int32_t id, double beta);
  void rjParentChange(int32_t id, double beta);
  void rjLegTable(int32_t id, double beta);
  void rjJitterTable(int32_t id, double beta);
  // log q(table | leg) of the births through a leg (drawTableThrough) for a leg of side
  // `leg_side`: 8 placements of the table's size, each with a Gaussian step, and (rooms) the
  // table's leg side about the leg's (logSideNearDensity). Width and depth are drawn from the
  // reference measure itself: they add nothing.
  double logTableBirthDensity(const TableHyp& table, const Pose2& leg, double leg_side) const;
  void rjTableBirthDeath(double beta);
  void rjTableGroup(double beta);
  // log q of rjTableGroup's birth of a table at `table` with legs at `legs[0..n)` (n <= 4):
  // summed over which leg came from a box (logLegBoxDensity; it must stand within
  // cornerLinkRadius of a corner) and over the assignments of the others to the corners but
  // that leg's nearest; -infinity if none can produce them. Under the rooms model the legs'
  // sides count too: the first's uniform (the reference measure's: 0), the table's leg side
  // about it (in logTableBirthDensity) and the others' about the table's (logSideNearDensity).
  double logGroupBirthDensity(const TableHyp& table, const Pose2* legs, const double* sides,
                              int n) const;
  // log of the density of a leg drawn uniformly in the box of a uniformly chosen slot of
  // rj_slots_ (summed over the boxes that hold it).
  double logLegBoxDensity(const Pose2& leg) const;
  // log of the density of a leg drawn at a table's corner: a Gaussian step (jitter_sigma_r,
  // jitter_sigma_theta) from the corner and the table's axes (theta modulo pi/2).
  double logCornerLegDensity(const TableHyp& table, int corner, const Pose2& leg) const;
  int nearestCorner(const TableHyp& table, const Vec2& at) const;
  // Walls under kReversibleJump (wall_moves.cc): the birth picks one of rj_fits_ uniformly and
  // draws each end around the fit's end: across the fit from a normal of prime_sigma_r, along it
  // from an even mixture of two normals, wall_end_sigma (extendWall's step) and 1 /
  // wall_cost_per_m (the scale over which an end is free to wander beyond its last contact at
  // beta = 1, so a wall the hot chain stretched can still be killed by the reverse). The death
  // picks a live wall uniformly. log q_birth(a, b) = log((1/N) sum_fits q(a; a_f) q(b; b_f)).
  double rjWallEndLogDensity(const Vec2& at, const Vec2& fit, const Vec2& dir) const;
  Vec2 rjWallEnd(const Vec2& fit, const Vec2& dir);
  void rjWallBirthDeath(double beta);
  double logWallBirthDensity(const Vec2& a, const Vec2& b) const;
  int32_t randomLiveWall();
  // `at` lies within cornerLinkRadius of a corner of `table` (its pose and size).
  bool nearCorner(const TableHyp& table, const Vec2& at) const;
  // The orphan legs within cornerLinkRadius of a corner of a table at `pose`; false if more
  // than kMaxChildren.
  bool adoptable(const Pose2& pose, IdSet<4 * kMaxChildren>& out) const;
  // log of the smart birth's density of a table at `pose` adopting `children` (sum over the
  // children that could have proposed it), without the 1/n_legs of the proposer's choice.
  double logSmartBirthDensity(const Pose2& pose, const IdSet<4 * kMaxChildren>& children) const;
  // The 8 placements of a table with `leg` at a corner, and their smart weights (legs already
  // near the other corners, SamplerOptions::smart_parent_gain).
  void smartPlacements(int32_t leg, std::array<Pose2, 8>& place, std::array<double, 8>& weight) const;
  // sampleParent's weights for `leg` excluding `exclude`: candidates and weights (up to 16).
  int parentCandidates(const LegHyp& leg, int32_t exclude, std::array<int32_t, 16>& cand,
                       std::array<double, 16>& weight) const;
  // A live id of the pool, uniformly (rejection over the extent); kNone if none is live.
  int32_t randomLiveLeg();
  int32_t randomLiveTable();
  // A uniformly drawn id in [0, extent) for which alive(id) holds (rejection); kNone when
  // `live` (their number) is 0. The three above share it.
  template <typename Alive>
  int32_t randomLive(int live, int32_t extent, Alive&& alive) {
    if (live == 0) return kNone;
    for (;;) {
      const auto id = static_cast<int32_t>(rng_.below(static_cast<uint32_t>(extent)));
      if (alive(id)) return id;
    }
  }
  void primeLeg(int slot, double beta);
  // Whether this sweep primes working-memory slot `slot` (SamplerOptions::prime_explained).
  bool primed(int slot);
  // primeLeg's leg for an oriented shapelet (on its face) and for a point contact.
  // `side` is the leg's side: the paper's one, or the rooms model's draw.
  Pose2 legOnFace(const Shapelet& s, double side);
  Pose2 legAtPoint(const Shapelet& s, double side);
  // A table's axis (modulo pi/2) from the legs around c other than `self`, or `fallback`.
  double axisFromLegs(const Vec2& c, int32_t self, double fallback);
  // axisFromLegs for the rooms model: partners weighted by the rectangle corners they complete.
  double axisFromPartners(const Vec2& c, int32_t self, double fallback);
  // How far from a leg its table's other legs can stand (a side or diagonal of any table).
  double reach() const;
  // Calls f(position) for each partner of a leg at c: the live legs within reach() but `self`,
  // and the point (unoriented) shapelets within it (they come before their legs).
  template <class F>
  void partnersNear(const Vec2& c, int32_t self, F&& f) const;
  // Shapelets lie near c and none is oriented (ContactReport::oriented).
  bool pointSupported(const Vec2& c) const;
  // A point (unoriented) shapelet lies within radius of c.
  bool pointNear(const Vec2& c, double radius) const;
  // Proposes a new leg at `pose` under `parent` (or kNone); the birth moves of priming and of
  // Q(ch(T)) share it.
  void proposeLegBirth(const Pose2& pose, double side, int32_t parent, double beta);
  void deathTable(int32_t id, double beta);
  // The walled models' other table death: the table and its legs die together, the reverse of
  // a table born with its legs (proposeParent's adoption, then proposeChild; the pool's start).
  void deathTableWithLegs(int32_t id, double beta);
  // The death of table `id` with all its legs: under kReversibleJump accepted with
  // log_q_ratio (rjTableGroup), else by the paper's rule (deathTableWithLegs).
  void proposeDeathWithLegs(int32_t id, double beta, double log_q_ratio);
  void deathLeg(int32_t id, double beta);
  void parentChange(int32_t leg, double beta);
  // A pose move's target: Gaussian steps in x, y and theta (theta kept modulo `period`).
  Pose2 jittered(const Pose2& p, double period);
  void jitterTable(int32_t id, double beta);
  void jitterLeg(int32_t id, double beta);
  void proposeChild(int32_t table, double beta);
  void proposeParent(int32_t leg, double beta);
  // The rooms model's moves (docs/BLACKBOARD.md "Tables of any size"): a table's width and
  // depth with one corner's leg held fixed; a table's leg side (half the time with its legs'
  // sides, its outline held); a leg's side about its centre or a corner; and a parent for a leg
  // whose size comes from the legs and point contacts around it, its legs re-sided about their
  // outer corners ("A leg's side, seen from outside"). With a catalog
  // (ModelParams::catalog_weight > 0) half the legs also get proposeParent's proposal, a table of
  // the catalog's size ("The catalog: the table the model knows, inside the rooms model").
  void resizeTable(int32_t id, double beta);
  void tableLegSide(int32_t id, double beta);
  void legSide(int32_t id, double beta);
  // A new leg side for legSide and tableLegSide: a symmetric kernel, local or from the prior.
  double drawSideStep(double side);
  void proposeParentSized(int32_t leg, double beta);
  // Splits a table across its long axis at an orphan leg standing on one of its long sides: the
  // table keeps its children at one end and ends at that leg (a corner of it), a new table
  // touching it takes the children at the other end, and orphans at the two new tables' new
  // corners are adopted (docs/BLACKBOARD.md "Splitting a table at an orphan leg"). The reverse
  // of what proposeParent does when one table grows over two neighbours' outer legs.
  void splitTable(int32_t id, double beta);
  // A signed centre-to-centre span of one side of a table proposed for a leg of `leg_side`,
  // drawn from the prior's range; `other` is the other side's span (0: unknown).
  double priorSpan(double leg_side, double other);
  // The end of a table birth that adopted legs (proposeParent, proposeParentSized): `table` is
  // live with its children set, `t` what the move touches, e0 its energy before. Turns the
  // children to the table's axes (`turn`: no leg, those only point contacts support, or all),
  // kills the tables the move emptied, and decides. Accepted: releases them, true. Refused:
  // turns the legs back and revives those tables, false (the caller restores parents and
  // removes `table`).
  enum class Turn { kNoLeg, kPointSupported, kAll };
  // Kills each of `tables` left without a child, adding it to `emptied` (a move that takes legs
  // from their tables: revive them if refused, release them if accepted).
  void killEmptied(const IdSet<8>& tables, IdSet<8>& emptied);
  bool decideNewTable(int32_t table, const Pose2& pose, Turn turn, Touched& t, double e0,
                      double beta);
  // Proposes wall `id` at a..b (jitterWall, extendWall): the shapelets near the old and the
  // new segment are touched; refused, the wall goes back.
  void moveWallTo(int32_t id, const Vec2& a, const Vec2& b, double beta);
  bool legDirectlyLinked(int32_t leg) const;
  // Samples a parent for a leg at `leg` among tables with a corner near it and the null prior,
  // weighted by their densities (eq. 9 vs eq. 13); `exclude` is never chosen.
  int32_t sampleParent(const LegHyp& leg, int32_t exclude);

  // ---- Walls (wall_moves.cc) ----
  bool walls() const { return bb_.params().walled(); }
  // The segment a wall birth seeded at `slot` fits to the oriented shapelets collinear with it
  // (grown along the line, refitted by total least squares; shapelets only, no hypothesis and
  // no random draw): ends p0, p1, and whether the wall's free side (the seed's whisker's) is
  // the left of p1 -> p0 rather than of p0 -> p1. False when the seed is a point contact or
  // its evidence is a leg's (too few inliers, too short).
  struct WallFit {
    Vec2 a, b;  // ordered: the free side is the left of a -> b
    Vec2 dir;   // (b - a) / |b - a|
  };
  bool fitWallAt(int slot, Vec2& p0, Vec2& p1, bool& swapped);
  // fitWallAt's answer for `slot`, kept until the working memory changes
  // (Blackboard::workingMemoryGeneration): the same numbers, computed once per slot and memory
  // instead of once per proposal.
  bool wallFitOf(int slot, Vec2& p0, Vec2& p1, bool& swapped);
  // A wall at a..b would share space with a live wall but `self` (of id below `below`): the
  // face of one passes
  // strictly inside the other's solid band (wall_solid_depth behind its face, within its
  // length). Walls that meet at a corner do not. The reversible-jump chain's state space
  // excludes such pairs (two solids cannot overlap; docs/BLACKBOARD.md "Walls under
  // reversible jump"): its births and steps that would make one are refused.
  bool sharesSpace(const Vec2& a, const Vec2& b, int32_t self,
                   int32_t below = std::numeric_limits<int32_t>::max()) const;
  // enterReversibleSpace's walls: kills those outside the reversible state space.
  void enterReversibleWalls();
  // A wall explains shapelet s within three sigmas already.
  bool wallExplains(const Shapelet& s) const;
  void proposeWallBirth(int slot, double beta);
  void wallMove(int32_t id, double beta);
  void deathWall(int32_t id, double beta);
  // Proposes the death of wall `id`: under kReversibleJump accepted with log_q_ratio, else by
  // the paper's rule.
  void proposeWallDeath(int32_t id, double beta, double log_q_ratio);
  void jitterWall(int32_t id, double beta);
  void extendWall(int32_t id, double beta);
  void mergeWall(int32_t id, double beta);
  // Walls end at walls: one end carried along the wall's line to the line of a wall crossing it
  // at a junction's angle, that wall's near end carried to the meeting point too when it falls
  // beyond it (a corner); the paper's acceptance only.
  void joinWallEnd(int32_t id, double beta);
  // A wall moving from its segment to a..b, into a move's blanket: the wall, the shapelets along
  // both segments (wall_slots_, after beginCollect()) and the walls whose ends either can join.
  void touchWallMove(Touched& t, int32_t id, const Vec2& a, const Vec2& b);
  void splitWall(int32_t id, double beta);
  // Removes walls along which no shapelet lies (within wallLinkRadius), as prune() does legs.
  void pruneWalls();

  Blackboard& bb_;
  SamplerOptions opt_;
  Rng& rng_;
  SamplerStats stats_;
  MoveKind move_ = MoveKind::kPrime;  // the family of the move being made, for stats_.by_move
  std::vector<double> betas_;
  std::vector<Ref> order_;
  std::vector<int> rj_slots_;  // working-memory slots with a birth box (sweepReversible)
  std::vector<int32_t> wall_slots_;  // shapelets along the walls a move changes
  struct FitMemo {
    uint64_t gen = 0;  // the working memory's generation it was computed for (0: never)
    long long rays = 0;  // and the free space's ray count
    bool ok = false;
    bool swapped = false;
    Vec2 p0{0.0, 0.0}, p1{0.0, 0.0};
  };
  std::vector<FitMemo> fit_memo_;  // by working-memory slot (wallFitOf)
  std::vector<WallFit> rj_fits_;     // each working-memory seed's fit (sweepReversible)
  // axisFromPartners' partners and their weights (fixed size: a sweep allocates nothing).
  static constexpr int kMaxPartners = 32;
  // legAtPoint's directions around a point contact when negative evidence is attached.
  static constexpr int kPointSides = 8;
  std::array<Vec2, kMaxPartners> partners_{};
  std::array<double, kMaxPartners> partner_weights_{};
  bool audit_ = false;
  double audit_before_ = 0.0;
};

}  // namespace crunch
