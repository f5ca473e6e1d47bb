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

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "crunch/blackboard/blackboard.h"
#include "crunch/core/result.h"
#include "crunch/core/rng.h"

namespace crunch {

enum class Acceptance {
  kTempered,  // P(new)^b / (P(new)^b + P(old)^b): the annealed Gibbs conditional (default)
  kLiteral,   // P(new | mb)^b, eq. 29 read literally
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
  // Pose moves.
  double jitter_sigma_r = 0.01;
  double jitter_sigma_theta = kPi / 90;
  // Q(pa(L)): weight each of the 8 table placements that put the leg at a corner by the legs
  // already near its other corners, and let the new table adopt those orphan legs in the same
  // move (the paper's "smart proposals", §4). Off: uniform over the 8 placements, no adoption.
  bool smart_parent = true;
  // Each leg near another corner of a placement adds this to its weight (base weight 1).
  double smart_parent_gain = 8.0;
  bool prune = true;
  // Walls (ModelParams::objects == kRooms; wall_moves.cc). Each sweep, each oriented shapelet
  // no wall explains yet seeds a data-driven wall birth with this probability: a segment fitted
  // to the collinear shapelets around it (grown along the line while the next inlier is within
  // wall_grow_gap).
  double wall_birth_rate = 0.25;
  double wall_grow_gap = 0.5;
  // Pose moves of a wall: perpendicular shift and turn about its middle; an end moved along it;
  // the gap a split cuts out at most; the reach within which merge finds a partner.
  double wall_jitter_r = 0.005;
  double wall_jitter_theta = kPi / 360;
  double wall_end_sigma = 0.05;
  double wall_split_gap = 0.3;
  double wall_merge_reach = 0.5;
  // Called by anneal() after each temperature (its sweeps and pruning) with the temperature's
  // place in the annealing, 0 = the hottest (beta_{schedule_steps-1}) ... schedule_steps - 1 =
  // the coldest, its beta, and the blackboard: for pictures of it part-way (paper Fig. 4).
  // Empty by default.
  std::function<void(int step, double beta, const Blackboard& board)> after_temperature;

  // The ranges: schedule_steps and sweeps_per_temperature 1..1000 (a run's time grows with
  // their product); schedule_log_top in [-50, 50] and schedule_log_step in [0, 10] (beta stays
  // a finite double); 0 <= r1 <= r2 <= r3 <= 1; proposal spreads 0..1 m and 0..pi rad;
  // smart_parent_gain 0..1e6; wall_birth_rate 0..1; wall lengths 0..10 m and angles 0..pi.
  // okStatus(), or an Error naming the first bad field.
  Status validate() const;
};

struct SamplerStats {
  long long proposals = 0;
  long long accepted = 0;
  // With setAudit(true): the largest |local change - brute-force change| of the log joint seen
  // over all moves. Tests use it to prove each move's Markov blanket is complete.
  double audit_max_error = 0.0;
};

class Sampler {
 public:
  Sampler(Blackboard& board, const SamplerOptions& options, Rng& rng);

  // Runs the whole annealing schedule on the blackboard's current working memory.
  void anneal();
  // One pass of Algorithm 1's inner loop at inverse temperature beta (without pruning).
  void sweep(double beta);
  // Removes hypotheses linked to no shapelet directly or via a common ancestor.
  void prune();

  // MAP_t (eq. 27): the live tables after annealing.
  void mapTables(std::vector<Pose2>& out) const;
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
  void primeLeg(int slot, double beta);
  // primeLeg's leg for an oriented shapelet (on its face) and for a point contact.
  Pose2 legOnFace(const Shapelet& s);
  Pose2 legAtPoint(const Shapelet& s);
  // A table's axis (modulo pi/2) from the legs around c other than `self`, or `fallback`.
  double axisFromLegs(const Vec2& c, int32_t self, double fallback);
  // Shapelets lie near c and none is oriented (ContactReport::oriented).
  bool pointSupported(const Vec2& c) const;
  // A point (unoriented) shapelet lies within radius of c.
  bool pointNear(const Vec2& c, double radius) const;
  // Proposes a new leg at `pose` under `parent` (or kNone); the birth moves of priming and of
  // Q(ch(T)) share it.
  void proposeLegBirth(const Pose2& pose, int32_t parent, double beta);
  void deathTable(int32_t id, double beta);
  void deathLeg(int32_t id, double beta);
  void parentChange(int32_t leg, double beta);
  // A pose move's target: Gaussian steps in x, y and theta (theta kept modulo `period`).
  Pose2 jittered(const Pose2& p, double period);
  void jitterTable(int32_t id, double beta);
  void jitterLeg(int32_t id, double beta);
  void proposeChild(int32_t table, double beta);
  void proposeParent(int32_t leg, double beta);
  bool legDirectlyLinked(int32_t leg) const;
  // Samples a parent for a leg at `leg` among tables with a corner near it and the null prior,
  // weighted by their densities (eq. 9 vs eq. 13); `exclude` is never chosen.
  int32_t sampleParent(const LegHyp& leg, int32_t exclude);

  // ---- Walls (wall_moves.cc) ----
  bool walls() const { return bb_.params().objects == ObjectModel::kRooms; }
  // A wall explains shapelet s within three sigmas already.
  bool wallExplains(const Shapelet& s) const;
  void proposeWallBirth(int slot, double beta);
  void wallMove(int32_t id, double beta);
  void deathWall(int32_t id, double beta);
  void jitterWall(int32_t id, double beta);
  void extendWall(int32_t id, double beta);
  void mergeWall(int32_t id, double beta);
  void splitWall(int32_t id, double beta);
  // Removes walls along which no shapelet lies (within wallLinkRadius), as prune() does legs.
  void pruneWalls();

  Blackboard& bb_;
  SamplerOptions opt_;
  Rng& rng_;
  SamplerStats stats_;
  std::vector<double> betas_;
  std::vector<Ref> order_;
  std::vector<int32_t> wall_slots_;  // shapelets along the walls a move changes
  std::vector<int32_t> inliers_;     // a wall birth's fitted shapelets
  bool audit_ = false;
  double audit_before_ = 0.0;
};

}  // namespace crunch
