#include "crunch/blackboard/sampler.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>

#include "crunch/core/range_check.h"

namespace crunch {

Status SamplerOptions::validate() const {
  const Status checks[] = {
      checkCount("schedule_steps", schedule_steps, 1, 1000),
      checkCount("sweeps_per_temperature", sweeps_per_temperature, 1, 1000),
      checkRange("schedule_log_top", schedule_log_top, -50.0, 50.0),
      checkRange("schedule_log_step", schedule_log_step, 0.0, 10.0),
      checkRange("r1", r1, 0.0, 1.0),
      checkRange("r2", r2, r1, 1.0),
      checkRange("r3", r3, r2, 1.0),
      checkRange("prime_sigma_r", prime_sigma_r, 0.0, 1.0),
      checkRange("prime_sigma_theta", prime_sigma_theta, 0.0, kPi),
      checkRange("jitter_sigma_r", jitter_sigma_r, 0.0, 1.0),
      checkRange("jitter_sigma_theta", jitter_sigma_theta, 0.0, kPi),
      checkRange("smart_parent_gain", smart_parent_gain, 0.0, 1e6),
      checkRange("rj_moves.leg_birth_death", rj_moves.leg_birth_death, 0.0, 1e6),
      checkRange("rj_moves.leg_jitter", rj_moves.leg_jitter, 0.0, 1e6),
      checkRange("rj_moves.leg_parent", rj_moves.leg_parent, 0.0, 1e6),
      checkRange("rj_moves.leg_table", rj_moves.leg_table, 0.0, 1e6),
      checkRange("rj_moves.table_jitter", rj_moves.table_jitter, 0.0, 1e6),
      checkRange("rj_moves.table_birth_death", rj_moves.table_birth_death, 0.0, 1e6),
      checkRange("rj_moves.table_group", rj_moves.table_group, 0.0, 1e6),
      checkRange("rj_moves.wall_birth_death", rj_moves.wall_birth_death, 0.0, 1e6),
      checkRange("rj_moves.wall_jitter", rj_moves.wall_jitter, 0.0, 1e6),
      checkRange("rj_moves.sizes", rj_moves.sizes, 0.0, 1e6),
      checkAbove("rj_box_margin", rj_box_margin, 0.0, 1.0),
      checkAbove("rj_box_theta", rj_box_theta, 0.0, kPi / 4),
      checkCount("rj_steps_per_shapelet", rj_steps_per_shapelet, 1, 1000),
      checkAbove("rj_cell", rj_cell, 0.0, 1.0),
      checkAbove("rj_wall_cell", rj_wall_cell, 0.0, 1.0),
      checkRange("resize_sigma", resize_sigma, 0.0, 1.0),
      checkRange("leg_side_sigma", leg_side_sigma, 0.0, 1.0),
      checkRange("side_prior_draws", side_prior_draws, 0.0, 1.0),
      checkRange("prime_explained", prime_explained, 0.0, 1.0),
      checkRange("wall_birth_rate", wall_birth_rate, 0.0, 1.0),
      checkRange("wall_grow_gap", wall_grow_gap, 0.0, 10.0),
      checkRange("wall_grow_gap_unseen", wall_grow_gap_unseen, 0.0, 10.0),
      checkRange("wall_jitter_r", wall_jitter_r, 0.0, 10.0),
      checkRange("wall_jitter_theta", wall_jitter_theta, 0.0, kPi),
      checkRange("wall_end_sigma", wall_end_sigma, 0.0, 10.0),
      checkRange("wall_split_gap", wall_split_gap, 0.0, 10.0),
      checkRange("wall_merge_reach", wall_merge_reach, 0.0, 10.0),
      checkRange("wall_join_reach", wall_join_reach, 0.0, 10.0)};
  for (const Status& s : checks) {
    if (!s) return s;
  }
  const ReversibleMoves& m = rj_moves;
  if (m.leg_birth_death + m.leg_jitter + m.leg_parent + m.leg_table + m.table_jitter +
          m.table_birth_death + m.table_group + m.wall_birth_death + m.wall_jitter + m.sizes <=
      0.0)
    return Error{"rj_moves: every weight is 0 (at least one must be positive)"};
  return okStatus();
}

Result<Acceptance> acceptanceByName(const std::string& name) {
  if (name == "paper") return Acceptance::kTempered;
  if (name == "literal") return Acceptance::kLiteral;
  if (name == "rj") return Acceptance::kReversibleJump;
  return Error{"acceptance: unknown acceptance '" + name + "' (expected paper, literal or rj)"};
}

const char* acceptanceName(Acceptance a) {
  switch (a) {
    case Acceptance::kLiteral: return "literal";
    case Acceptance::kReversibleJump: return "rj";
    case Acceptance::kTempered: break;
  }
  return "paper";
}

Sampler::Sampler(Blackboard& board, const SamplerOptions& options, Rng& rng)
    : bb_(board), opt_(options), rng_(rng) {
  bb_.setIncremental(opt_.incremental_energy);
  for (int i = opt_.schedule_steps - 1; i >= 0; --i)
    betas_.push_back(std::exp(opt_.schedule_log_top - opt_.schedule_log_step * i));
  order_.reserve(4096);
  rj_slots_.reserve(static_cast<size_t>(bb_.workingMemoryCapacity()));
  if (walls()) {
    if (rj()) rj_fits_.reserve(static_cast<size_t>(bb_.workingMemoryCapacity()));
    wall_slots_.reserve(static_cast<size_t>(bb_.workingMemoryCapacity()));
    fit_memo_.resize(static_cast<size_t>(bb_.workingMemoryCapacity()));
  }
}

void Sampler::anneal() {
  const int n = annealSweeps();
  for (int k = 0; k < n; ++k) annealSweep(k);
}

void Sampler::annealSweep(int k) {
  assert(k >= 0 && k < annealSweeps());
  if (k == 0 && rj()) enterReversibleSpace();
  const int step = k / opt_.sweeps_per_temperature;
  const int s = k % opt_.sweeps_per_temperature;
  const double beta = betas_[static_cast<std::size_t>(step)];
  sweep(beta);
  if (opt_.after_sweep) opt_.after_sweep(step, s, beta, bb_);
  if (s + 1 == opt_.sweeps_per_temperature) {
    if (opt_.prune && !rj()) prune();
    if (opt_.after_temperature) opt_.after_temperature(step, beta, bb_);
  }
}

namespace {
// The board is in a sweep (Blackboard::beginSweep) while this lives.
struct SweepScope {
  explicit SweepScope(Blackboard& b) : bb(b) { bb.beginSweep(); }
  ~SweepScope() { bb.endSweep(); }
  SweepScope(const SweepScope&) = delete;
  SweepScope& operator=(const SweepScope&) = delete;
  Blackboard& bb;
};

// A born table's legs against its corners, for fitRigid: the proposer's pair first, then each
// adopted leg's (the corner's offset in the table's frame, the leg's centre).
struct CornerPairs {
  std::array<Vec2, 5> local, at;
  int n = 0;
  void add(const Vec2& corner, const Vec2& centre) {
    local[static_cast<size_t>(n)] = corner;
    at[static_cast<size_t>(n++)] = centre;
  }
  // The table's pose that fits its corners to its legs in least squares, theta modulo pi.
  Pose2 fit(double theta) const {
    const Pose2 f = fitRigid(local.data(), at.data(), n, theta);
    return {f.x, f.y, wrapPeriod(f.theta, kPi)};
  }
};

// The adoption of both table births: every live leg but `self` within r of `corner` joins
// `adopt` (as many as it holds) and, if it joined, is paired in `pairs` with the corner's offset
// in the table's frame, `local()` (evaluated only then).
template <typename Local>
void adoptAt(const Blackboard& bb, const Vec2& corner, Local&& local, double r, int32_t self,
             IdSet<4>& adopt, CornerPairs& pairs) {
  bb.legsNear(corner, r, [&](int32_t o) {
    const LegHyp& ol = bb.leg(o);
    if (o == self || !ol.alive || (ol.pose.position() - corner).squaredNorm() > r * r) return;
    const int before = adopt.n;
    adopt.add(o);
    if (adopt.n > before) pairs.add(local(), ol.pose.position());
  });
}
}  // namespace

void Sampler::sweep(double beta) {
  const SweepScope scope(bb_);
  if (rj()) {
    sweepReversible(beta);
    return;
  }
  move_ = MoveKind::kPrime;
  for (int slot = 0; slot < bb_.workingMemoryCapacity(); ++slot)
    if (bb_.slotUsed(slot) && primed(slot)) primeLeg(slot, beta);
  if (walls()) {
    move_ = MoveKind::kWallBirth;
    for (int slot = 0; slot < bb_.workingMemoryCapacity(); ++slot)
      if (bb_.slotUsed(slot)) proposeWallBirth(slot, beta);
  }

  order_.clear();
  for (int32_t id = 0; id < bb_.tableExtent(); ++id)
    if (bb_.table(id).alive) order_.push_back({true, id});
  for (int32_t id = 0; id < bb_.legExtent(); ++id)
    if (bb_.leg(id).alive) order_.push_back({false, id});
  if (walls())
    for (int32_t id = 0; id < bb_.wallExtent(); ++id)
      if (bb_.wall(id).alive) order_.push_back({false, id, true});

  const bool sized = bb_.params().sized();
  for (const Ref& h : order_) {
    if (h.is_wall) {
      move_ = MoveKind::kWall;
      if (bb_.wall(h.id).alive) wallMove(h.id, beta);
      continue;
    }
    const double r = rng_.uniform();
    if (h.is_table) {
      if (!bb_.table(h.id).alive) continue;
      if (r < opt_.r1) {
        move_ = MoveKind::kTableDeath;
        if (walls() && rng_.uniform() < 0.5) deathTableWithLegs(h.id, beta);
        else deathTable(h.id, beta);
      } else if (r < opt_.r3 && r >= opt_.r2) {
        move_ = MoveKind::kChild;
        proposeChild(h.id, beta);
      } else if (!sized) {
        move_ = MoveKind::kTablePose;
        jitterTable(h.id, beta);  // tables have only the null parent
      } else {
        // The rooms model shares the pose-move slot among pose, size and leg side.
        const double u = rng_.uniform();
        move_ = u < 0.4 ? MoveKind::kTablePose : MoveKind::kTableSize;
        if (u < 0.4) jitterTable(h.id, beta);
        else if (u < 0.85) resizeTable(h.id, beta);
        else tableLegSide(h.id, beta);
        // and, where an orphan leg stands on its long side, a split there.
        move_ = MoveKind::kTableSize;
        if (opt_.split_tables && bb_.table(h.id).alive) splitTable(h.id, beta);
      }
    } else {
      if (!bb_.leg(h.id).alive) continue;
      if (r < opt_.r1) {
        move_ = MoveKind::kLegDeath;
        deathLeg(h.id, beta);
      } else if (r < opt_.r2) {
        move_ = MoveKind::kParentChange;
        parentChange(h.id, beta);
      } else if (r < opt_.r3) {  // a leg's children are observations
        move_ = MoveKind::kLegPose;
        if (sized && rng_.uniform() < 0.3) legSide(h.id, beta);
        else jitterLeg(h.id, beta);
      } else if (sized) {
        move_ = MoveKind::kParentBirth;
        // With a catalog, half the time also a birth of its size: the walls model's, its 8
        // placements of the one size weighed by the legs at their corners.
        proposeParentSized(h.id, beta);
        if (bb_.params().catalog_weight > 0.0 && bb_.leg(h.id).alive && rng_.uniform() < 0.5)
          proposeParent(h.id, beta);
      } else {
        move_ = MoveKind::kParentBirth;
        proposeParent(h.id, beta);
      }
    }
  }
}

bool Sampler::primed(int slot) {
  // A shapelet that a live cause explains at least as well as clutter does (its background's
  // responsibility <= 1/2) is primed at prime_explained: a leg born there would mostly duplicate
  // the cause and be refused (docs/BENCHMARKS.md "The move mix"). 1 draws nothing: the paper's.
  if (opt_.prime_explained >= 1.0) return true;
  if (bb_.shapeletExplanation(slot) < std::log(2.0)) return true;
  return rng_.uniform() < opt_.prime_explained;
}

void Sampler::accepted(bool ok) {
  stats_.accepted += ok;
  stats_.by_move[static_cast<size_t>(move_)].accepted += ok;
  if (!ok) return;
  bb_.acceptMove();
  if (audit_) stats_.audit_cache_max_error = std::max(stats_.audit_cache_max_error, bb_.cacheError());
}

void Sampler::begin() {
  if (audit_) audit_before_ = bb_.totalEnergy();
}

bool Sampler::decide(double delta, double beta) {
  // Under kReversibleJump the sweep calls decide() only from symmetric proposals (jitterWall,
  // extendWall): Metropolis-Hastings with a log q ratio of 0.
  if (rj()) return decideRj(delta, beta, 0.0);
  if (audit_ && std::isfinite(delta)) {  // -infinity: refused by a constraint, nothing to audit
    const double err = std::abs((bb_.totalEnergy() - audit_before_) - delta);
    stats_.audit_max_error = std::max(stats_.audit_max_error, err);
  }
  ++stats_.proposals;
  ++stats_.by_move[static_cast<size_t>(move_)].proposals;
  const double a = opt_.acceptance == Acceptance::kTempered ? temperedAcceptance(delta, beta)
                                                            : literalAcceptance(delta, beta);
  const bool ok = rng_.uniform() < a;
  accepted(ok);
  return ok;
}

int32_t Sampler::sampleParent(const LegHyp& leg, int32_t exclude) {
  std::array<int32_t, 16> cand;
  std::array<double, 16> weight;
  const int n = parentCandidates(leg, exclude, cand, weight);
  double total = 0.0;
  for (int i = 0; i < n; ++i) total += weight[i];
  if (total <= 0.0) return exclude;
  double u = rng_.uniform() * total;
  for (int i = 0; i < n; ++i) {
    if ((u -= weight[i]) < 0.0) return cand[i];
  }
  return cand[n - 1];
}

int Sampler::parentCandidates(const LegHyp& leg, int32_t exclude, std::array<int32_t, 16>& cand,
                              std::array<double, 16>& weight) const {
  const ModelParams& p = bb_.params();
  constexpr int kMaxCand = 16;
  int n = 0;
  cand[n] = kNone;
  weight[n++] = exclude == kNone ? 0.0 : p.c_L;
  const double reach =
      (p.sized() ? p.maxTableCircumradius() : bb_.tableRect(Pose2{}).circumradius()) +
      p.cornerLinkRadius();
  const double cut = p.link_sigmas * p.link_sigmas;
  bb_.tablesNear(leg.pose.position(), reach, [&](int32_t t) {
    const TableHyp& tab = bb_.table(t);
    if (t == exclude || !tab.alive || n >= kMaxCand || tab.n_children >= kMaxChildren) return;
    const double d = deltaTLHeld(tab, leg, p, nullptr);
    if (d > cut) return;
    cand[n] = t;
    weight[n++] = p.alpha_L * std::exp(-d);
  });
  return n;
}

namespace {
// The inward normal of shapelet s: perpendicular to its surface, pointing away from the whisker
// that touched it (into the object).
Vec2 inwardNormal(const Shapelet& s) {
  const Vec2 n{-std::sin(s.phi), std::cos(s.phi)};
  return n.dot(Vec2{s.ox - s.x, s.oy - s.y}) > 0 ? Vec2(-n) : n;
}
}  // namespace

void Sampler::primeLeg(int slot, double beta) {
  const Shapelet& s = bb_.shapelet(slot);
  const ModelParams& p = bb_.params();
  if (!legCanCause(p.maxLegSide(), s)) return;  // no leg's face is that long
  // The rooms model's legs are born with the standard side (or the least side that holds the
  // contact's face span), so legs of one object agree and a table over them pays; side moves
  // (legSide, tableLegSide) refine it. A side drawn from the prior's range instead places each
  // leg's centre for a different side, and eq. 10's leg-width term keeps their table from paying.
  const double side =
      p.sized() ? std::clamp(std::max(p.leg_side, s.face_span / std::sqrt(2.0)), p.leg_min, p.leg_max)
                : p.leg_side;
  LegHyp probe;
  probe.pose = s.oriented ? legOnFace(s, side) : legAtPoint(s, side);
  probe.side = side;
  const int32_t parent = sampleParent(probe, kNone);
  proposeLegBirth(probe.pose, side, parent, beta);
}

Pose2 Sampler::legOnFace(const Shapelet& s, double side) {
  const double half = 0.5 * side;
  const Vec2 along{std::cos(s.phi), std::sin(s.phi)};
  const Vec2 in = inwardNormal(s);
  // Q(pa(S)): a leg whose face passes through the shapelet. Where another shapelet nearby lies on
  // a perpendicular face, place the leg touching both (a corner fit); otherwise anywhere along
  // the face.
  int partner = -1;
  if (opt_.smart_parent) {
    ShapeletSet near;
    bb_.shapeletsNear({s.x, s.y}, near);
    const double reach2 = 4.0 * side * side;  // (2 side)^2: squared distances, no hypot
    for (int32_t o : near.span()) {
      const Shapelet& so = bb_.shapelet(o);
      if (!so.oriented || (Vec2{so.x - s.x, so.y - s.y}).squaredNorm() > reach2) continue;
      if (std::abs(wrapPeriod(so.phi - s.phi, kPi)) < kPi / 4) continue;
      if (partner < 0 || rng_.uniform() < 0.5) partner = o;
    }
  }
  Vec2 c;
  if (partner >= 0) {
    // Intersect the two faces' centre lines: c = s + half*in + a*along with
    // (c - s2).in2 = half.
    const Shapelet& s2 = bb_.shapelet(partner);
    const Vec2 in2 = inwardNormal(s2);
    const Vec2 base = Vec2{s.x, s.y} + half * in;
    const double denom = along.dot(in2);
    const double a = (half - (base - Vec2{s2.x, s2.y}).dot(in2)) / denom;
    c = base + std::clamp(a, -half, half) * along;
  } else {
    c = Vec2{s.x, s.y} + half * in + rng_.uniform(-half, half) * along;
  }
  c += Vec2{rng_.normal(0, opt_.prime_sigma_r), rng_.normal(0, opt_.prime_sigma_r)};
  return {c.x(), c.y(), wrapPeriod(s.phi + rng_.normal(0, opt_.prime_sigma_theta), kPi / 2)};
}

Pose2 Sampler::legAtPoint(const Shapelet& s, double side) {
  // An edge or point contact (no orientation): the leg lies beyond the point as seen from the
  // whisker, its centre between a face's and a corner's distance from it, turned as the legs
  // already believed around it say (axisFromLegs), or any way.
  const double half = 0.5 * side;
  Vec2 away = Vec2{s.x - s.ox, s.y - s.oy};
  away = away.norm() > 0.0 ? Vec2(away.normalized()) : Vec2{1.0, 0.0};
  if (!bb_.hasFreeSpace()) {
    const Vec2 c = Vec2{s.x, s.y} + rng_.uniform(half, half * std::sqrt(2.0)) * away +
                   Vec2{rng_.normal(0, opt_.prime_sigma_r), rng_.normal(0, opt_.prime_sigma_r)};
    const double theta = axisFromLegs(c, -1, rng_.uniform(0.0, kPi / 2)) +
                         rng_.normal(0, opt_.prime_sigma_theta);
    return {c.x(), c.y(), wrapPeriod(theta, kPi / 2)};
  }
  const double theta = wrapPeriod(axisFromLegs({s.x, s.y}, -1, rng_.uniform(0.0, kPi / 2)) +
                                      rng_.normal(0, opt_.prime_sigma_theta),
                                  kPi / 2);
  const Vec2 jitter{rng_.normal(0, opt_.prime_sigma_r), rng_.normal(0, opt_.prime_sigma_r)};
  const double reach = rng_.uniform(half, half * std::sqrt(2.0));
  // With negative evidence, where the leg stands around the point is seen: the whisker that
  // touched it swept up to it, so the straight continuation of its shaft past a shaft contact
  // is often swept, and the leg is to the side the whisker turned towards. Its centre lies
  // anywhere within 90 degrees of `away` (the touched outline faces the whisker): kPointSides
  // directions across that half-plane, each weighted by what a leg there pays for the free
  // passes through its core (Blackboard::freeTerm, the factor the acceptance then weighs):
  // a proposal from the leg's conditional given its free space, not a guess the negative
  // evidence kills at once (issue 12: on the robot's two-table run no leg on a single point
  // contact survived a global chain).
  std::array<Vec2, kPointSides> centre;
  std::array<double, kPointSides> log_w;
  for (int k = 0; k < kPointSides; ++k) {
    const double turn = kPi * ((k + 0.5) / kPointSides - 0.5);
    const Vec2 dir{away.x() * std::cos(turn) - away.y() * std::sin(turn),
                   away.x() * std::sin(turn) + away.y() * std::cos(turn)};
    const Vec2 c = Vec2{s.x, s.y} + reach * dir;
    centre[static_cast<size_t>(k)] = c;
    log_w[static_cast<size_t>(k)] = bb_.freeTerm({c.x(), c.y(), theta}, side);
  }
  const Vec2 c = centre[drawLogWeighted(log_w, rng_)] + jitter;
  return {c.x(), c.y(), theta};
}

template <class F>
void Sampler::partnersNear(const Vec2& c, int32_t self, F&& f) const {
  bb_.legsNear(c, reach(), [&](int32_t o) {
    const LegHyp& l = bb_.leg(o);
    if (o != self && l.alive) f(l.pose.position());
  });
  if (bb_.pointShapeletCount() == 0) return;  // only point contacts are partners
  bb_.shapeletsWithin(c, reach(), [&](int32_t slot) {
    const Shapelet& sh = bb_.shapelet(slot);
    if (!sh.oriented) f(Vec2{sh.x, sh.y});
  });
}

double Sampler::axisFromLegs(const Vec2& c, int32_t self, double fallback) {
  // Another leg, or a point contact, at a table side's or diagonal's distance from c gives the
  // table's axes (modulo pi/2) as a table would hold both. Point contacts count as well as legs:
  // they are there before their legs are.
  const ModelParams& p = bb_.params();
  if (p.sized()) return axisFromPartners(c, self, fallback);
  // The paper's one size: each partner at a side's or the diagonal's length is equally likely
  // to be chosen.
  const double w = p.table_width - p.leg_side, d = p.table_depth - p.leg_side;
  const double diag = std::hypot(w, d), diag_angle = std::atan2(d, w);
  const double tol = 2.0 * p.leg_side;
  double axis = fallback;
  int seen = 0;
  const auto consider = [&](const Vec2& other) {
    const Vec2 v = other - c;
    const double len = v.norm(), dir = std::atan2(v.y(), v.x());
    double a;
    if (std::abs(len - w) < tol || std::abs(len - d) < tol) a = dir;
    else if (std::abs(len - diag) < tol) a = dir + (rng_.uniform() < 0.5 ? -diag_angle : diag_angle);
    else return;
    if (rng_.uniform() * ++seen < 1.0) axis = a;
  };
  partnersNear(c, self, consider);
  return axis;
}

double Sampler::reach() const {
  const ModelParams& p = bb_.params();
  if (p.sized()) return std::hypot(p.size_max_long, p.size_max_short);
  return std::hypot(p.table_width - p.leg_side, p.table_depth - p.leg_side) + 2.0 * p.leg_side;
}

double Sampler::axisFromPartners(const Vec2& c, int32_t self, double fallback) {
  // The rooms model knows no one size: a partner q at any distance a side of the prior's range
  // can span is taken as lying along a side, axis (q - c). Three corners of a rectangle fix it,
  // so a partner is weighted as proposeParentSized weights its rectangles: 1, plus
  // smart_parent_gain if another partner stands where the side from c perpendicular to (q - c)
  // ends, plus smart_parent_gain if one stands at the corner diagonal to c. A partner that is
  // the far end of a diagonal, or a leg of another object, then rarely sets the axis, where
  // drawn uniformly it set it as often as the partners that span the table's sides (a room's
  // walls and other tables give many such partners: issue 12's two-table room).
  const ModelParams& p = bb_.params();
  const double tol_end = 2.0 * p.leg_side;
  const double side_lo = p.size_min_side - p.leg_max - tol_end;
  const double span_lo = p.size_min_side - p.leg_max, span_hi = p.size_max_long;
  const double tol = p.cornerLinkRadius() * 0.5 + 0.5 * p.maxLegSide();  // as proposeParentSized
  std::array<Vec2, kMaxPartners>& q = partners_;
  int n = 0, seen = 0;
  const auto keep = [&](const Vec2& other) {
    const double len = (other - c).norm();
    if (len < side_lo || len > p.size_max_long) return;
    // More than kMaxPartners: a uniform sample of them (reservoir).
    if (n < kMaxPartners) {
      q[static_cast<size_t>(n++)] = other;
    } else {
      const int k = static_cast<int>(rng_.uniform() * (seen + 1));
      if (k < kMaxPartners) q[static_cast<size_t>(k)] = other;
    }
    ++seen;
  };
  partnersNear(c, self, keep);
  if (n == 0) return fallback;
  const double gain = opt_.smart_parent ? opt_.smart_parent_gain : 0.0;
  std::array<double, kMaxPartners>& weight = partner_weights_;
  double total = 0.0;
  for (int i = 0; i < n; ++i) {
    const Vec2 a = q[static_cast<size_t>(i)] - c;
    const double span = a.norm();
    const Vec2 u = a / span, v{-u.y(), u.x()};
    bool side = false, diagonal = false;
    for (int j = 0; j < n && gain > 0.0 && !(side && diagonal); ++j) {
      if (j == i) continue;
      const Vec2 b = q[static_cast<size_t>(j)] - c;
      const double along = b.dot(u), across = std::abs(b.dot(v));
      if (across < span_lo || across > span_hi) continue;
      if (std::abs(along) < tol) side = true;
      else if (std::abs(along - span) < tol) diagonal = true;
    }
    weight[static_cast<size_t>(i)] = 1.0 + (side ? gain : 0.0) + (diagonal ? gain : 0.0);
    total += weight[static_cast<size_t>(i)];
  }
  double pick = rng_.uniform() * total;
  int k = 0;
  while (k < n - 1 && (pick -= weight[static_cast<size_t>(k)]) >= 0.0) ++k;
  const Vec2 a = q[static_cast<size_t>(k)] - c;
  return std::atan2(a.y(), a.x());
}

bool Sampler::pointNear(const Vec2& c, double radius) const {
  bool found = false;
  bb_.shapeletsWithin(c, radius, [&](int32_t slot) {
    const Shapelet& sh = bb_.shapelet(slot);
    if (!sh.oriented && (Vec2{sh.x, sh.y} - c).squaredNorm() <= radius * radius) found = true;
  });
  return found;
}

bool Sampler::pointSupported(const Vec2& c) const {
  // Shapelets within the link radius of c (shapeletsNear), none of them oriented: a leg that only point contacts support, whose
  // orientation nothing but its table constrains.
  ShapeletSet near;
  bb_.shapeletsNear(c, near);
  bool any = false;
  for (int32_t o : near.span()) {
    if (bb_.shapelet(o).oriented) return false;
    any = true;
  }
  return any;
}

void Sampler::proposeLegBirth(const Pose2& pose, double side, int32_t parent, double beta) {
  Touched t;
  t.tables.add(parent);
  bb_.shapeletsNear(pose.position(), t.shapelets);
  begin();
  const double e0 = bb_.energyBefore(t);
  const int32_t id = bb_.addLeg(pose, side, parent);
  t.legs.add(id);
  const double e1 = bb_.energyAfterBirth(t, id);
  if (!decide(e1 - e0, beta)) {
    bb_.killLeg(id);
    bb_.releaseLeg(id);
  }
}

void Sampler::deathLeg(int32_t id, double beta) {
  Touched t;
  t.legs.add(id);
  t.tables.add(bb_.leg(id).parent);
  bb_.shapeletsNear(bb_.leg(id).pose.position(), t.shapelets);
  begin();
  const double e0 = bb_.energyBefore(t);
  bb_.killLeg(id);
  const double e1 = bb_.energyAfter(t);
  if (decide(e1 - e0, beta)) bb_.releaseLeg(id);
  else bb_.reviveLeg(id);
}

void Sampler::deathTable(int32_t id, double beta) {
  Touched t;
  t.tables.add(id);
  const TableHyp& tab = bb_.table(id);
  for (int i = 0; i < tab.n_children; ++i) t.legs.add(tab.children[i]);
  begin();
  const double e0 = bb_.energyBefore(t);
  bb_.killTable(id);
  const double e1 = bb_.energyAfter(t);
  if (decide(e1 - e0, beta)) bb_.releaseTable(id);
  else bb_.reviveTable(id);
}

void Sampler::deathTableWithLegs(int32_t id, double beta) {
  // A table alone dies leaving its legs orphans, each then paying its null prior (and a leg at a
  // corner no contact supports explains nothing); its legs alone die one by one while the table
  // pays eps_a for each corner emptied. Either first step is uphill where the whole object is
  // not worth its evidence: a table on a wall's noisy contacts, its far legs out where nothing
  // was sensed (docs/BLACKBOARD.md "Noisy walls"). This move crosses that valley in one step.
  proposeDeathWithLegs(id, beta, 0.0);
}

void Sampler::proposeDeathWithLegs(int32_t id, double beta, double log_q_ratio) {
  Touched t;
  t.tables.add(id);
  const TableHyp& tab = bb_.table(id);
  const int n = tab.n_children;
  std::array<int32_t, kMaxChildren> kids;
  for (int i = 0; i < n; ++i) {
    kids[static_cast<size_t>(i)] = tab.children[i];
    t.legs.add(tab.children[i]);
    bb_.shapeletsNear(bb_.leg(tab.children[i]).pose.position(), t.shapelets);
  }
  // A full set may have dropped a shapelet the move changes: not proposed.
  if (t.shapelets.n >= static_cast<int>(std::size(t.shapelets.ids))) return;
  begin();
  const double e0 = bb_.energyBefore(t);
  for (int i = 0; i < n; ++i) bb_.killLeg(kids[static_cast<size_t>(i)]);
  bb_.killTable(id);
  const double e1 = bb_.energyAfter(t);
  const bool ok = rj() ? decideRj(e1 - e0, beta, log_q_ratio) : decide(e1 - e0, beta);
  if (ok) {
    bb_.releaseTable(id);
    for (int i = 0; i < n; ++i) bb_.releaseLeg(kids[static_cast<size_t>(i)]);
    return;
  }
  bb_.reviveTable(id);
  for (int i = 0; i < n; ++i) bb_.reviveLeg(kids[static_cast<size_t>(i)]);
}

void Sampler::parentChange(int32_t leg, double beta) {
  const int32_t old_parent = bb_.leg(leg).parent;
  const int32_t new_parent = sampleParent(bb_.leg(leg), old_parent);
  if (new_parent == old_parent) return;
  Touched t;
  t.legs.add(leg);
  t.tables.add(old_parent);
  t.tables.add(new_parent);
  begin();
  const double e0 = bb_.energyBefore(t);
  bb_.setParent(leg, new_parent);
  const double e1 = bb_.energyAfter(t);
  if (!decide(e1 - e0, beta)) bb_.setParent(leg, old_parent);
}

Pose2 Sampler::jittered(const Pose2& p, double period) {
  const double x = p.x + rng_.normal(0, opt_.jitter_sigma_r);
  const double y = p.y + rng_.normal(0, opt_.jitter_sigma_r);
  return {x, y, wrapPeriod(p.theta + rng_.normal(0, opt_.jitter_sigma_theta), period)};
}

void Sampler::jitterLeg(int32_t id, double beta) {
  const Pose2 old = bb_.leg(id).pose;
  const Pose2 moved = jittered(old, kPi / 2);
  Touched t;
  t.legs.add(id);
  t.tables.add(bb_.leg(id).parent);
  bb_.shapeletsNear(old.position(), t.shapelets);
  bb_.shapeletsNear(moved.position(), t.shapelets);
  begin();
  const double e0 = bb_.energyBefore(t);
  bb_.moveLeg(id, moved);
  const double e1 = bb_.energyAfter(t);
  if (!decide(e1 - e0, beta)) bb_.moveLeg(id, old);
}

void Sampler::jitterTable(int32_t id, double beta) {
  const Pose2 old = bb_.table(id).pose;
  const Pose2 moved = jittered(old, kPi);
  // Half the moves carry the children along rigidly: a table and its legs are tightly coupled
  // (sigma_r_leg), so moving either alone barely moves the pair at low temperature.
  const bool rigid = rng_.uniform() < 0.5;
  Touched t;
  t.tables.add(id);
  const TableHyp& tab = bb_.table(id);
  const int n = tab.n_children;
  std::array<int32_t, kMaxChildren> kids;
  std::array<Pose2, kMaxChildren> kid_old;
  for (int i = 0; i < n; ++i) {
    kids[static_cast<size_t>(i)] = tab.children[i];
    kid_old[static_cast<size_t>(i)] = bb_.leg(tab.children[i]).pose;
    t.legs.add(tab.children[i]);
  }
  auto carried = [&](const Pose2& leg) {
    const Vec2 w = moved.toWorld(old.toLocal(leg.position()));
    return Pose2{w.x(), w.y(), wrapPeriod(leg.theta + moved.theta - old.theta, kPi / 2)};
  };
  if (rigid) {
    for (int i = 0; i < n; ++i) {
      bb_.shapeletsNear(kid_old[static_cast<size_t>(i)].position(), t.shapelets);
      bb_.shapeletsNear(carried(kid_old[static_cast<size_t>(i)]).position(), t.shapelets);
    }
  }
  begin();
  const double e0 = bb_.energyBefore(t);
  bb_.moveTable(id, moved);
  if (rigid)
    for (int i = 0; i < n; ++i)
      bb_.moveLeg(kids[static_cast<size_t>(i)], carried(kid_old[static_cast<size_t>(i)]));
  const double e1 = bb_.energyAfter(t);
  if (!decide(e1 - e0, beta)) {
    if (rigid)
      for (int i = 0; i < n; ++i)
        bb_.moveLeg(kids[static_cast<size_t>(i)], kid_old[static_cast<size_t>(i)]);
    bb_.moveTable(id, old);
  }
}

void Sampler::proposeChild(int32_t table, double beta) {
  const TableHyp& tab = bb_.table(table);
  if (tab.n_children >= kMaxChildren) return;
  std::array<int, 4> missing;
  int n = 0;
  for (int c = 0; c < 4; ++c)
    if (tab.corner_count[static_cast<size_t>(c)] == 0) missing[static_cast<size_t>(n++)] = c;
  if (n == 0) return;
  const int corner = missing[rng_.below(static_cast<uint32_t>(n))];
  const Vec2 c = tab.corner(corner);
  proposeLegBirth({c.x(), c.y(), wrapPeriod(tab.pose.theta, kPi / 2)}, tab.leg, table, beta);
}

void Sampler::proposeParent(int32_t leg, double beta) {
  const ModelParams& p = bb_.params();
  const LegHyp l = bb_.leg(leg);
  // A leg only point contacts support has no orientation of its own: the table's axes come from
  // the legs at a side's or diagonal's distance, and the legs so supported that the table takes
  // turn with it (below).
  const bool free_turn = opt_.smart_parent && pointSupported(l.pose.position());
  // With walls in the model (and the fit below), half the time the axes come from the partners
  // even when oriented shapelets support the leg, as proposeParentSized takes them: a leg's
  // orientation comes from its few shapelets and scatters with their angle noise (pi/8 in the
  // paper's "very noisy" regime: 0.3 rad puts a 0.8 m table's far corner 25 cm from its leg),
  // the line between two legs by the legs' position errors over their span (~0.03 rad).
  const bool from_partners =
      free_turn || (opt_.smart_parent && opt_.fit_parent && walls() && rng_.uniform() < 0.5);
  const double axis =
      from_partners ? axisFromLegs(l.pose.position(), leg, l.pose.theta) : l.pose.theta;
  // The 8 table placements with this leg at a corner: 2 orientations (modulo pi) x 4 corners.
  std::array<Pose2, 8> place;
  std::array<double, 8> weight;
  double total = 0.0;
  const double link_r = p.cornerLinkRadius(), link_r2 = std::pow(link_r, 2);
  std::array<double, 2> cos_th, sin_th;  // the two orientations' cos/sin, once each
  for (int k = 0; k < 8; ++k) {
    const double th = wrapPeriod(axis + (k / 4) * (kPi / 2), kPi);
    if (k % 4 == 0) {
      cos_th[static_cast<size_t>(k / 4)] = std::cos(th);
      sin_th[static_cast<size_t>(k / 4)] = std::sin(th);
    }
    const double c_th = cos_th[static_cast<size_t>(k / 4)], s_th = sin_th[static_cast<size_t>(k / 4)];
    const Pose2 frame{0, 0, th};
    const Vec2 off = frame.toWorld(p.cornerOffset(k % 4), c_th, s_th);
    place[static_cast<size_t>(k)] = {l.pose.x - off.x(), l.pose.y - off.y(), th};
    double w = 1.0;
    if (opt_.smart_parent) {
      for (int c = 0; c < 4; ++c) {
        if (c == k % 4) continue;
        const Vec2 corner = place[static_cast<size_t>(k)].toWorld(p.cornerOffset(c), c_th, s_th);
        bb_.legsNear(corner, link_r, [&](int32_t o) {
          const LegHyp& ol = bb_.leg(o);
          if (o != leg && ol.alive && (ol.pose.position() - corner).squaredNorm() <= link_r2)
            w += opt_.smart_parent_gain;
        });
        // A point contact on a leg at that corner (within a leg's half-diagonal of it) counts
        // as that leg would: it is the evidence a leg there will explain.
        if (free_turn && pointNear(corner, link_r)) w += opt_.smart_parent_gain;
      }
    }
    weight[static_cast<size_t>(k)] = w;
    total += w;
  }
  double u = rng_.uniform() * total;
  int k = 0;
  while (k < 7 && (u -= weight[static_cast<size_t>(k)]) >= 0.0) ++k;
  Pose2 pose = place[static_cast<size_t>(k)];

  // Legs already at the other corners join the new table in the same move, taken from their
  // old table if they had one; an old table left without legs dies in the same move. This is the
  // jump between the rival tables T1 and T2 of Fig. 5, which single-hypothesis moves can only
  // make through a deep valley of two overlapping tables.
  IdSet<4> adopt;
  CornerPairs pairs;
  pairs.add(p.cornerOffset(k % 4), l.pose.position());
  if (opt_.smart_parent) {
    for (int c = 0; c < 4; ++c) {
      const Vec2 corner =
          pose.toWorld(p.cornerOffset(c), cos_th[static_cast<size_t>(k / 4)], sin_th[static_cast<size_t>(k / 4)]);
      adoptAt(bb_, corner, [&] { return p.cornerOffset(c); }, link_r, leg, adopt, pairs);
    }
  }
  // With legs at two or more corners the table goes where its corners fit them best (eq. 10's
  // position term is a squared distance: the least-squares rigid fit is the table's most
  // probable pose given its legs), not where the proposer's own corner and orientation put it:
  // a leg's orientation comes from its few shapelets' and is the noisier. Not under the paper's
  // model (no walls): there the fit mostly builds tables on the legs of wall contacts
  // (docs/BLACKBOARD.md "Tables fitted to their legs"), and its figures stay the paper's.
  const bool fitted = opt_.fit_parent && walls() && adopt.n > 0;
  if (fitted) pose = pairs.fit(pose.theta);
  std::array<int32_t, 4> adopt_parent;
  Touched t;
  t.legs.add(leg);
  t.tables.add(l.parent);
  for (int i = 0; i < adopt.n; ++i) {
    adopt_parent[static_cast<size_t>(i)] = bb_.leg(adopt.ids[i]).parent;
    t.legs.add(adopt.ids[i]);
    t.tables.add(adopt_parent[static_cast<size_t>(i)]);
  }
  // Every child of a touched table is touched too: a table that dies orphans them.
  for (int32_t tab : t.tables.span())
    for (int i = 0; i < bb_.table(tab).n_children; ++i) t.legs.add(bb_.table(tab).children[i]);
  // A fitted table turns its legs to its axes (below): their shapelets' terms change too.
  if (fitted) {
    bb_.shapeletsNear(l.pose.position(), t.shapelets);
    for (int32_t o : adopt.span()) bb_.shapeletsNear(bb_.leg(o).pose.position(), t.shapelets);
  }
  begin();
  const double e0 = bb_.energyBefore(t);
  const int32_t table = bb_.addTable(pose);
  bb_.setParent(leg, table);
  for (int32_t o : adopt.span()) bb_.setParent(o, table);
  const Turn turn = fitted ? Turn::kAll : free_turn ? Turn::kPointSupported : Turn::kNoLeg;
  if (decideNewTable(table, pose, turn, t, e0, beta))
    return;
  bb_.setParent(leg, l.parent);
  for (int i = 0; i < adopt.n; ++i) bb_.setParent(adopt.ids[i], adopt_parent[static_cast<size_t>(i)]);
  bb_.killTable(table);
  bb_.releaseTable(table);
}

bool Sampler::decideNewTable(int32_t table, const Pose2& pose, Turn turn, Touched& t,
                             double e0, double beta) {
  // Legs whose orientation nothing but their table constrains (or, Turn::kAll, every child)
  // turn with it.
  IdSet<5> turned;
  std::array<Pose2, 5> turned_from;
  if (turn != Turn::kNoLeg) {
    for (int32_t o : t.legs.span()) {
      if (bb_.leg(o).parent != table) continue;
      if (turn == Turn::kPointSupported && !pointSupported(bb_.leg(o).pose.position())) continue;
      turned_from[static_cast<size_t>(turned.n)] = bb_.leg(o).pose;
      turned.add(o);
      Pose2 q = bb_.leg(o).pose;
      q.theta = wrapPeriod(pose.theta, kPi / 2);
      bb_.moveLeg(o, q);
    }
  }
  IdSet<8> emptied;
  killEmptied(t.tables, emptied);
  t.tables.add(table);
  const double e1 = bb_.energyAfter(t);
  if (decide(e1 - e0, beta)) {
    for (int32_t tab : emptied.span()) bb_.releaseTable(tab);
    return true;
  }
  for (int i = 0; i < turned.n; ++i) bb_.moveLeg(turned.ids[i], turned_from[static_cast<size_t>(i)]);
  for (int32_t tab : emptied.span()) bb_.reviveTable(tab);
  return false;
}

void Sampler::killEmptied(const IdSet<8>& tables, IdSet<8>& emptied) {
  for (int32_t tab : tables.span()) {
    if (bb_.table(tab).n_children > 0) continue;
    emptied.add(tab);
    bb_.killTable(tab);
  }
}

bool Sampler::legDirectlyLinked(int32_t leg) const {
  ShapeletSet near;
  bb_.shapeletsNear(bb_.leg(leg).pose.position(), near);
  return near.n > 0;
}

void Sampler::prune() {
  if (walls()) pruneWalls();
  for (int32_t id = 0; id < bb_.tableExtent(); ++id) {
    const TableHyp& tab = bb_.table(id);
    if (!tab.alive) continue;
    bool linked = false;
    for (int i = 0; i < tab.n_children && !linked; ++i) linked = legDirectlyLinked(tab.children[i]);
    if (!linked) {
      bb_.killTable(id);
      bb_.releaseTable(id);
    }
  }
  for (int32_t id = 0; id < bb_.legExtent(); ++id) {
    const LegHyp& l = bb_.leg(id);
    if (!l.alive || l.parent != kNone || legDirectlyLinked(id)) continue;
    bb_.killLeg(id);
    bb_.releaseLeg(id);
  }
}

void Sampler::mapTables(std::vector<TableHyp>& out) const {
  out.clear();
  for (int32_t id = 0; id < bb_.tableExtent(); ++id)
    if (bb_.table(id).alive) out.push_back(bb_.table(id));
}

void Sampler::mapTables(std::vector<Pose2>& out) const {
  out.clear();
  for (int32_t id = 0; id < bb_.tableExtent(); ++id)
    if (bb_.table(id).alive) out.push_back(bb_.table(id).pose);
}


// ---- Reversible-jump moves ----------------------------------------------------------------
//
// The target is exp(beta J(B)) / rj_cell^n(B) (beta tempers the log joint; the reference
// measure's cells are not tempered), a density of the unordered configuration B of n hypotheses against the
// unit-rate Poisson reference measure over leg and table poses (x, y, theta). The chain's state space: every leg lies in the birth box of a working-memory
// shapelet (boxOf), every table has at least one child. Each step draws one kernel with fixed
// probabilities (ReversibleMoves), then its object uniformly among a set whose size the move does
// not change (the slots; the live legs; the live tables), so the selection probabilities cancel
// between a move and its reverse and each kernel satisfies detailed balance on its own:
//   leg birth/death at slot s: probability 1/2 each. Birth: pose uniform over the box B_s
//     (density 1 / |B_s|), parent none. Death: one of the n orphan legs lying in B_s,
//     uniformly. Birth ratio: log q_rev - log q_fwd = log(|B_s| / n_after), plus the reference
//     measure's -log rj_cell for the new hypothesis; death: the negative with n_before.
//   leg jitter, table jitter: symmetric Gaussian steps (children carried rigidly half the time:
//     a rotation and translation of their poses, Jacobian 1); ratio 0. A step that would leave
//     a leg outside every box is rejected (the target is 0 there).
//   parent change: sampleParent's weights excluding the current parent; ratio
//     log(w_old / W_rev) - log(w_new / W_fwd), both weights computed in the state they apply to.
//     Refused if it would leave the old parent without a child.
//   leg table: an orphan leg proposes a parent table at one of the 8 placements that put it at
//     a corner (probability 1/8 each) plus a Gaussian step (jitter_sigma_r, jitter_sigma_theta),
//     refused unless the leg lies within cornerLinkRadius of one of its corners; a leg whose
//     parent has no other child and lies so proposes that parent's death. Ratio for the birth
//     -log q(T | L) - log rj_cell (q: the 8-component mixture, logTableBirthDensity), for the
//     death the negative.
//   table birth/death (probability 1/2 each). Birth: a live leg uniformly (1/n_legs; n_legs is
//     the same before and after), if an orphan it proposes one of its 8 placements with the
//     smart weights of proposeParent (legs already near the placement's other corners) plus a
//     Gaussian step; the table adopts exactly the orphans within cornerLinkRadius of its corners
//     (refused if the proposer is not among them or they are more than kMaxChildren). Its
//     density sums over every adopted leg that could have proposed it:
//     q_b(T) = (1/n_legs) sum_{L in C(T)} sum_k w_k(L)/W(L) N(T; placement_k(L)). The weights
//     count live legs, whatever their parents, so they are the same before and after.
//     Death: a live table uniformly (1/n_tables), its children become orphans; refused unless a
//     birth from the result would adopt exactly these children. Ratio for the birth
//     log(1/n_tables_after) - log q_b(T) - log rj_cell; for the death the negative.
// The paper's priming, proposeChild, proposeParent (its adoption takes legs from other tables
// and kills emptied ones, a move whose reverse has no known density) and prune do not fire
// under kReversibleJump; the smart table birth above is their reversible substitute.

void Sampler::enterReversibleSpace() {
  if (walls()) enterReversibleWalls();
  for (int32_t id = 0; id < bb_.legExtent(); ++id) {
    const LegHyp& l = bb_.leg(id);
    if (!l.alive || inSomeBox(l.pose)) continue;
    bb_.killLeg(id);
    bb_.releaseLeg(id);
  }
  // A leg off every corner of its table (a table jittered away from it under the paper's
  // moves) leaves it: it stays, an orphan.
  for (int32_t id = 0; id < bb_.legExtent(); ++id) {
    const LegHyp& l = bb_.leg(id);
    if (l.alive && l.parent != kNone && !nearCorner(bb_.table(l.parent), l.pose.position()))
      bb_.setParent(id, kNone);
  }
  for (int32_t id = 0; id < bb_.tableExtent(); ++id) {
    const TableHyp& t = bb_.table(id);
    if (!t.alive) continue;
    bool child = false;
    for (int i = 0; i < t.n_children && !child; ++i) child = bb_.leg(t.children[i]).alive;
    if (child) continue;
    bb_.killTable(id);
    bb_.releaseTable(id);
  }
}

bool Sampler::decideRj(double delta, double beta, double log_q_ratio) {
  if (audit_ && std::isfinite(delta)) {  // -infinity: refused by a constraint, nothing to audit
    const double err = std::abs((bb_.totalEnergy() - audit_before_) - delta);
    stats_.audit_max_error = std::max(stats_.audit_max_error, err);
  }
  ++stats_.proposals;
  ++stats_.by_move[static_cast<size_t>(move_)].proposals;
  const double log_a = beta * delta + log_q_ratio;
  const bool ok = log_a >= 0.0 || std::log(rng_.uniform()) < log_a;
  accepted(ok);
  return ok;
}

bool Sampler::boxOf(int slot, Box& b) const {
  const Shapelet& s = bb_.shapelet(slot);
  const double side = bb_.params().leg_side;
  if (!legCanCause(side, s)) return false;
  const double half = 0.5 * side, m = opt_.rj_box_margin;
  b.origin = {s.x, s.y};
  b.oriented = s.oriented;
  b.phi = s.phi;
  if (s.oriented) {
    b.along = {std::cos(s.phi), std::sin(s.phi)};
    b.in = inwardNormal(s);
    b.v0 = half - m;
    b.v1 = half + m;
  } else {
    Vec2 away{s.x - s.ox, s.y - s.oy};
    b.in = away.norm() > 0.0 ? Vec2(away.normalized()) : Vec2{1.0, 0.0};
    b.along = {-b.in.y(), b.in.x()};
    b.v0 = half - m;
    b.v1 = half * std::sqrt(2.0) + m;
  }
  b.u = half + m;
  const double turn = s.oriented ? 2.0 * opt_.rj_box_theta : kPi / 2;
  b.volume = 2.0 * b.u * (b.v1 - b.v0) * turn;
  return true;
}

bool Sampler::inBox(const Box& b, const Pose2& pose) const {
  const Vec2 d = pose.position() - b.origin;
  const double u = d.dot(b.along), v = d.dot(b.in);
  if (std::abs(u) > b.u || v < b.v0 || v > b.v1) return false;
  return !b.oriented || std::abs(wrapPeriod(pose.theta - b.phi, kPi / 2)) <= opt_.rj_box_theta;
}

double Sampler::boxReach() const {
  const double side = bb_.params().leg_side;
  return std::hypot(0.5 * side + opt_.rj_box_margin, 0.5 * side * std::sqrt(2.0) + opt_.rj_box_margin);
}

bool Sampler::inSomeBox(const Pose2& pose) const {
  const double reach = boxReach();
  bool found = false;
  bb_.shapeletsWithin(pose.position(), reach, [&](int32_t slot) {
    Box b;
    if (!found && bb_.slotUsed(slot) && boxOf(slot, b) && inBox(b, pose)) found = true;
  });
  return found;
}

int Sampler::orphansInBox(const Box& b, int k, int32_t* kth) const {
  const double reach = std::hypot(b.u, b.v1);
  // Ids in increasing order: the hash visits cells in an order that does not depend on ids, so
  // collect the matches' ids by a scan of the (few) candidates and rank them.
  int n = 0;
  int32_t best = kNone;
  // Two passes: the count, then the k-th smallest id (k < n) by counting smaller ids.
  bb_.legsNear(b.origin + 0.5 * (b.v0 + b.v1) * b.in, reach, [&](int32_t id) {
    const LegHyp& l = bb_.leg(id);
    if (l.alive && l.parent == kNone && inBox(b, l.pose)) ++n;
  });
  if (kth != nullptr && k < n) {
    bb_.legsNear(b.origin + 0.5 * (b.v0 + b.v1) * b.in, reach, [&](int32_t id) {
      const LegHyp& l = bb_.leg(id);
      if (!l.alive || l.parent != kNone || !inBox(b, l.pose)) return;
      int smaller = 0;
      bb_.legsNear(b.origin + 0.5 * (b.v0 + b.v1) * b.in, reach, [&](int32_t o) {
        const LegHyp& lo = bb_.leg(o);
        if (o < id && lo.alive && lo.parent == kNone && inBox(b, lo.pose)) ++smaller;
      });
      if (smaller == k) best = id;
    });
    *kth = best;
  }
  return n;
}

int32_t Sampler::randomLiveLeg() {
  return randomLive(bb_.liveLegs(), bb_.legExtent(), [&](int32_t id) { return bb_.leg(id).alive; });
}

int32_t Sampler::randomLiveTable() {
  return randomLive(bb_.liveTables(), bb_.tableExtent(),
                    [&](int32_t id) { return bb_.table(id).alive; });
}

void Sampler::sweepReversible(double beta) {
  move_ = MoveKind::kReversible;
  rj_slots_.clear();
  for (int slot = 0; slot < bb_.workingMemoryCapacity(); ++slot) {
    Box b;
    if (bb_.slotUsed(slot) && boxOf(slot, b)) rj_slots_.push_back(slot);
  }
  const ReversibleMoves& m = opt_.rj_moves;
  // The walls' kernels, and each seed's fitted segment (data only: fixed through the sweep).
  const double wall_bd = walls() ? m.wall_birth_death : 0.0;
  const double wall_jit = walls() ? m.wall_jitter : 0.0;
  rj_fits_.clear();
  if (wall_bd > 0.0) {
    for (int slot = 0; slot < bb_.workingMemoryCapacity(); ++slot) {
      Vec2 p0, p1;
      bool swapped = false;
      if (!bb_.slotUsed(slot) || !wallFitOf(slot, p0, p1, swapped)) continue;
      const Vec2 a = swapped ? p1 : p0, b = swapped ? p0 : p1;
      rj_fits_.push_back({a, b, (b - a) / (b - a).norm()});
    }
  }
  // The smart birth places tables of the model's one size only; the rooms model's sizes move by
  // their own symmetric steps.
  const bool sized = bb_.params().sized();
  const double smart_bd = sized ? 0.0 : m.table_birth_death;
  const double sizes = sized ? m.sizes : 0.0;
  const double total = m.leg_birth_death + m.leg_jitter + m.leg_parent + m.leg_table +
                       m.table_jitter + smart_bd + m.table_group + wall_bd + wall_jit + sizes;
  if (total <= 0.0) return;
  const int steps = opt_.rj_steps_per_shapelet * std::max<int>(1, static_cast<int>(rj_slots_.size()));
  for (int i = 0; i < steps; ++i) {
    double u = rng_.uniform() * total;
    if ((u -= m.leg_birth_death) < 0.0) {
      if (!rj_slots_.empty())
        rjLegBirthDeath(rj_slots_[rng_.below(static_cast<uint32_t>(rj_slots_.size()))], beta);
    } else if ((u -= m.leg_jitter) < 0.0) {
      if (const int32_t id = randomLiveLeg(); id != kNone) rjJitterLeg(id, beta);
    } else if ((u -= m.leg_parent) < 0.0) {
      if (const int32_t id = randomLiveLeg(); id != kNone) rjParentChange(id, beta);
    } else if ((u -= m.leg_table) < 0.0) {
      if (const int32_t id = randomLiveLeg(); id != kNone) rjLegTable(id, beta);
    } else if ((u -= m.table_jitter) < 0.0) {
      if (const int32_t id = randomLiveTable(); id != kNone) rjJitterTable(id, beta);
    } else if ((u -= smart_bd) < 0.0) {
      rjTableBirthDeath(beta);
    } else if ((u -= m.table_group) < 0.0) {
      rjTableGroup(beta);
    } else if ((u -= wall_bd) < 0.0) {
      rjWallBirthDeath(beta);
    } else if ((u -= sizes) < 0.0) {
      rjSizeStep(beta);
    } else if (const int32_t id = randomLiveWall(); id != kNone) {
      if (rng_.uniform() < 0.5) jitterWall(id, beta);
      else extendWall(id, beta);
    }
  }
}

Pose2 Sampler::drawInBox(const Box& b) {
  const double a = rng_.uniform(-b.u, b.u), v = rng_.uniform(b.v0, b.v1);
  const double th = b.oriented ? b.phi + rng_.uniform(-opt_.rj_box_theta, opt_.rj_box_theta)
                               : rng_.uniform(0.0, kPi / 2);
  const Vec2 c = b.origin + a * b.along + v * b.in;
  return {c.x(), c.y(), wrapPeriod(th, kPi / 2)};
}

TableHyp Sampler::drawTableSize(double leg_side) {
  const ModelParams& p = bb_.params();
  TableHyp t;
  t.width = p.table_width;
  t.depth = p.table_depth;
  t.leg = p.leg_side;
  if (!p.sized()) return t;
  // Uniform over S = {min_side <= shorter <= max_short, longer <= max_long} (both orders): the
  // shorter side by inverting its marginal's CDF (density proportional to max_long - shorter),
  // the longer uniform above it, then which of width and depth is the shorter.
  const double m = p.size_min_side, ms = p.size_max_short, ml = p.size_max_long;
  const double a2 = (ml - m) * (ml - m), b2 = (ml - ms) * (ml - ms);
  const double lo = ml - std::sqrt(a2 - rng_.uniform() * (a2 - b2));
  const double hi = rng_.uniform(lo, ml);
  const bool wide = rng_.uniform() < 0.5;
  t.width = wide ? hi : lo;
  t.depth = wide ? lo : hi;
  t.leg = drawSideNear(leg_side);
  return t;
}

double Sampler::drawLegSide() {
  const ModelParams& p = bb_.params();
  return p.sized() ? rng_.uniform(p.leg_min, p.leg_max) : p.leg_side;
}

double Sampler::drawSideNear(double side) {
  const ModelParams& p = bb_.params();
  return p.sized() ? side + rng_.normal(0, p.sigma_w) : p.leg_side;
}

double Sampler::logSideNearDensity(double side, double near) const {
  const ModelParams& p = bb_.params();
  if (!p.sized()) return 0.0;
  const double z = (side - near) / p.sigma_w;
  // The normal's density against the prior's uniform probability on [leg_min, leg_max].
  return -0.5 * z * z - std::log(std::sqrt(2 * kPi) * p.sigma_w) + std::log(p.leg_max - p.leg_min);
}

Pose2 Sampler::drawPlacement(const Pose2& leg, const TableHyp& shape) {
  const int k = static_cast<int>(rng_.below(8));
  const double th0 = wrapPeriod(leg.theta + (k / 4) * (kPi / 2), kPi);
  const Vec2 off = Pose2{0, 0, th0}.toWorld(shape.cornerOffset(k % 4));
  return {leg.x - off.x() + rng_.normal(0, opt_.jitter_sigma_r),
          leg.y - off.y() + rng_.normal(0, opt_.jitter_sigma_r),
          wrapPeriod(th0 + rng_.normal(0, opt_.jitter_sigma_theta), kPi)};
}

void Sampler::rjLegBirthDeath(int slot, double beta) {
  Box b;
  if (!boxOf(slot, b)) return;
  if (rng_.uniform() < 0.5) {
    // log_q_ratio = log(P(death) / n_after) - log(P(birth) / |B_s|) = log(|B_s| / n_after).
    const Pose2 pose = drawInBox(b);
    const int n_after = orphansInBox(b, 0, nullptr) + 1;
    Touched t;
    bb_.shapeletsNear(pose.position(), t.shapelets);
    begin();
    const double e0 = bb_.energyBefore(t);
    const int32_t id = bb_.addLeg(pose, drawLegSide(), kNone);
    t.legs.add(id);
    const double e1 = bb_.energyAfter(t);
    if (!decideRj(e1 - e0, beta, std::log(b.volume / (n_after * opt_.rj_cell)))) {
      bb_.killLeg(id);
      bb_.releaseLeg(id);
    }
    return;
  }
  // log_q_ratio = log(P(birth) / |B_s|) - log(P(death) / n_before) = log(n_before / |B_s|).
  const int n = orphansInBox(b, 0, nullptr);
  if (n == 0) return;
  int32_t id = kNone;
  orphansInBox(b, static_cast<int>(rng_.below(static_cast<uint32_t>(n))), &id);
  Touched t;
  t.legs.add(id);
  bb_.shapeletsNear(bb_.leg(id).pose.position(), t.shapelets);
  begin();
  const double e0 = bb_.energyBefore(t);
  bb_.killLeg(id);
  const double e1 = bb_.energyAfter(t);
  if (decideRj(e1 - e0, beta, std::log(n * opt_.rj_cell / b.volume))) bb_.releaseLeg(id);
  else bb_.reviveLeg(id);
}

void Sampler::rjJitterLeg(int32_t id, double beta) {
  // Symmetric Gaussian step (theta modulo pi/2 keeps it symmetric): log_q_ratio = 0.
  const Pose2 old = bb_.leg(id).pose;
  const Pose2 moved = jittered(old, kPi / 2);
  // Outside the state space (target 0, rejected): in no box, or off its table's corners.
  const int32_t parent = bb_.leg(id).parent;
  if (!inSomeBox(moved)) return;
  if (parent != kNone && !nearCorner(bb_.table(parent), moved.position())) return;
  Touched t;
  t.legs.add(id);
  t.tables.add(bb_.leg(id).parent);
  bb_.shapeletsNear(old.position(), t.shapelets);
  bb_.shapeletsNear(moved.position(), t.shapelets);
  begin();
  const double e0 = bb_.energyBefore(t);
  bb_.moveLeg(id, moved);
  const double e1 = bb_.energyAfter(t);
  if (!decideRj(e1 - e0, beta, 0.0)) bb_.moveLeg(id, old);
}

void Sampler::rjParentChange(int32_t leg, double beta) {
  const int32_t old_parent = bb_.leg(leg).parent;
  // Every table keeps a child: a move that would empty one is outside the state space.
  if (old_parent != kNone && bb_.table(old_parent).n_children <= 1) return;
  std::array<int32_t, 16> cand;
  std::array<double, 16> weight;
  int n = parentCandidates(bb_.leg(leg), old_parent, cand, weight);
  double total = 0.0;
  for (int i = 0; i < n; ++i) total += weight[i];
  if (total <= 0.0) return;
  double u = rng_.uniform() * total;
  int pick = n - 1;
  for (int i = 0; i < n; ++i) {
    if ((u -= weight[i]) < 0.0) {
      pick = i;
      break;
    }
  }
  const int32_t new_parent = cand[pick];
  const double log_fwd = std::log(weight[pick] / total);
  Touched t;
  t.legs.add(leg);
  t.tables.add(old_parent);
  t.tables.add(new_parent);
  begin();
  const double e0 = bb_.energyBefore(t);
  bb_.setParent(leg, new_parent);
  const double e1 = bb_.energyAfter(t);
  // The reverse: sampleParent's weights in the new state, excluding the new parent.
  n = parentCandidates(bb_.leg(leg), new_parent, cand, weight);
  double rev_total = 0.0, w_old = 0.0;
  for (int i = 0; i < n; ++i) {
    rev_total += weight[i];
    if (cand[i] == old_parent) w_old = weight[i];
  }
  const double log_rev = w_old > 0.0 ? std::log(w_old / rev_total)
                                     : -std::numeric_limits<double>::infinity();
  if (!decideRj(e1 - e0, beta, log_rev - log_fwd)) bb_.setParent(leg, old_parent);
}

double Sampler::logTableBirthDensity(const TableHyp& shape, const Pose2& leg,
                                     double leg_side) const {
  const Pose2& table = shape.pose;
  const double sr = opt_.jitter_sigma_r, st = opt_.jitter_sigma_theta;
  double acc = -std::numeric_limits<double>::infinity();
  for (int k = 0; k < 8; ++k) {
    const double th = wrapPeriod(leg.theta + (k / 4) * (kPi / 2), kPi);
    const Vec2 off = Pose2{0, 0, th}.toWorld(shape.cornerOffset(k % 4));
    const double dx = table.x - (leg.x - off.x()), dy = table.y - (leg.y - off.y());
    // Wrapped normal of period pi: the nearest three windings (sigma << pi).
    double dth = wrapPeriod(table.theta - th, kPi);
    if (dth > kPi / 2) dth -= kPi;
    double wrap = -std::numeric_limits<double>::infinity();
    for (int j = -1; j <= 1; ++j) {
      const double e = (dth + j * kPi) / st;
      wrap = logAddExp(wrap, -0.5 * e * e);
    }
    const double lg = -0.5 * (dx * dx + dy * dy) / (sr * sr) - std::log(2 * kPi * sr * sr) +
                      wrap - std::log(std::sqrt(2 * kPi) * st);
    acc = logAddExp(acc, std::log(1.0 / 8.0) + lg);
  }
  return acc + logSideNearDensity(shape.leg, leg_side);
}

bool Sampler::nearCorner(const TableHyp& table, const Vec2& at) const {
  const double r = bb_.params().cornerLinkRadius();
  for (int c = 0; c < 4; ++c)
    if ((table.corner(c) - at).squaredNorm() <= r * r) return true;
  return false;
}

bool Sampler::childrenAtCorners(const TableHyp& table) const {
  for (int i = 0; i < table.n_children; ++i)
    if (!nearCorner(table, bb_.leg(table.children[i]).pose.position())) return false;
  return true;
}

bool Sampler::sizeAllowed(const TableHyp& shape) const {
  // The paper's and the walls model's one size is not judged by the rooms model's prior.
  const ModelParams& p = bb_.params();
  return !p.sized() || std::isfinite(p.logSizePrior(shape.width, shape.depth, shape.leg));
}

TableHyp Sampler::shaped(const TableHyp& shape, const Pose2& pose) {
  return reshaped(shape, pose, shape.width, shape.depth, shape.leg);
}

bool Sampler::drawTableThrough(const Pose2& leg, double side, TableHyp& born) {
  const TableHyp shape = drawTableSize(side);
  if (!sizeAllowed(shape)) return false;
  born = shaped(shape, drawPlacement(leg, shape));
  return nearCorner(born, leg.position());
}

void Sampler::rjLegTable(int32_t leg, double beta) {
  const LegHyp l = bb_.leg(leg);
  if (l.parent == kNone) {
    // Birth of a parent table: its size from the prior (the rooms model), placement k uniform
    // of 8, then a Gaussian step. The size's reference measure is the prior itself, so drawing
    // from it adds nothing to the ratio (sampler.cc's top).
    TableHyp born;
    if (!drawTableThrough(l.pose, l.side, born)) return;
    const double log_q = logTableBirthDensity(born, l.pose, l.side);
    Touched t;
    t.legs.add(leg);
    begin();
    const double e0 = bb_.energyBefore(t);
    const int32_t table = bb_.addTable(born.pose, born.width, born.depth, born.leg);
    bb_.setParent(leg, table);
    t.tables.add(table);
    const double e1 = bb_.energyAfter(t);
    // Reverse: this leg's kernel kills its sole parent with probability 1.
    if (!decideRj(e1 - e0, beta, -log_q - std::log(opt_.rj_cell))) {
      bb_.setParent(leg, kNone);
      bb_.killTable(table);
      bb_.releaseTable(table);
    }
    return;
  }
  const TableHyp& tab = bb_.table(l.parent);
  if (tab.n_children != 1) return;  // not the sole child: nothing this kernel can do
  const int32_t table = l.parent;
  if (!nearCorner(tab, l.pose.position())) return;  // the birth could not have made it
  const double log_q = logTableBirthDensity(tab, l.pose, l.side);
  Touched t;
  t.legs.add(leg);
  t.tables.add(table);
  begin();
  const double e0 = bb_.energyBefore(t);
  bb_.killTable(table);
  const double e1 = bb_.energyAfter(t);
  if (decideRj(e1 - e0, beta, log_q + std::log(opt_.rj_cell))) bb_.releaseTable(table);
  else bb_.reviveTable(table);
}

int Sampler::nearestCorner(const TableHyp& table, const Vec2& at) const {
  int best = 0;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (int c = 0; c < 4; ++c) {
    const double d2 = (table.corner(c) - at).squaredNorm();
    if (d2 < best_d2) {
      best_d2 = d2;
      best = c;
    }
  }
  return best;
}

double Sampler::logLegBoxDensity(const Pose2& leg) const {
  const double reach = boxReach();
  double acc = -std::numeric_limits<double>::infinity();
  bb_.shapeletsWithin(leg.position(), reach, [&](int32_t slot) {
    Box b;
    if (bb_.slotUsed(slot) && boxOf(slot, b) && inBox(b, leg)) acc = logAddExp(acc, -std::log(b.volume));
  });
  return acc - std::log(static_cast<double>(std::max<size_t>(1, rj_slots_.size())));
}

double Sampler::logCornerLegDensity(const TableHyp& table, int corner, const Pose2& leg) const {
  const double sr = opt_.jitter_sigma_r, st = opt_.jitter_sigma_theta;
  const Vec2 d = leg.position() - table.corner(corner);
  // Wrapped normal of period pi/2: the nearest three windings (sigma << pi/2).
  double dth = wrapPeriod(leg.theta - table.pose.theta, kPi / 2);
  if (dth > kPi / 4) dth -= kPi / 2;
  double wrap = -std::numeric_limits<double>::infinity();
  for (int j = -1; j <= 1; ++j) {
    const double e = (dth + j * kPi / 2) / st;
    wrap = logAddExp(wrap, -0.5 * e * e);
  }
  return -0.5 * d.squaredNorm() / (sr * sr) - std::log(2 * kPi * sr * sr) + wrap -
         std::log(std::sqrt(2 * kPi) * st);
}

double Sampler::logGroupBirthDensity(const TableHyp& table, const Pose2* legs, const double* sides,
                                     int n) const {
  const double neg_inf = -std::numeric_limits<double>::infinity();
  if (n < 1 || n > 4) return neg_inf;
  const double half = std::log(0.5);
  double total = neg_inf;
  for (int first = 0; first < n; ++first) {
    const double head = logLegBoxDensity(legs[first]);
    if (head == neg_inf || !nearCorner(table, legs[first].position())) continue;
    const int c1 = nearestCorner(table, legs[first].position());
    std::array<int, 3> corners{};
    int nc = 0;
    for (int c = 0; c < 4; ++c)
      if (c != c1) corners[static_cast<size_t>(nc++)] = c;
    std::array<int, 3> others{};
    int no = 0;
    for (int i = 0; i < n; ++i)
      if (i != first) others[static_cast<size_t>(no++)] = i;
    // Injective assignments of the other legs to the three corners (at most 3! = 6): each
    // corner has a leg (1/2 times its density) or none (1/2).
    double assign = neg_inf;
    std::array<int, 3> perm{0, 1, 2};
    do {
      // perm[i] < no: corner i takes leg others[perm[i]]; each assignment is visited once for
      // every order of the corners left empty, so only the sorted order of those counts.
      bool canonical = true;
      int last_empty = -1;
      for (int i = 0; i < 3; ++i) {
        if (perm[static_cast<size_t>(i)] < no) continue;
        if (perm[static_cast<size_t>(i)] < last_empty) canonical = false;
        last_empty = perm[static_cast<size_t>(i)];
      }
      if (!canonical) continue;
      double e = 0.0;
      for (int i = 0; i < 3; ++i) {
        const int leg = perm[static_cast<size_t>(i)];
        e += half;
        if (leg < no) {
          const int o = others[static_cast<size_t>(leg)];
          e += logCornerLegDensity(table, corners[static_cast<size_t>(i)], legs[o]) +
               logSideNearDensity(sides[o], table.leg);
        }
      }
      assign = logAddExp(assign, e);
    } while (std::next_permutation(perm.begin(), perm.end()));
    total = logAddExp(total,
                      head + logTableBirthDensity(table, legs[first], sides[first]) + assign);
  }
  return total;
}

void Sampler::rjTableGroup(double beta) {
  if (rj_slots_.empty()) return;
  if (rng_.uniform() < 0.5) {
    // Birth: a leg uniform in a slot's box, a table at one of its 8 placements with a Gaussian
    // step, and at each other corner a leg (1/2, a Gaussian step from the corner) or none.
    // log q ratio = log(P(death) / n_tables_after) - log(P(birth) q(T, legs)) - (1 + n) log cell.
    Box b;
    if (!boxOf(rj_slots_[rng_.below(static_cast<uint32_t>(rj_slots_.size()))], b)) return;
    std::array<Pose2, 4> legs;
    std::array<double, 4> sides{};
    legs[0] = drawInBox(b);
    sides[0] = drawLegSide();
    // The width and depth from the prior (rooms model; their reference measure: the ratio gains
    // nothing), the leg sides about the first leg's.
    // As rjLegTable's birth: only tables with the leg at a corner (the target's known limit,
    // docs/BLACKBOARD.md); the density below has the same indicator.
    TableHyp born;
    if (!drawTableThrough(legs[0], sides[0], born)) return;
    const Pose2& pose = born.pose;
    const int c1 = nearestCorner(born, legs[0].position());
    int n = 1;
    for (int c = 0; c < 4; ++c) {
      if (c == c1 || rng_.uniform() < 0.5) continue;
      const Vec2 at = born.corner(c);
      const Pose2 leg{at.x() + rng_.normal(0, opt_.jitter_sigma_r),
                      at.y() + rng_.normal(0, opt_.jitter_sigma_r),
                      wrapPeriod(pose.theta + rng_.normal(0, opt_.jitter_sigma_theta), kPi / 2)};
      if (!inSomeBox(leg)) return;  // outside the state space: target 0
      sides[static_cast<size_t>(n)] = drawSideNear(born.leg);
      if (bb_.params().sized() && !bb_.params().legSideAllowed(sides[static_cast<size_t>(n)]))
        return;
      legs[static_cast<size_t>(n++)] = leg;
    }
    const double log_q = logGroupBirthDensity(born, legs.data(), sides.data(), n);
    Touched t;
    for (int i = 0; i < n; ++i) bb_.shapeletsNear(legs[static_cast<size_t>(i)].position(), t.shapelets);
    if (t.shapelets.n >= static_cast<int>(std::size(t.shapelets.ids))) return;
    const double n_after = bb_.liveTables() + 1.0;
    begin();
    const double e0 = bb_.energyBefore(t);
    const int32_t table = bb_.addTable(pose, born.width, born.depth, born.leg);
    t.tables.add(table);
    std::array<int32_t, 4> ids{};
    for (int i = 0; i < n; ++i) {
      ids[static_cast<size_t>(i)] =
          bb_.addLeg(legs[static_cast<size_t>(i)], sides[static_cast<size_t>(i)], table);
      t.legs.add(ids[static_cast<size_t>(i)]);
    }
    const double e1 = bb_.energyAfter(t);
    if (!decideRj(e1 - e0, beta,
                  -std::log(n_after) - log_q - (1.0 + n) * std::log(opt_.rj_cell))) {
      for (int i = n - 1; i >= 0; --i) {
        bb_.killLeg(ids[static_cast<size_t>(i)]);
        bb_.releaseLeg(ids[static_cast<size_t>(i)]);
      }
      bb_.killTable(table);
      bb_.releaseTable(table);
    }
    return;
  }
  // Death of a table with all its legs: the negative of the birth's ratio.
  const int32_t id = randomLiveTable();
  if (id == kNone) return;
  const TableHyp& tab = bb_.table(id);
  const int n = tab.n_children;
  if (n < 1 || n > 4) return;  // the birth makes one to four legs
  std::array<Pose2, 4> legs;
  std::array<double, 4> sides{};
  for (int i = 0; i < n; ++i) {
    legs[static_cast<size_t>(i)] = bb_.leg(tab.children[i]).pose;
    sides[static_cast<size_t>(i)] = bb_.leg(tab.children[i]).side;
  }
  const double log_q = logGroupBirthDensity(tab, legs.data(), sides.data(), n);
  if (log_q == -std::numeric_limits<double>::infinity()) return;
  proposeDeathWithLegs(id, beta,
                       std::log(static_cast<double>(bb_.liveTables())) + log_q +
                           (1.0 + n) * std::log(opt_.rj_cell));
}

void Sampler::rjJitterTable(int32_t id, double beta) {
  // jitterTable's move with symmetric steps; a carried child outside every box is refused.
  const Pose2 old = bb_.table(id).pose;
  const Pose2 moved = jittered(old, kPi);
  const bool rigid = rng_.uniform() < 0.5;
  Touched t;
  t.tables.add(id);
  const TableHyp& tab = bb_.table(id);
  const TableHyp moved_tab = shaped(tab, moved);
  const int n = tab.n_children;
  std::array<int32_t, kMaxChildren> kids;
  std::array<Pose2, kMaxChildren> kid_old, kid_new;
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<size_t>(i);
    kids[k] = tab.children[i];
    kid_old[k] = bb_.leg(tab.children[i]).pose;
    const Vec2 w = moved.toWorld(old.toLocal(kid_old[k].position()));
    kid_new[k] = rigid ? Pose2{w.x(), w.y(), wrapPeriod(kid_old[k].theta + moved.theta - old.theta, kPi / 2)}
                       : kid_old[k];
    t.legs.add(kids[k]);
    // Every child stays at a corner of the moved table (the state space).
    if (!nearCorner(moved_tab, (rigid ? kid_new[k] : kid_old[k]).position())) return;
    if (rigid) {
      if (!inSomeBox(kid_new[k])) return;
      bb_.shapeletsNear(kid_old[k].position(), t.shapelets);
      bb_.shapeletsNear(kid_new[k].position(), t.shapelets);
    }
  }
  begin();
  const double e0 = bb_.energyBefore(t);
  bb_.moveTable(id, moved);
  if (rigid)
    for (int i = 0; i < n; ++i) bb_.moveLeg(kids[static_cast<size_t>(i)], kid_new[static_cast<size_t>(i)]);
  const double e1 = bb_.energyAfter(t);
  if (!decideRj(e1 - e0, beta, 0.0)) {
    if (rigid)
      for (int i = 0; i < n; ++i) bb_.moveLeg(kids[static_cast<size_t>(i)], kid_old[static_cast<size_t>(i)]);
    bb_.moveTable(id, old);
  }
}


void Sampler::smartPlacements(int32_t leg, std::array<Pose2, 8>& place,
                              std::array<double, 8>& weight) const {
  const ModelParams& p = bb_.params();
  const LegHyp& l = bb_.leg(leg);
  const double r = p.cornerLinkRadius();
  for (int k = 0; k < 8; ++k) {
    const auto kk = static_cast<size_t>(k);
    const double th = wrapPeriod(l.pose.theta + (k / 4) * (kPi / 2), kPi);
    const Vec2 off = Pose2{0, 0, th}.toWorld(p.cornerOffset(k % 4));
    place[kk] = {l.pose.x - off.x(), l.pose.y - off.y(), th};
    double w = 1.0;
    for (int c = 0; c < 4; ++c) {
      if (c == k % 4) continue;
      const Vec2 corner = place[kk].toWorld(p.cornerOffset(c));
      bb_.legsNear(corner, r, [&](int32_t o) {
        const LegHyp& ol = bb_.leg(o);
        if (o != leg && ol.alive && (ol.pose.position() - corner).squaredNorm() <= r * r)
          w += opt_.smart_parent_gain;
      });
    }
    weight[kk] = w;
  }
}

bool Sampler::adoptable(const Pose2& pose, IdSet<4 * kMaxChildren>& out) const {
  const ModelParams& p = bb_.params();
  const double r = p.cornerLinkRadius();
  bool overflow = false;
  for (int c = 0; c < 4; ++c) {
    const Vec2 corner = pose.toWorld(p.cornerOffset(c));
    bb_.legsNear(corner, r, [&](int32_t o) {
      const LegHyp& ol = bb_.leg(o);
      if (!ol.alive || ol.parent != kNone || (ol.pose.position() - corner).squaredNorm() > r * r)
        return;
      if (!out.contains(o) && out.n >= kMaxChildren) overflow = true;
      out.add(o);
    });
  }
  return !overflow;
}

double Sampler::logSmartBirthDensity(const Pose2& pose,
                                     const IdSet<4 * kMaxChildren>& children) const {
  const double sr = opt_.jitter_sigma_r, st = opt_.jitter_sigma_theta;
  const double log_norm = -std::log(2 * kPi * sr * sr) - std::log(std::sqrt(2 * kPi) * st);
  double acc = -std::numeric_limits<double>::infinity();
  std::array<Pose2, 8> place;
  std::array<double, 8> weight;
  for (int32_t leg : children.span()) {
    smartPlacements(leg, place, weight);
    double total = 0.0;
    for (double w : weight) total += w;
    for (size_t k = 0; k < 8; ++k) {
      const double dx = pose.x - place[k].x, dy = pose.y - place[k].y;
      double dth = wrapPeriod(pose.theta - place[k].theta, kPi);
      if (dth > kPi / 2) dth -= kPi;
      double wrap = -std::numeric_limits<double>::infinity();
      for (int j = -1; j <= 1; ++j) {
        const double e = (dth + j * kPi) / st;
        wrap = logAddExp(wrap, -0.5 * e * e);
      }
      acc = logAddExp(acc, std::log(weight[k] / total) - 0.5 * (dx * dx + dy * dy) / (sr * sr) +
                               wrap + log_norm);
    }
  }
  return acc;
}

void Sampler::rjTableBirthDeath(double beta) {
  const double log_cell = std::log(opt_.rj_cell);
  if (rng_.uniform() < 0.5) {
    const int32_t leg = randomLiveLeg();
    if (leg == kNone || bb_.leg(leg).parent != kNone) return;
    const double log_pick = -std::log(static_cast<double>(bb_.liveLegs()));
    std::array<Pose2, 8> place;
    std::array<double, 8> weight;
    smartPlacements(leg, place, weight);
    double total = 0.0;
    for (double w : weight) total += w;
    double u = rng_.uniform() * total;
    size_t k = 0;
    while (k < 7 && (u -= weight[k]) >= 0.0) ++k;
    const Pose2 pose{place[k].x + rng_.normal(0, opt_.jitter_sigma_r),
                     place[k].y + rng_.normal(0, opt_.jitter_sigma_r),
                     wrapPeriod(place[k].theta + rng_.normal(0, opt_.jitter_sigma_theta), kPi)};
    IdSet<4 * kMaxChildren> kids;
    if (!adoptable(pose, kids) || !kids.contains(leg)) return;
    const double log_fwd = log_pick + logSmartBirthDensity(pose, kids);
    Touched t;
    for (int32_t o : kids.span()) t.legs.add(o);
    begin();
    const double e0 = bb_.energyBefore(t);
    const int32_t table = bb_.addTable(pose);
    for (int32_t o : kids.span()) bb_.setParent(o, table);
    t.tables.add(table);
    const double e1 = bb_.energyAfter(t);
    const double log_rev = -std::log(static_cast<double>(bb_.liveTables()));
    if (!decideRj(e1 - e0, beta, log_rev - log_fwd - log_cell)) {
      for (int32_t o : kids.span()) bb_.setParent(o, kNone);
      bb_.killTable(table);
      bb_.releaseTable(table);
    }
    return;
  }
  const int32_t table = randomLiveTable();
  if (table == kNone) return;
  const double log_fwd = -std::log(static_cast<double>(bb_.liveTables()));
  const TableHyp& tab = bb_.table(table);
  const Pose2 pose = tab.pose;
  Touched t;
  t.tables.add(table);
  for (int i = 0; i < tab.n_children; ++i) t.legs.add(tab.children[i]);
  begin();
  const double e0 = bb_.energyBefore(t);
  bb_.killTable(table);
  // The reverse birth must adopt exactly these children.
  IdSet<4 * kMaxChildren> kids;
  bool same = adoptable(pose, kids) && kids.n == t.legs.n;
  for (int32_t o : t.legs.span()) same = same && kids.contains(o);
  if (!same) {
    bb_.reviveTable(table);
    return;
  }
  const double e1 = bb_.energyAfter(t);
  const double log_rev = -std::log(static_cast<double>(bb_.liveLegs())) +
                         logSmartBirthDensity(pose, kids);
  if (decideRj(e1 - e0, beta, log_rev + log_cell - log_fwd)) bb_.releaseTable(table);
  else bb_.reviveTable(table);
}

// ---------------------------------------------------------------- the rooms model's size moves
//
// Each move below writes log_q_ratio = log q(reverse) - log q(forward), the proposal's part of a
// Metropolis-Hastings ratio, where it can be computed. The three size steps are symmetric (0):
// under kReversibleJump decide() takes them with that ratio (rjSizeStep); proposeParentSized's
// density is unknown and it does not fire there.

void Sampler::resizeTable(int32_t id, double beta) {
  const ModelParams& p = bb_.params();
  const TableHyp old = bb_.table(id);
  // One corner's leg centre stays where it is; the opposite sides move. A step on the width, the
  // depth or both (each a third of the time).
  const int k = static_cast<int>(rng_.below(4));
  const uint32_t which = rng_.below(3);
  const double w = old.width + (which != 1 ? rng_.normal(0, opt_.resize_sigma) : 0.0);
  const double d = old.depth + (which != 0 ? rng_.normal(0, opt_.resize_sigma) : 0.0);
  if (!std::isfinite(p.logSizePrior(w, d, old.leg))) return;  // outside the prior: rejected
  const Vec2 fixed = old.corner(k);
  const Vec2 off = Pose2{0, 0, old.pose.theta}.toWorld(ModelParams::cornerOffset(k, w, d, old.leg));
  const Pose2 pose{fixed.x() - off.x(), fixed.y() - off.y(), old.pose.theta};
  // Symmetric: the corner and the branch are drawn independently of the state, the Gaussian step
  // is symmetric, and from the new state the same corner and the negated step give back the old
  // one (corner k's world position is unchanged by construction). The map (pose, w, d) ->
  // (pose', w', d') for a given step is a translation: Jacobian 1.
  [[maybe_unused]] const double log_q_ratio = 0.0;
  // Under reversible jump every child stays at a corner (the state space; target 0 outside).
  if (rj() && !childrenAtCorners(reshaped(old, pose, w, d, old.leg))) return;
  Touched t;
  t.tables.add(id);
  for (int i = 0; i < old.n_children; ++i) t.legs.add(old.children[i]);
  begin();
  const double e0 = bb_.energyBefore(t);
  bb_.reshapeTable(id, pose, w, d, old.leg);
  const double e1 = bb_.energyAfter(t);
  if (!decide(e1 - e0, beta)) bb_.reshapeTable(id, old.pose, old.width, old.depth, old.leg);
}

void Sampler::splitTable(int32_t id, double beta) {
  const ModelParams& p = bb_.params();
  const TableHyp old = bb_.table(id);
  // The long axis: the table frame's x when width >= depth, else its y (u along it, v across).
  const bool along_x = old.width >= old.depth;
  const double len = along_x ? old.width : old.depth, across = along_x ? old.depth : old.width;
  const double half = 0.5 * len, r = p.cornerLinkRadius();
  const double edge = 0.5 * (across - old.leg);  // the long sides' leg centres, +-edge across
  // Orphans on a long side, far enough from both ends that each piece is a table the prior
  // allows; one of them drawn uniformly.
  std::array<int32_t, 8> cand{};
  int n = 0;
  bb_.legsNear(old.pose.position(), 0.5 * std::hypot(old.width, old.depth) + r, [&](int32_t o) {
    const LegHyp& l = bb_.leg(o);
    if (!l.alive || l.parent != kNone || n == 8) return;
    const Vec2 q = old.pose.toLocal(l.pose.position());
    const double u = along_x ? q.x() : q.y(), v = along_x ? q.y() : q.x();
    if (std::abs(std::abs(v) - edge) > r) return;
    const double cut = u + 0.5 * l.side;  // the first piece ends at the orphan's outer face
    if (cut + half < p.size_min_side || half - cut < p.size_min_side) return;
    cand[static_cast<size_t>(n++)] = o;
  });
  if (n == 0) return;
  // The cut: in the gap between the drawn orphan and its neighbour on the same side when one
  // stands within a leg of it (the inner legs of two touching tables), else at the orphan's
  // face towards either end (a coin).
  const int32_t seed = cand[static_cast<size_t>(rng_.below(static_cast<uint32_t>(n)))];
  const LegHyp& sl = bb_.leg(seed);
  const Vec2 sq = old.pose.toLocal(sl.pose.position());
  const double su = along_x ? sq.x() : sq.y(), sv = along_x ? sq.y() : sq.x();
  double cut = su + (rng_.uniform() < 0.5 ? 0.5 : -0.5) * sl.side, gap = p.leg_max + r;
  for (int i = 0; i < n; ++i) {
    const LegHyp& ol = bb_.leg(cand[static_cast<size_t>(i)]);
    const Vec2 oq = old.pose.toLocal(ol.pose.position());
    const double ou = along_x ? oq.x() : oq.y(), ov = along_x ? oq.y() : oq.x();
    if (cand[static_cast<size_t>(i)] == seed || ov * sv <= 0.0 || std::abs(ou - su) >= gap)
      continue;
    gap = std::abs(ou - su);
    cut = ou > su ? 0.5 * ((su + 0.5 * sl.side) + (ou - 0.5 * ol.side))
                  : 0.5 * ((ou + 0.5 * ol.side) + (su - 0.5 * sl.side));
  }
  const double len_a = cut + half, len_b = half - cut;
  const double wa = along_x ? len_a : old.width, da = along_x ? old.depth : len_a;
  const double wb = along_x ? len_b : old.width, db = along_x ? old.depth : len_b;
  if (!std::isfinite(p.logSizePrior(wa, da, old.leg)) ||
      !std::isfinite(p.logSizePrior(wb, db, old.leg)))
    return;
  const auto at = [&](double u) {
    const Vec2 c = old.pose.toWorld(along_x ? Vec2{u, 0.0} : Vec2{0.0, u});
    return Pose2{c.x(), c.y(), old.pose.theta};
  };
  const Pose2 pose_a = at(0.5 * (cut - half)), pose_b = at(0.5 * (cut + half));
  // Children at the far end (+u: corners 0, 3 along x; corners 0, 1 along y) go to the new table.
  const auto far_end = [&](int corner) {
    return along_x ? (corner == 0 || corner == 3) : (corner == 0 || corner == 1);
  };
  IdSet<kMaxChildren> moved;
  for (int i = 0; i < old.n_children; ++i)
    if (far_end(bb_.leg(old.children[i]).corner)) moved.add(old.children[i]);
  // At each of the pieces' new corners (the cut's two sides) the nearest orphan joins, while
  // the piece has room for a child.
  const TableHyp a = reshaped(old, pose_a, wa, da, old.leg);
  const TableHyp b = reshaped(old, pose_b, wb, db, old.leg);
  IdSet<4> join_a, join_b;
  const auto nearestOrphan = [&](const Vec2& c) {
    int32_t best = kNone;
    double best_d2 = r * r;
    bb_.legsNear(c, r, [&](int32_t o) {
      const LegHyp& l = bb_.leg(o);
      const double d2 = (l.pose.position() - c).squaredNorm();
      if (l.alive && l.parent == kNone && !join_a.contains(o) && d2 <= best_d2) {
        best = o;
        best_d2 = d2;
      }
    });
    return best;
  };
  const int near_children = old.n_children - moved.n;
  for (int k = 0; k < 4; ++k) {
    if (!far_end(k) || near_children + join_a.n >= kMaxChildren) continue;
    if (const int32_t o = nearestOrphan(a.corner(k)); o != kNone) join_a.add(o);
  }
  for (int k = 0; k < 4; ++k) {
    if (far_end(k) || moved.n + join_b.n >= kMaxChildren) continue;
    const int32_t o = nearestOrphan(b.corner(k));
    if (o != kNone && !join_b.contains(o)) join_b.add(o);
  }
  Touched t;
  t.tables.add(id);
  for (int i = 0; i < old.n_children; ++i) t.legs.add(old.children[i]);
  for (int32_t o : join_a.span()) t.legs.add(o);
  for (int32_t o : join_b.span()) t.legs.add(o);
  begin();
  const double e0 = bb_.energyBefore(t);
  const int32_t nb = bb_.addTable(pose_b, wb, db, old.leg);
  bb_.reshapeTable(id, pose_a, wa, da, old.leg);
  for (int32_t o : moved.span()) bb_.setParent(o, nb);
  for (int32_t o : join_a.span()) bb_.setParent(o, id);
  for (int32_t o : join_b.span()) bb_.setParent(o, nb);
  t.tables.add(nb);
  const double e1 = bb_.energyAfter(t);
  if (decide(e1 - e0, beta)) return;
  for (int32_t o : join_b.span()) bb_.setParent(o, kNone);
  for (int32_t o : join_a.span()) bb_.setParent(o, kNone);
  for (int32_t o : moved.span()) bb_.setParent(o, id);
  bb_.reshapeTable(id, old.pose, old.width, old.depth, old.leg);
  bb_.killTable(nb);
  bb_.releaseTable(nb);
}

void Sampler::tableLegSide(int32_t id, double beta) {
  const ModelParams& p = bb_.params();
  const TableHyp old = bb_.table(id);
  const double leg = drawSideStep(old.leg);
  const double step = leg - old.leg;
  if (!std::isfinite(p.logSizePrior(old.width, old.depth, leg))) return;
  // Half the steps carry the children: each leg's side changes by the same step and its centre
  // moves with its corner's leg centre, so the faces on the top's outline stay where they are
  // (the faces the whiskers touch from outside the object) and the legs grow or shrink inwards.
  // A table's leg side and its legs' are held together by eq. 10's leg-width term (sigma_w), so
  // moving either alone barely moves the pair, as a table's pose and its legs' (jitterTable).
  // Not under reversible jump (as legSide's anchor: a carried leg's centre moves).
  const bool carry = !rj() && rng_.uniform() < 0.5;
  // Symmetric: the branch is drawn independently of the state, the side step is symmetric
  // (drawSideStep), and the negated step gives back the old state (each child keeps its corner,
  // whose leg centre moves by the same offset back). For a given step the map is a translation
  // of (leg side, children's sides and centres): Jacobian 1.
  [[maybe_unused]] const double log_q_ratio = 0.0;
  const TableHyp shape = reshaped(old, old.pose, old.width, old.depth, leg);
  if (rj() && !childrenAtCorners(shape)) return;
  Touched t;
  t.tables.add(id);
  const int n = old.n_children;
  std::array<int32_t, kMaxChildren> kids;
  std::array<Pose2, kMaxChildren> kid_old;
  std::array<Pose2, kMaxChildren> kid_new;
  std::array<double, kMaxChildren> side_old;
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<size_t>(i);
    const LegHyp& l = bb_.leg(old.children[i]);
    kids[k] = old.children[i];
    kid_old[k] = l.pose;
    side_old[k] = l.side;
    t.legs.add(kids[k]);
    if (!carry) continue;
    if (!p.legSideAllowed(l.side + step)) return;
    const Vec2 shift = shape.corner(l.corner) - old.corner(l.corner);
    kid_new[k] = {l.pose.x + shift.x(), l.pose.y + shift.y(), l.pose.theta};
    bb_.shapeletsNear(kid_old[k].position(), t.shapelets);
    bb_.shapeletsNear(kid_new[k].position(), t.shapelets);
  }
  begin();
  const double e0 = bb_.energyBefore(t);
  bb_.reshapeTable(id, old.pose, old.width, old.depth, leg);
  if (carry) {
    for (int i = 0; i < n; ++i) {
      const auto k = static_cast<size_t>(i);
      bb_.moveLeg(kids[k], kid_new[k]);
      bb_.setLegSide(kids[k], side_old[k] + step);
    }
  }
  const double e1 = bb_.energyAfter(t);
  if (decide(e1 - e0, beta)) return;
  if (carry) {
    for (int i = 0; i < n; ++i) {
      const auto k = static_cast<size_t>(i);
      bb_.setLegSide(kids[k], side_old[k]);
      bb_.moveLeg(kids[k], kid_old[k]);
    }
  }
  bb_.reshapeTable(id, old.pose, old.width, old.depth, old.leg);
}

double Sampler::drawSideStep(double side) {
  // A local step (a Gaussian of leg_side_sigma), or with probability side_prior_draws a fresh
  // draw from the prior's range. Both kernels are symmetric (q(s' | s) = q(s | s')), so their
  // mixture is: log q ratio 0.
  const ModelParams& p = bb_.params();
  if (opt_.side_prior_draws > 0.0 && rng_.uniform() >= 1.0 - opt_.side_prior_draws)
    return rng_.uniform(p.leg_min, p.leg_max);
  return side + rng_.normal(0, opt_.leg_side_sigma);
}

void Sampler::legSide(int32_t id, double beta) {
  const ModelParams& p = bb_.params();
  const LegHyp l = bb_.leg(id);
  const double side = drawSideStep(l.side);
  const double step = side - l.side;
  if (!p.legSideAllowed(side)) return;
  // The point of the leg's square that stays: its centre, or one of its four corners (each a
  // fifth of the time). A contact fixes the face it lies on, not the leg's centre: whiskers touch
  // a leg from outside, on one face or two adjacent ones, and a side step about the centre moves
  // every face (so a leg born too wide could not shrink without leaving its contacts). About the
  // corner between the touched faces the step keeps both.
  // Under reversible jump the centre: its state space holds each leg in a shapelet's birth box,
  // which a step that moves the centre would have to check, and its exact test holds the leg's
  // pose fixed (detailed_balance_test); the side draw itself is the same.
  const uint32_t anchor = rj() ? 4 : rng_.below(5);
  Pose2 moved = l.pose;
  if (anchor < 4) {
    // Corner i of the leg's square at (+-side/2, +-side/2) in its frame stays put.
    const double sx = (anchor == 0 || anchor == 3) ? 1.0 : -1.0, sy = anchor < 2 ? 1.0 : -1.0;
    const Vec2 shift = Pose2{0, 0, l.pose.theta}.toWorld(Vec2{-0.5 * step * sx, -0.5 * step * sy});
    moved = {l.pose.x + shift.x(), l.pose.y + shift.y(), l.pose.theta};
  }
  // Symmetric: the anchor is drawn independently of the state and the side step is symmetric
  // (drawSideStep); from the new state the same anchor and the negated step give back the old one
  // (the anchor's world position is unchanged by construction). A translation: Jacobian 1.
  [[maybe_unused]] const double log_q_ratio = 0.0;
  Touched t;
  t.legs.add(id);
  t.tables.add(l.parent);
  bb_.shapeletsNear(l.pose.position(), t.shapelets);
  bb_.shapeletsNear(moved.position(), t.shapelets);
  begin();
  const double e0 = bb_.energyBefore(t);
  bb_.moveLeg(id, moved);
  bb_.setLegSide(id, side);
  const double e1 = bb_.energyAfter(t);
  if (decide(e1 - e0, beta)) return;
  bb_.setLegSide(id, l.side);
  bb_.moveLeg(id, l.pose);
}

TableHyp Sampler::reshaped(const TableHyp& t, const Pose2& pose, double width, double depth,
                          double leg) {
  TableHyp r = t;
  r.pose = pose;
  r.width = width;
  r.depth = depth;
  r.leg = leg;
  return r;
}

void Sampler::rjSizeStep(double beta) {
  // One of the three symmetric size steps, on a table or a leg drawn uniformly (the sets' sizes
  // do not change): each is its own reverse with the negated step, ratio 0 (decide() under
  // kReversibleJump), refused outside the prior and the state space.
  const uint32_t which = rng_.below(3);
  if (which == 2) {
    if (const int32_t id = randomLiveLeg(); id != kNone) legSide(id, beta);
    return;
  }
  const int32_t id = randomLiveTable();
  if (id == kNone) return;
  if (which == 0) resizeTable(id, beta);
  else tableLegSide(id, beta);
}

double Sampler::priorSpan(double leg_side, double other) {
  const ModelParams& p = bb_.params();
  // A side drawn uniformly from the prior's range (the shorter side's bound applies when the
  // other side is already long), as a signed centre-to-centre span.
  const double hi = std::abs(other) + leg_side > p.size_max_short ? p.size_max_short
                                                                  : p.size_max_long;
  const double side = rng_.uniform(p.size_min_side, hi);
  return (rng_.uniform() < 0.5 ? -1.0 : 1.0) * (side - leg_side);
}

void Sampler::proposeParentSized(int32_t leg, double beta) {
  const ModelParams& p = bb_.params();
  const LegHyp l = bb_.leg(leg);
  const Vec2 c = l.pose.position();
  // The table's axis: from the rectangle the partners complete (axisFromPartners) when only
  // point contacts support the leg; when oriented ones do, their face gives it half the time and
  // the partners the other half. The physics classifiers' faces scatter by ~25 degrees on legs
  // (docs/TRAINING.md), the rectangle of three legs by a few; a table with a face's axis keeps
  // it, and one with the partners' turns every leg it adopts to its axes (eq. 10's leg-table
  // angle is stiffer than eq. 12's shapelet-leg angle), the acceptance weighing both.
  const bool point = opt_.smart_parent && pointSupported(c);
  const bool from_partners = point || (opt_.smart_parent && rng_.uniform() < 0.5);
  const double axis = from_partners ? axisFromLegs(c, leg, l.pose.theta) : l.pose.theta;
  const Vec2 u{std::cos(axis), std::sin(axis)}, v{-std::sin(axis), std::cos(axis)};
  // Partners: other legs, and point contacts (they come before their legs), around the leg. One
  // on the leg's u axis at a side's span gives the table's side along u; one on its v axis the
  // side along v; one off both axes at spans both sides allow gives the whole rectangle. Spans
  // are centre to centre: a side is its span plus a leg side.
  const double lo = p.size_min_side - l.side, hi = p.size_max_long - l.side;
  const double tol = p.cornerLinkRadius() * 0.5 + 0.5 * p.maxLegSide();
  std::array<double, 8> su{}, sv{}, du{}, dv{};
  int nu = 0, nv = 0, nd = 0;
  const auto consider = [&](const Vec2& q) {
    const double a = (q - c).dot(u), b = (q - c).dot(v);
    const bool a_span = std::abs(a) >= lo && std::abs(a) <= hi;
    const bool b_span = std::abs(b) >= lo && std::abs(b) <= hi;
    if (std::abs(b) < tol && a_span && nu < 8) su[static_cast<size_t>(nu++)] = a;
    else if (std::abs(a) < tol && b_span && nv < 8) sv[static_cast<size_t>(nv++)] = b;
    else if (a_span && b_span && nd < 8) {
      du[static_cast<size_t>(nd)] = a;
      dv[static_cast<size_t>(nd++)] = b;
    }
  };
  if (opt_.smart_parent) {
    bb_.legsNear(c, reach(), [&](int32_t o) {
      const LegHyp& ol = bb_.leg(o);
      if (o != leg && ol.alive) consider(ol.pose.position());
    });
    bb_.shapeletsWithin(c, reach(), [&](int32_t slot) {
      const Shapelet& sh = bb_.shapelet(slot);
      if (!sh.oriented && (Vec2{sh.x, sh.y} - c).norm() > tol) consider({sh.x, sh.y});
    });
  }
  // Candidate rectangles: every u-partner (or a prior draw when there is none) crossed with every
  // v-partner (or a prior draw), and every diagonal partner. Each is weighted as proposeParent weights its
  // placements: 1 plus smart_parent_gain for each of its other corners where a leg or a point
  // contact stands, so the rectangle that the evidence supports at most corners is likeliest
  // (a chair's own legs rather than a leg of the desk beside it).
  // A side no partner gives is drawn from the prior.
  if (nu == 0) su[static_cast<size_t>(nu++)] = priorSpan(l.side, 0.0);
  if (nv == 0) sv[static_cast<size_t>(nv++)] = priorSpan(l.side, su[0]);
  const int mu = nu, mv = nv;
  constexpr int kMaxCand = 8 * 8 + 8;
  std::array<double, kMaxCand> cx, cy, cw;
  int nc = 0;
  double total = 0.0;
  const double r = p.cornerLinkRadius();
  const auto add = [&](double a, double b) {
    const double w = std::abs(a) + l.side, d = std::abs(b) + l.side;
    if (!std::isfinite(p.logSizePrior(w, d, l.side))) return;
    double weight = 1.0;
    if (opt_.smart_parent) {
      // The other three corners: (a, 0), (0, b), (a, b) from the leg.
      const Vec2 corners[3] = {c + a * u, c + b * v, c + a * u + b * v};
      for (const Vec2& k : corners) {
        bool hit = pointNear(k, r);  // a point contact is evidence of a leg there
        if (!hit) {
          bb_.legsNear(k, r, [&](int32_t o) {
            const LegHyp& ol = bb_.leg(o);
            if (o != leg && ol.alive && (ol.pose.position() - k).squaredNorm() <= r * r) hit = true;
          });
        }
        if (hit) weight += opt_.smart_parent_gain;
      }
    }
    cx[static_cast<size_t>(nc)] = a;
    cy[static_cast<size_t>(nc)] = b;
    cw[static_cast<size_t>(nc++)] = weight;
    total += weight;
  };
  for (int i = 0; i < mu; ++i)
    for (int j = 0; j < mv; ++j) add(su[static_cast<size_t>(i)], sv[static_cast<size_t>(j)]);
  for (int i = 0; i < nd; ++i) add(du[static_cast<size_t>(i)], dv[static_cast<size_t>(i)]);
  if (nc == 0) return;  // no rectangle the prior allows
  double pick = rng_.uniform() * total;
  int k = 0;
  while (k < nc - 1 && (pick -= cw[static_cast<size_t>(k)]) >= 0.0) ++k;
  const double sx = cx[static_cast<size_t>(k)], sy = cy[static_cast<size_t>(k)];
  const double w = std::abs(sx) + l.side, d = std::abs(sy) + l.side;
  if (!std::isfinite(p.logSizePrior(w, d, l.side))) return;  // outside the prior: rejected
  const Vec2 centre = c + 0.5 * sx * u + 0.5 * sy * v;
  Pose2 pose{centre.x(), centre.y(), wrapPeriod(axis, kPi)};
  // log_q_ratio is not computed for this move: its forward density is a mixture over the
  // partners found (and the prior draws where none is taken), and its reverse is a table death
  // together with the re-parenting of every adopted leg, which no single move proposes. The
  // paper's proposeParent has the same structure; the reversible-jump change pairs them.

  // As proposeParent: legs at the other corners join the new table in the same move; a table
  // left without legs dies in it; legs only point contacts support turn with the table.
  TableHyp shape;
  shape.pose = pose;
  shape.width = w;
  shape.depth = d;
  shape.leg = l.side;
  IdSet<4> adopt;
  CornerPairs pairs;
  pairs.add(pose.toLocal(c), c);
  if (opt_.smart_parent) {
    for (int corner_i = 0; corner_i < 4; ++corner_i) {
      const Vec2 corner = shape.corner(corner_i);
      adoptAt(bb_, corner, [&] { return pose.toLocal(corner); }, r, leg, adopt, pairs);
    }
  }
  // One table has one leg side: the new table's is the mean of its legs' and they all take it in
  // the same move (legs born with sides drawn from the prior rarely agree, and eq. 10's leg-width
  // term would keep their table from paying). Each leg takes it about the corner of its square
  // farthest from the table's centre: whiskers touch a table's legs from outside its top, so a
  // contact fixes a leg's outer faces, and a side its contacts leave open (an unswept inside)
  // changes the leg inwards. About its centre instead every face moved, off its contacts.
  double side_sum = l.side;
  for (int i = 0; i < adopt.n; ++i) side_sum += bb_.leg(adopt.ids[i]).side;
  const double table_leg = side_sum / (adopt.n + 1);
  const Pose2 unfitted = pose;
  const auto resided = [&](const Pose2& at, double side) {
    const Vec2 q = unfitted.toLocal(at.position());
    const double h = 0.5 * (side - table_leg);
    const Vec2 out =
        unfitted.toWorld(Vec2{q.x() + (q.x() >= 0 ? h : -h), q.y() + (q.y() >= 0 ? h : -h)});
    return Pose2{out.x(), out.y(), at.theta};
  };
  std::array<Pose2, 5> old_pose, new_pose;  // the seed leg's, then the adopted legs'
  std::array<double, 5> old_side;
  old_pose[0] = l.pose;
  old_side[0] = l.side;
  for (int i = 0; i < adopt.n; ++i) {
    old_pose[static_cast<size_t>(i + 1)] = bb_.leg(adopt.ids[i]).pose;
    old_side[static_cast<size_t>(i + 1)] = bb_.leg(adopt.ids[i]).side;
  }
  for (int i = 0; i <= adopt.n; ++i) {
    const auto j = static_cast<size_t>(i);
    new_pose[j] = resided(old_pose[j], old_side[j]);
    pairs.at[j] = new_pose[j].position();  // pairs: the seed's, then the adopted legs' in order
  }
  // The spans from centre to centre, between the legs as re-sided: along each axis, the mean
  // over the adopted legs across the table from the seed leg, or the drawn span moved with the
  // seed's centre where none stands there. The top is then its legs' outline.
  const Vec2 seed_at = unfitted.toLocal(new_pose[0].position());
  double span[2] = {std::abs(sx) + 0.5 * (old_side[0] - table_leg),
                    std::abs(sy) + 0.5 * (old_side[0] - table_leg)};
  for (int ax = 0; ax < 2; ++ax) {
    double sum = 0.0;
    int n_far = 0;
    for (int i = 1; i <= adopt.n; ++i) {
      const Vec2 q = unfitted.toLocal(new_pose[static_cast<size_t>(i)].position());
      const double off = ax == 0 ? q.x() - seed_at.x() : q.y() - seed_at.y();
      const double half = 0.5 * (ax == 0 ? std::abs(sx) : std::abs(sy));
      if (std::abs(off) > half) {
        sum += std::abs(off);
        ++n_far;
      }
    }
    if (n_far > 0) span[ax] = sum / n_far;
  }
  const double tw = span[0] + table_leg, td = span[1] + table_leg;
  if (!std::isfinite(p.logSizePrior(tw, td, table_leg))) return;
  // Each pair's corner of the top so sized (the same corner: the signs of its offset).
  for (int i = 0; i < pairs.n; ++i) {
    const Vec2 o = pairs.local[static_cast<size_t>(i)];
    pairs.local[static_cast<size_t>(i)] = {std::copysign(0.5 * span[0], o.x()),
                                           std::copysign(0.5 * span[1], o.y())};
  }
  // As proposeParent: the table where its corners fit its legs best, its legs turned to it.
  const bool fitted = opt_.fit_parent && adopt.n > 0;
  if (fitted) pose = pairs.fit(pose.theta);
  const Turn turn = (fitted || from_partners) ? Turn::kAll : Turn::kNoLeg;
  std::array<int32_t, 4> adopt_parent;
  Touched t;
  t.legs.add(leg);
  t.tables.add(l.parent);
  bb_.shapeletsNear(c, t.shapelets);
  bb_.shapeletsNear(new_pose[0].position(), t.shapelets);
  for (int i = 0; i < adopt.n; ++i) {
    adopt_parent[static_cast<size_t>(i)] = bb_.leg(adopt.ids[i]).parent;
    t.legs.add(adopt.ids[i]);
    t.tables.add(adopt_parent[static_cast<size_t>(i)]);
    bb_.shapeletsNear(old_pose[static_cast<size_t>(i + 1)].position(), t.shapelets);
    bb_.shapeletsNear(new_pose[static_cast<size_t>(i + 1)].position(), t.shapelets);
  }
  for (int32_t tab : t.tables.span())
    for (int i = 0; i < bb_.table(tab).n_children; ++i) t.legs.add(bb_.table(tab).children[i]);
  // A leg that turns with the table changes its shapelets' kernels.
  if (turn == Turn::kAll)
    for (int32_t o : t.legs.span()) bb_.shapeletsNear(bb_.leg(o).pose.position(), t.shapelets);
  begin();
  const double e0 = bb_.energyBefore(t);
  const int32_t table = bb_.addTable(pose, tw, td, table_leg);
  const auto take = [&](int32_t o, size_t slot) {
    bb_.moveLeg(o, new_pose[slot]);
    bb_.setLegSide(o, table_leg);
    bb_.setParent(o, table);
  };
  take(leg, 0);
  for (int i = 0; i < adopt.n; ++i) take(adopt.ids[i], static_cast<size_t>(i + 1));
  if (decideNewTable(table, pose, turn, t, e0, beta)) return;
  const auto give_back = [&](int32_t o, size_t slot, int32_t parent) {
    bb_.setParent(o, parent);
    bb_.setLegSide(o, old_side[slot]);
    bb_.moveLeg(o, old_pose[slot]);
  };
  give_back(leg, 0, l.parent);
  for (int i = 0; i < adopt.n; ++i)
    give_back(adopt.ids[i], static_cast<size_t>(i + 1), adopt_parent[static_cast<size_t>(i)]);
  bb_.killTable(table);
  bb_.releaseTable(table);
}

}  // namespace crunch
