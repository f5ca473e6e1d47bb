// The factors of the blackboard's factor graph (paper eqs. 9-12, 17, 24-26, 28), in log space.
// Pure functions of hypothesis values: no blackboard state, no allocation.
//
// Each factor comes in two forms with the same arithmetic, so the same result bit for bit: the
// reference form takes ModelParams and the records' poses and calls libm for every log of a
// constant and every cos/sin; the hot form (issue 15) takes the logs once computed (FactorLogs)
// and the cos/sin a Blackboard keeps with each of its records (TableHyp::trig, LegHyp::trig).
// The reference form is what Blackboard::totalEnergy() (the audit) uses.
#pragma once

#include <span>

#include "crunch/blackboard/hypotheses.h"
#include "crunch/blackboard/params.h"
#include "crunch/robot/shapelet.h"

namespace crunch {

// Delta_TL of eq. 10 for leg `leg` under table `table`; `corner` receives the argmin corner i.
// The angle term compares the leg's square outline, so it is taken modulo pi/2.
// This form is for a table of the paper's one size (ModelParams::table_width ...); the next
// uses the table's own size, and its leg-width term compares the table's leg side with the leg's.
double deltaTL(const Pose2& table, const LegHyp& leg, const ModelParams& p, int* corner);
double deltaTLSized(const TableHyp& table, const LegHyp& leg, const ModelParams& p, int* corner);
// deltaTLSized with table.trig (a Blackboard's record) for the table's cos/sin.
double deltaTLHeld(const TableHyp& table, const LegHyp& leg, const ModelParams& p, int* corner);

// The logs of the model's constant parameters, computed once (a term of the log joint calls no
// libm function for a constant).
struct FactorLogs {
  explicit FactorLogs(const ModelParams& p);
  double c_S, c_L, alpha_L, alpha_S, alpha_W, delta3, p_miss;
  double max_p;  // log of logPresenceOdds' cap on P(H)
};

// Delta_LS of eq. 12: squared perimeter distance and side-angle error (modulo pi, since a
// surface orientation is a line direction) of shapelet `s` against the leg. tau terms vanish:
// every surface has tau = 1 in the present system.
double deltaLS(const LegHyp& leg, const Shapelet& s, const ModelParams& p);
// deltaLS with leg.trig (a Blackboard's record) for the leg's cos/sin.
double deltaLSHeld(const LegHyp& leg, const Shapelet& s, const ModelParams& p);

// log p(L | parent) with the leg caused by a mixture of its parent and the null prior (eq. 9,
// eq. 13 combined by eq. 17): log(c_L + alpha_L exp(-Delta_TL)); log c_L without a parent.
double logLegDensity(double delta_tl, bool has_parent, const ModelParams& p);
double logLegDensity(double delta_tl, bool has_parent, const FactorLogs& k);

// Whether a leg of side `side` can cause `s`: not when s lies on a flat face known to be longer
// than the leg's diagonal (Shapelet::face_span: two whiskers' tips on one face further apart
// than any two points of the leg). Such a contact is left to the background term c_S (eq. 14).
inline bool legCanCause(double side, const Shapelet& s) {
  return s.face_span <= side * 1.4142135623730951;
}

// log of the kernel alpha_S exp(-Delta_LS) of eq. 11; -infinity where !legCanCause.
double logShapeletKernel(const LegHyp& leg, const Shapelet& s, const ModelParams& p);
// The same with leg.trig (a Blackboard's record) and the logs computed once.
double logShapeletKernelHeld(const LegHyp& leg, const Shapelet& s, const ModelParams& p,
                             const FactorLogs& k);

// Delta_WS of a wall (objects == kRooms): (distance from s to the segment / sigma_r_shapelet)^2
// plus, for an oriented shapelet, (angle between phi and the segment, modulo pi,
// / sigma_theta_shapelet)^2: eq. 12's style with the segment for the leg's perimeter.
double deltaWS(const WallHyp& wall, const Shapelet& s, const ModelParams& p);

// Whether a wall's surface faces the whisker that sensed s: its base (ox, oy) lies on the wall's
// free side (the left of a->b). A face cannot be touched from inside the solid behind it.
inline bool wallFaces(const WallHyp& wall, const Shapelet& s) {
  return wall.solidNormal().dot(Vec2{s.ox - wall.a.x(), s.oy - wall.a.y()}) < 0.0;
}

// log of the wall's kernel alpha_W exp(-Delta_WS); -infinity where !wallFaces. A wall can cause
// any contact on it whatever its face_span (a wall is the long face legCanCause() refuses legs).
double logWallKernel(const WallHyp& wall, const Shapelet& s, const ModelParams& p);
double logWallKernel(const WallHyp& wall, const Shapelet& s, const ModelParams& p,
                     const FactorLogs& k);

// log p(S | pa(S)) by the continuous noisy-OR of eq. 17: log(c_S + sum_j kernel_j), from the
// kernels' logs.
double logShapeletDensity(std::span<const double> log_kernels, const ModelParams& p);

// log P(H) - log P(not H) for a hypothesis whose density under its parents is exp(log_density):
// P(H) = delta^3 p (eq. 28). This is the hypothesis' own factor in the Markov-blanket
// conditional of eq. 29. P(H) is capped just below one.
double logPresenceOdds(double log_density, const ModelParams& p);
double logPresenceOdds(double log_density, const FactorLogs& k);

// log(exp(a) + exp(b)) without overflow.
double logAddExp(double a, double b);

// Acceptance probability of a move that changes the log joint by `delta` at inverse temperature
// beta: the annealed Gibbs conditional of eq. 29, P(new)^beta / (P(new)^beta + P(old)^beta).
double temperedAcceptance(double delta, double beta);

// The literal reading of eq. 29, P^beta(new | mb) with P the untempered conditional. Kept as an
// option; see docs/BLACKBOARD.md for why it is not the default.
double literalAcceptance(double delta, double beta);

}  // namespace crunch
