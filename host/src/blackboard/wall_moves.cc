// The sampler's wall moves (ModelParams::walled(); docs/BLACKBOARD.md "Walls"):
// a data-driven birth that fits a segment to the collinear shapelets around a seed shapelet
// (grown along the line, refitted by total least squares as it grows: a RANSAC-style fit used as
// a Metropolis-Hastings proposal, paper §4), death, a pose jitter, moving one end, merging two
// collinear walls and splitting one with a gap cut out. Each move computes the change of the
// log joint over the walls it changes and every shapelet along their old and new segments
// (Blackboard::collectShapeletsNearSegment), so the audit (Sampler::setAudit) checks it.
//
// Under Acceptance::kReversibleJump the sweep (sweepReversible) runs rjWallBirthDeath, whose
// birth draws a wall around one seed's fit with a density it can evaluate for the reverse, and
// the two symmetric pose steps, jitterWall and extendWall (decide() applies the Metropolis-
// Hastings rule with a log q ratio of 0 there). The other moves have no computable reverse
// (the birth that kills legs in the new wall's solid, merge, split, death by wallMove's draw)
// and run under the paper's acceptance only; their "RJ:" comments say why.
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "crunch/blackboard/factors.h"
#include "crunch/blackboard/sampler.h"

namespace crunch {

namespace {
constexpr double kLog2Pi = 1.8378770664093453;

// Running sums for a total-least-squares line fit.
struct LineFit {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
  void add(const Vec2& p) {
    n += 1;
    sx += p.x();
    sy += p.y();
    sxx += p.x() * p.x();
    sxy += p.x() * p.y();
    syy += p.y() * p.y();
  }
  Vec2 centroid() const { return {sx / n, sy / n}; }
  // Principal direction's angle (modulo pi).
  double angle() const {
    const double cxx = sxx / n - (sx / n) * (sx / n), cyy = syy / n - (sy / n) * (sy / n);
    const double cxy = sxy / n - (sx / n) * (sy / n);
    return 0.5 * std::atan2(2.0 * cxy, cxx - cyy);
  }
};
}  // namespace

namespace {
// The face a..b of one wall passes strictly inside the solid band of `w`, [0, depth] behind w's
// face and within its length (Liang-Barsky clipping of the segment in w's frame).
bool faceInSolid(const Vec2& a, const Vec2& b, const WallHyp& w, double depth) {
  const double len = w.length();
  if (len <= 0.0) return false;
  const Vec2 dir = (w.b - w.a) / len, n = w.solidNormal();
  const Vec2 pa = a - w.a, d = b - a;
  double lo = 0.0, hi = 1.0;
  const auto clip = [&](double start, double rate, double min, double max) {
    if (rate == 0.0) return start > min && start < max;
    double t0 = (min - start) / rate, t1 = (max - start) / rate;
    if (t0 > t1) std::swap(t0, t1);
    lo = std::max(lo, t0);
    hi = std::min(hi, t1);
    return lo < hi;
  };
  return clip(pa.dot(dir), d.dot(dir), 0.0, len) && clip(pa.dot(n), d.dot(n), 0.0, depth);
}
}  // namespace

bool Sampler::sharesSpace(const Vec2& a, const Vec2& b, int32_t self, int32_t below) const {
  const double depth = bb_.params().wall_solid_depth;
  WallHyp probe;
  probe.a = a;
  probe.b = b;
  const Vec2 mid = 0.5 * (a + b);
  const double reach = 0.5 * (b - a).norm() + depth;
  for (int32_t o = 0; o < std::min(below, bb_.wallExtent()); ++o) {
    const WallHyp& w = bb_.wall(o);
    if (o == self || !w.alive) continue;
    if (distanceToSegment(mid, w.a, w.b) > reach) continue;
    if (faceInSolid(a, b, w, depth) || faceInSolid(w.a, w.b, probe, depth)) return true;
  }
  return false;
}

bool Sampler::wallExplains(const Shapelet& s) const {
  const ModelParams& p = bb_.params();
  bool yes = false;
  bb_.wallsNear({s.x, s.y}, p.wallLinkRadius(), [&](int32_t o) {
    const WallHyp& w = bb_.wall(o);
    if (w.alive && deltaWS(w, s, p) < 9.0) yes = true;
  });
  return yes;
}

bool Sampler::fitWallAt(int slot, Vec2& p0, Vec2& p1, bool& swapped) {
  const ModelParams& p = bb_.params();
  const Shapelet& seed = bb_.shapelet(slot);
  if (!seed.oriented) return false;
  // Inliers: oriented shapelets within three sigmas of the line in distance and angle.
  const double tol_r = 3.0 * p.sigma_r_shapelet, tol_th = 3.0 * p.sigma_theta_shapelet;
  const double leg_diag = p.leg_side * std::sqrt(2.0);
  const double gap = opt_.wall_grow_gap;
  LineFit fit;
  Vec2 c{seed.x, seed.y};
  double th = seed.phi;
  Vec2 dir{std::cos(th), std::sin(th)};
  Vec2 lo = c, hi = c;  // the inliers furthest back and forward along dir
  const Vec2 nrm0{-dir.y(), dir.x()};
  const double seed_side = (Vec2{seed.ox, seed.oy} - c).dot(nrm0);
  if (seed_side == 0.0) return false;
  double max_span = 0.0;
  // An inlier of the current line: oriented along it within tol_th, sensed from the seed's side
  // (the same face), within tol_r of it; `t` its place along dir.
  const auto inlier = [&](const Shapelet& so, double& t) {
    if (!so.oriented || lineAngleDiff(so.phi, th) > tol_th) return false;
    const double side = (Vec2{so.ox, so.oy} - c).dot(nrm0);
    if (side * seed_side <= 0.0) return false;
    const Vec2 q = Vec2{so.x, so.y} - c;
    t = q.dot(dir);
    return std::abs(q.x() * dir.y() - q.y() * dir.x()) <= tol_r;
  };
  // Window [t_from, t_to] along the current line; the first is around the seed.
  const auto take = [&](double t_from, double t_to) {
    int added = 0;
    const Vec2 mid = c + dir * (0.5 * (t_from + t_to));
    bb_.shapeletsWithin(mid, 0.5 * (t_to - t_from) + tol_r, [&](int32_t o) {
      const Shapelet& so = bb_.shapelet(o);
      double t = 0.0;
      if (!inlier(so, t) || t < t_from || t > t_to) return;
      fit.add({so.x, so.y});
      max_span = std::max(max_span, so.face_span);
      if (t < (lo - c).dot(dir)) lo = {so.x, so.y};
      if (t > (hi - c).dot(dir)) hi = {so.x, so.y};
      ++added;
    });
    return added;
  };
  // Past the near gap: the nearest inlier within unseen_gap beyond `from` (sense +1 forward,
  // -1 back), taken when no free ray crossed the line between (Blackboard::wallFreeTerm is 0
  // there): a wall predicts a contact wherever a whisker reached its line, so a gap no whisker
  // crossed is as much a wall's as a contact is, and one a whisker passed through is not.
  const double unseen_gap = std::max(gap, opt_.wall_grow_gap_unseen);
  const auto takeUnseen = [&](double from, double sense) {
    if (unseen_gap <= gap || !bb_.hasFreeSpace()) return 0;
    double best = std::numeric_limits<double>::infinity();
    const Vec2 mid = c + dir * (from + sense * 0.5 * unseen_gap);
    bb_.shapeletsWithin(mid, 0.5 * unseen_gap + tol_r, [&](int32_t o) {
      double t = 0.0;
      if (!inlier(bb_.shapelet(o), t)) return;
      const double ahead = sense * (t - from);
      if (ahead > 1e-9 && ahead <= unseen_gap) best = std::min(best, ahead);
    });
    if (!std::isfinite(best)) return 0;
    const double to = from + sense * best;
    if (bb_.wallFreeTerm(c + dir * from, c + dir * to) != 0.0) return 0;
    return sense > 0 ? take(from + 1e-9, to) : take(to, from - 1e-9);
  };
  const auto refit = [&]() {
    if (fit.n < 2) return;
    const Vec2 cen = fit.centroid();
    if ((hi - lo).norm() >= leg_diag) {
      double a = fit.angle();
      if (std::cos(a - th) < 0) a += kPi;  // keep the direction's sense
      th = a;
      dir = {std::cos(th), std::sin(th)};
    }
    c = cen;
  };
  take(-gap, gap);
  refit();
  for (int guard = 0; guard < 1000; ++guard) {
    const double t1 = (hi - c).dot(dir), t0 = (lo - c).dot(dir);
    int grown = take(t1 + 1e-9, t1 + gap) + take(t0 - gap, t0 - 1e-9);
    if (grown == 0) grown = takeUnseen(t1, 1.0) + takeUnseen(t0, -1.0);
    if (grown == 0) break;
    refit();
  }
  const double t0 = (lo - c).dot(dir), t1 = (hi - c).dot(dir);
  // Evidence no longer than a leg's face is a leg's to explain (legCanCause's converse), unless
  // a contact on it is known to lie on a longer face.
  if (fit.n < 3 || (t1 - t0 < std::max(leg_diag, p.wall_min_length) && max_span <= leg_diag))
    return false;
  if (t1 - t0 < p.wall_min_length) return false;
  p0 = c + dir * t0;
  p1 = c + dir * t1;
  // The free side is the left of a->b (hypotheses.h): where the seed's whisker was.
  swapped = (p1 - p0).x() * (seed.oy - p0.y()) - (p1 - p0).y() * (seed.ox - p0.x()) < 0.0;
  return true;
}

bool Sampler::wallFitOf(int slot, Vec2& p0, Vec2& p1, bool& swapped) {
  FitMemo& m = fit_memo_[static_cast<size_t>(slot)];
  const uint64_t gen = bb_.workingMemoryGeneration();
  // The fit reads the free space too (takeUnseen): rays added since count as a new generation.
  const long long rays = bb_.freeSpaceRays();
  if (m.gen != gen || m.rays != rays) {
    m.gen = gen;
    m.rays = rays;
    m.ok = fitWallAt(slot, m.p0, m.p1, m.swapped);
  }
  p0 = m.p0;
  p1 = m.p1;
  swapped = m.swapped;
  return m.ok;
}

void Sampler::proposeWallBirth(int slot, double beta) {
  const Shapelet& seed = bb_.shapelet(slot);
  if (!seed.oriented || rng_.uniform() >= opt_.wall_birth_rate) return;
  if (wallExplains(seed)) return;
  Vec2 p0, p1;
  bool swapped = false;
  if (!wallFitOf(slot, p0, p1, swapped)) return;
  const double sr = opt_.prime_sigma_r;
  const Vec2 da{rng_.normal(0, sr), rng_.normal(0, sr)}, db{rng_.normal(0, sr), rng_.normal(0, sr)};
  Vec2 a = p0 + da, b = p1 + db;
  // The free side is the left of a->b (hypotheses.h): where the seed's whisker was.
  if ((b - a).x() * (seed.oy - a.y()) - (b - a).y() * (seed.ox - a.x()) < 0.0) std::swap(a, b);

  // Legs standing in the new wall's solid (priming puts a leg behind every contact, the wall's
  // included) die in the same move: the wall takes over their evidence, as a new table adopts
  // the legs at its corners (proposeParent). So do their tables when no leg is left to them:
  // a table born on a wall's contacts (its other corners out in unswept space, where nothing
  // refutes it) is then one move from the wall, not a death and a birth apart across a valley.
  // A leg whose table the move could not also track (Touched::tables full) stays. Not a
  // reversible-jump move (its reverse would have to rebirth those legs and tables at their
  // poses): the RJ sweep's wall birth is rjWallBirthDeath, which leaves legs to their own moves.
  WallHyp probe;
  probe.a = a;
  probe.b = b;
  Touched t;
  bb_.legsInSolid(probe, [&](int32_t o) {
    const int32_t parent = bb_.leg(o).parent;
    if (parent != kNone) t.tables.add(parent);
    if (parent == kNone || t.tables.contains(parent)) t.legs.add(o);
  });
  wall_slots_.clear();
  bb_.beginCollect();
  bb_.collectShapeletsNearSegment(a, b, wall_slots_);
  for (int32_t l : t.legs.span()) bb_.collectShapeletsNearLeg(l, wall_slots_);
  bb_.touchWallEnds(t, a, b);
  begin();
  const double e0 = bb_.energyBefore(t, wall_slots_);
  for (int32_t l : t.legs.span()) bb_.killLeg(l);
  IdSet<8> emptied;
  killEmptied(t.tables, emptied);
  const int32_t id = bb_.addWall(a, b);
  t.walls.add(id);
  const double e1 = bb_.energyAfter(t, wall_slots_);
  if (decide(e1 - e0, beta)) {
    for (int32_t l : t.legs.span()) bb_.releaseLeg(l);
    for (int32_t tab : emptied.span()) bb_.releaseTable(tab);
    return;
  }
  bb_.killWall(id);
  bb_.releaseWall(id);
  for (int32_t tab : emptied.span()) bb_.reviveTable(tab);
  for (int32_t l : t.legs.span()) bb_.reviveLeg(l);
}

void Sampler::wallMove(int32_t id, double beta) {
  const double r = rng_.uniform();
  if (r < opt_.r1) deathWall(id, beta);
  else if (r < 0.35) jitterWall(id, beta);
  else if (r < 0.6) extendWall(id, beta);
  else if (r < 0.75) joinWallEnd(id, beta);
  else if (r < 0.875) mergeWall(id, beta);
  else splitWall(id, beta);
}

void Sampler::deathWall(int32_t id, double beta) {
  // Under the paper's acceptance only (its reverse, the data-driven birth, has no density this
  // move could evaluate; the reversible chain's death is rjWallBirthDeath's).
  proposeWallDeath(id, beta, 0.0);
}

void Sampler::proposeWallDeath(int32_t id, double beta, double log_q_ratio) {
  const WallHyp w = bb_.wall(id);
  wall_slots_.clear();
  bb_.beginCollect();
  bb_.collectShapeletsNearSegment(w.a, w.b, wall_slots_);
  Touched t;
  t.walls.add(id);
  bb_.touchWallEnds(t, w.a, w.b);
  begin();
  const double e0 = bb_.energyBefore(t, wall_slots_);
  bb_.killWall(id);
  const double e1 = bb_.energyAfter(t, wall_slots_);
  const bool ok = rj() ? decideRj(e1 - e0, beta, log_q_ratio) : decide(e1 - e0, beta);
  if (ok) bb_.releaseWall(id);
  else bb_.reviveWall(id);
}

void Sampler::jitterWall(int32_t id, double beta) {
  // A Gaussian turn dth about the middle and a Gaussian shift s across the wall, along the
  // normal of the mean direction (theta + dth / 2). The reverse step (-dth, -s) has the same
  // mean direction, so it undoes the move exactly and has the same density: symmetric, and the
  // map (middle, theta) -> (middle + s n(theta + dth / 2), theta + dth) has Jacobian 1 (the
  // length is kept). Under kReversibleJump decide() takes it with a log q ratio of 0.
  const WallHyp w = bb_.wall(id);
  const double len = w.length();
  if (len <= 0) return;
  const Vec2 mid = 0.5 * (w.a + w.b), half = 0.5 * (w.b - w.a);
  const double dth = rng_.normal(0, opt_.wall_jitter_theta);
  const double c = std::cos(dth), sn = std::sin(dth);
  const Vec2 h{half.x() * c - half.y() * sn, half.x() * sn + half.y() * c};
  const double mean = std::atan2(half.y(), half.x()) + 0.5 * dth;
  const Vec2 nrm{-std::sin(mean), std::cos(mean)};
  const Vec2 m2 = mid + rng_.normal(0, opt_.wall_jitter_r) * nrm;
  moveWallTo(id, m2 - h, m2 + h, beta);
}

void Sampler::moveWallTo(int32_t id, const Vec2& a, const Vec2& b, double beta) {
  // The reversible-jump state space has no two walls sharing space (sharesSpace).
  if (rj() && sharesSpace(a, b, id)) return;
  const WallHyp w = bb_.wall(id);
  wall_slots_.clear();
  bb_.beginCollect();
  Touched t;
  touchWallMove(t, id, a, b);
  begin();
  const double e0 = bb_.energyBefore(t, wall_slots_);
  bb_.moveWall(id, a, b);
  const double e1 = bb_.energyAfter(t, wall_slots_);
  if (!decide(e1 - e0, beta)) bb_.moveWall(id, w.a, w.b);
}

void Sampler::touchWallMove(Touched& t, int32_t id, const Vec2& a, const Vec2& b) {
  const WallHyp& w = bb_.wall(id);
  bb_.collectShapeletsNearSegment(w.a, w.b, wall_slots_);
  bb_.collectShapeletsNearSegment(a, b, wall_slots_);
  t.walls.add(id);
  bb_.touchWallEnds(t, w.a, w.b);
  bb_.touchWallEnds(t, a, b);
}

void Sampler::extendWall(int32_t id, double beta) {
  // One end (either, equally likely) moved along the wall by a Gaussian step: symmetric, so
  // RJ: log_q_ratio = 0 (a step that would leave the wall shorter than wall_min_length is not
  // proposed; its reverse is not either).
  const WallHyp w = bb_.wall(id);
  const double len = w.length();
  if (len <= 0) return;
  const Vec2 dir = (w.b - w.a) / len;
  const double step = rng_.normal(0, opt_.wall_end_sigma);
  const bool move_b = rng_.uniform() < 0.5;
  if (len + step < bb_.params().wall_min_length) return;
  const Vec2 a = move_b ? w.a : Vec2(w.a - step * dir);
  const Vec2 b = move_b ? Vec2(w.b + step * dir) : w.b;
  moveWallTo(id, a, b, beta);
}

void Sampler::mergeWall(int32_t id, double beta) {
  const ModelParams& p = bb_.params();
  const WallHyp w = bb_.wall(id);
  const double len = w.length();
  if (len <= 0) return;
  const Vec2 dir = (w.b - w.a) / len;
  const double tol_r = 3.0 * p.sigma_r_shapelet, tol_th = 3.0 * p.sigma_theta_shapelet;
  // A partner: another wall along the same line (both its ends within tol_r of w's line, its
  // direction within tol_th) with an end within wall_merge_reach of one of w's.
  int32_t partner = kNone;
  int seen = 0;
  const auto consider = [&](int32_t o) {
    const WallHyp& ow = bb_.wall(o);
    if (o == id || !ow.alive || lineAngleDiff(ow.angle(), w.angle()) > tol_th) return;
    if ((ow.b - ow.a).dot(dir) <= 0.0) return;  // the other face (free sides opposite)
    const auto perp = [&](const Vec2& q) {
      const Vec2 d = q - w.a;
      return std::abs(d.x() * dir.y() - d.y() * dir.x());
    };
    if (perp(ow.a) > tol_r || perp(ow.b) > tol_r) return;
    const double reach = opt_.wall_merge_reach;
    const double near = std::min({(ow.a - w.a).norm(), (ow.a - w.b).norm(), (ow.b - w.a).norm(),
                                  (ow.b - w.b).norm()});
    if (near > reach && distanceToSegment(ow.a, w.a, w.b) > 0 &&
        distanceToSegment(w.a, ow.a, ow.b) > 0)
      return;
    if (rng_.uniform() * ++seen < 1.0) partner = o;
  };
  IdSet<64> cand;
  bb_.wallsNear(w.a, opt_.wall_merge_reach, [&](int32_t o) { cand.add(o); });
  bb_.wallsNear(w.b, opt_.wall_merge_reach, [&](int32_t o) { cand.add(o); });
  for (int32_t o : cand.span()) consider(o);
  if (partner == kNone) return;
  const WallHyp ow = bb_.wall(partner);
  // The merged wall: the length-weighted line of the two, spanning all four ends.
  const double l2 = ow.length();
  const Vec2 d2 = l2 > 0 ? Vec2((ow.b - ow.a) / l2) : dir;
  Vec2 md = len * dir + l2 * d2;
  md /= md.norm();
  const Vec2 cen = (len * 0.5 * (w.a + w.b) + l2 * 0.5 * (ow.a + ow.b)) / (len + l2);
  double t0 = 0, t1 = 0;
  bool first = true;
  for (const Vec2& q : {w.a, w.b, ow.a, ow.b}) {
    const double tq = (q - cen).dot(md);
    t0 = first ? tq : std::min(t0, tq);
    t1 = first ? tq : std::max(t1, tq);
    first = false;
  }
  const Vec2 a = cen + t0 * md, b = cen + t1 * md;
  // RJ: the reverse is a split of the merged wall that recreates both (a cut at the gap with
  // the gap's width, and re-fitted lines): not computable from split's draws (split keeps the
  // line); left for the reversible-jump option to pair.
  wall_slots_.clear();
  bb_.beginCollect();
  bb_.collectShapeletsNearSegment(w.a, w.b, wall_slots_);
  bb_.collectShapeletsNearSegment(ow.a, ow.b, wall_slots_);
  bb_.collectShapeletsNearSegment(a, b, wall_slots_);
  Touched t;
  t.walls.add(id);
  t.walls.add(partner);
  bb_.touchWallEnds(t, w.a, w.b);
  bb_.touchWallEnds(t, ow.a, ow.b);
  bb_.touchWallEnds(t, a, b);
  begin();
  const double e0 = bb_.energyBefore(t, wall_slots_);
  bb_.killWall(partner);
  bb_.moveWall(id, a, b);
  const double e1 = bb_.energyAfter(t, wall_slots_);
  if (decide(e1 - e0, beta)) {
    bb_.releaseWall(partner);
    return;
  }
  bb_.moveWall(id, w.a, w.b);
  bb_.reviveWall(partner);
}

void Sampler::joinWallEnd(int32_t id, double beta) {
  // Not a reversible-jump move: its reverse, the end let go back to where it was, has no
  // density this move could evaluate (ModelParams::p_wall_end_free, docs/BLACKBOARD.md "Walls
  // end at walls").
  if (rj()) return;
  const ModelParams& p = bb_.params();
  const WallHyp w = bb_.wall(id);
  const double len = w.length();
  if (len <= 0) return;
  const bool at_b = rng_.uniform() < 0.5;
  const Vec2 end = at_b ? w.b : w.a;
  const Vec2 out = (at_b ? Vec2(w.b - w.a) : Vec2(w.a - w.b)) / len;  // along the wall, outwards
  const double reach = opt_.wall_join_reach;
  // A partner, uniform among the live walls at a junction's angle whose line w's line meets
  // within reach of the end (s along `out`, backwards too: a wall through another is cut back),
  // at a point within reach of the partner's segment (u along it, in units of its length).
  int32_t partner = kNone;
  double s_at = 0, u_at = 0;
  int seen = 0;
  bb_.wallsNear(end, reach, [&](int32_t o) {
    const WallHyp& v = bb_.wall(o);
    if (o == id || !v.alive || lineAngleDiff(v.angle(), w.angle()) < kWallJunctionAngle) return;
    const Vec2 dv = v.b - v.a, q = v.a - end;
    const double den = cross2d(out, dv), vl = v.length();
    if (vl <= 0 || std::abs(den) < 1e-12) return;
    const double s = cross2d(q, dv) / den, u = cross2d(q, out) / den;
    if (std::abs(s) > reach || std::max({0.0, -u, u - 1.0}) * vl > reach) return;
    if (rng_.uniform() * ++seen < 1.0) {
      partner = o;
      s_at = s;
      u_at = u;
    }
  });
  if (partner == kNone || len + s_at < p.wall_min_length) return;
  const WallHyp v = bb_.wall(partner);
  const Vec2 meet = end + s_at * out;
  const Vec2 a = at_b ? w.a : meet, b = at_b ? meet : w.b;
  // The partner's near end to the meeting point when it lies beyond the partner (a corner).
  const bool v_moves = u_at < 0.0 || u_at > 1.0;
  const Vec2 va = u_at < 0.0 ? meet : v.a, vb = u_at > 1.0 ? meet : v.b;
  if (v_moves && (vb - va).norm() < p.wall_min_length) return;
  wall_slots_.clear();
  bb_.beginCollect();
  Touched t;
  touchWallMove(t, id, a, b);
  if (v_moves) touchWallMove(t, partner, va, vb);
  begin();
  const double e0 = bb_.energyBefore(t, wall_slots_);
  bb_.moveWall(id, a, b);
  if (v_moves) bb_.moveWall(partner, va, vb);
  const double e1 = bb_.energyAfter(t, wall_slots_);
  if (decide(e1 - e0, beta)) return;
  bb_.moveWall(id, w.a, w.b);
  if (v_moves) bb_.moveWall(partner, v.a, v.b);
}

void Sampler::splitWall(int32_t id, double beta) {
  const ModelParams& p = bb_.params();
  const WallHyp w = bb_.wall(id);
  const double len = w.length(), mn = p.wall_min_length;
  if (len < 2.0 * mn) return;
  const Vec2 dir = (w.b - w.a) / len;
  // A cut at u, uniform where both pieces keep the shortest length, and a gap uniform in
  // [0, min(wall_split_gap, what the second piece can spare)].
  const double u = rng_.uniform(mn, len - mn);
  const double g = rng_.uniform(0.0, std::min(opt_.wall_split_gap, len - mn - u));
  // RJ: forward density 1/(len - 2 mn) * 1/gmax; the reverse is a merge choosing this pair
  // (1/#partners within reach) that refits the line (deterministic): the ratio needs the merge
  // to reproduce the original exactly, which it does only for collinear pieces (as here).
  const double gmax = std::min(opt_.wall_split_gap, len - mn - u);
  const double log_q_ratio = std::log(len - 2.0 * mn) + (gmax > 0 ? std::log(gmax) : 0.0);
  (void)log_q_ratio;
  const Vec2 a1 = w.a, b1 = w.a + u * dir, a2 = w.a + (u + g) * dir, b2 = w.b;
  wall_slots_.clear();
  bb_.beginCollect();
  bb_.collectShapeletsNearSegment(w.a, w.b, wall_slots_);
  Touched t;
  t.walls.add(id);
  bb_.touchWallEnds(t, w.a, w.b);  // the pieces lie on it
  begin();
  const double e0 = bb_.energyBefore(t, wall_slots_);
  bb_.moveWall(id, a1, b1);
  const int32_t nid = bb_.addWall(a2, b2);
  t.walls.add(nid);
  const double e1 = bb_.energyAfter(t, wall_slots_);
  if (decide(e1 - e0, beta)) return;
  bb_.killWall(nid);
  bb_.releaseWall(nid);
  bb_.moveWall(id, w.a, w.b);
}

void Sampler::enterReversibleWalls() {
  // No wall shorter than wall_min_length (no move makes or keeps one), none sharing space with
  // a live wall of lower id.
  for (int32_t id = 0; id < bb_.wallExtent(); ++id) {
    const WallHyp& w = bb_.wall(id);
    if (!w.alive) continue;
    if (w.length() >= bb_.params().wall_min_length && !sharesSpace(w.a, w.b, id, id)) continue;
    bb_.killWall(id);
    bb_.releaseWall(id);
  }
}

int32_t Sampler::randomLiveWall() {
  return randomLive(bb_.liveWalls(), bb_.wallExtent(), [&](int32_t id) { return bb_.wall(id).alive; });
}

namespace {
// log N(x; 0, sigma) in one dimension.
double logNormal1(double x, double sigma) {
  return -0.5 * (x / sigma) * (x / sigma) - std::log(sigma) - 0.5 * kLog2Pi;
}
}  // namespace

double Sampler::rjWallEndLogDensity(const Vec2& at, const Vec2& fit, const Vec2& dir) const {
  const Vec2 d = at - fit;
  const double al = d.dot(dir), ac = d.x() * dir.y() - d.y() * dir.x();
  const double narrow = opt_.wall_end_sigma, wide = 1.0 / bb_.params().wall_cost_per_m;
  return logAddExp(logNormal1(al, narrow), logNormal1(al, wide)) + std::log(0.5) +
         logNormal1(ac, opt_.prime_sigma_r);
}

Vec2 Sampler::rjWallEnd(const Vec2& fit, const Vec2& dir) {
  const double narrow = opt_.wall_end_sigma, wide = 1.0 / bb_.params().wall_cost_per_m;
  const double al = rng_.normal(0, rng_.uniform() < 0.5 ? narrow : wide);
  return fit + al * dir + rng_.normal(0, opt_.prime_sigma_r) * Vec2{-dir.y(), dir.x()};
}

double Sampler::logWallBirthDensity(const Vec2& a, const Vec2& b) const {
  // log((1/N) sum_f q(a; a_f) q(b; b_f)), summed in log space.
  double acc = -std::numeric_limits<double>::infinity();
  for (const WallFit& f : rj_fits_)
    acc = logAddExp(acc, rjWallEndLogDensity(a, f.a, f.dir) + rjWallEndLogDensity(b, f.b, f.dir));
  return acc - std::log(static_cast<double>(rj_fits_.size()));
}

void Sampler::rjWallBirthDeath(double beta) {
  const double min_len = bb_.params().wall_min_length;
  if (rng_.uniform() < 0.5) {
    // Birth: log q ratio = log(P(death) / n_after) - log(P(birth) q_birth(a, b)) - log cell.
    if (rj_fits_.empty()) return;
    const WallFit& f = rj_fits_[rng_.below(static_cast<uint32_t>(rj_fits_.size()))];
    const Vec2 a = rjWallEnd(f.a, f.dir), b = rjWallEnd(f.b, f.dir);
    // Outside the state space (target 0): shorter than the shortest wall, or sharing space.
    if ((b - a).norm() < min_len || sharesSpace(a, b, kNone)) return;
    const double log_q = logWallBirthDensity(a, b);
    const double n_after = bb_.liveWalls() + 1.0;
    wall_slots_.clear();
    bb_.beginCollect();
    bb_.collectShapeletsNearSegment(a, b, wall_slots_);
    Touched t;
    bb_.touchWallEnds(t, a, b);
    begin();
    const double e0 = bb_.energyBefore(t, wall_slots_);
    const int32_t id = bb_.addWall(a, b);
    t.walls.add(id);
    const double e1 = bb_.energyAfter(t, wall_slots_);
    if (!decideRj(e1 - e0, beta, -std::log(n_after) - log_q - std::log(opt_.rj_wall_cell))) {
      bb_.killWall(id);
      bb_.releaseWall(id);
    }
    return;
  }
  // Death: the negative of the birth's ratio with n_after = n.
  if (rj_fits_.empty() || bb_.liveWalls() == 0) return;  // no birth could restore it
  const double n = bb_.liveWalls();
  const int32_t id = randomLiveWall();
  const WallHyp& w = bb_.wall(id);
  proposeWallDeath(id, beta,
                   std::log(n) + logWallBirthDensity(w.a, w.b) + std::log(opt_.rj_wall_cell));
}

void Sampler::pruneWalls() {
  for (int32_t id = 0; id < bb_.wallExtent(); ++id) {
    const WallHyp& w = bb_.wall(id);
    if (!w.alive) continue;
    wall_slots_.clear();
    bb_.beginCollect();
    bb_.collectShapeletsNearSegment(w.a, w.b, wall_slots_);
    if (!wall_slots_.empty()) continue;
    bb_.killWall(id);
    bb_.releaseWall(id);
  }
}

void Sampler::mapWalls(std::vector<WallHyp>& out) const {
  out.clear();
  for (int32_t id = 0; id < bb_.wallExtent(); ++id)
    if (bb_.wall(id).alive) out.push_back(bb_.wall(id));
}

}  // namespace crunch
