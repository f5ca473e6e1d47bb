#include "crunch/blackboard/sampler.h"

#include <algorithm>
#include <array>
#include <cmath>

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
      checkRange("wall_birth_rate", wall_birth_rate, 0.0, 1.0),
      checkRange("wall_grow_gap", wall_grow_gap, 0.0, 10.0),
      checkRange("wall_jitter_r", wall_jitter_r, 0.0, 10.0),
      checkRange("wall_jitter_theta", wall_jitter_theta, 0.0, kPi),
      checkRange("wall_end_sigma", wall_end_sigma, 0.0, 10.0),
      checkRange("wall_split_gap", wall_split_gap, 0.0, 10.0),
      checkRange("wall_merge_reach", wall_merge_reach, 0.0, 10.0)};
  for (const Status& s : checks) {
    if (!s) return s;
  }
  return okStatus();
}

Sampler::Sampler(Blackboard& board, const SamplerOptions& options, Rng& rng)
    : bb_(board), opt_(options), rng_(rng) {
  for (int i = opt_.schedule_steps - 1; i >= 0; --i)
    betas_.push_back(std::exp(opt_.schedule_log_top - opt_.schedule_log_step * i));
  order_.reserve(4096);
  if (walls()) {
    wall_slots_.reserve(static_cast<size_t>(bb_.workingMemoryCapacity()));
    inliers_.reserve(static_cast<size_t>(bb_.workingMemoryCapacity()));
  }
}

void Sampler::anneal() {
  for (std::size_t step = 0; step < betas_.size(); ++step) {
    const double beta = betas_[step];
    for (int s = 0; s < opt_.sweeps_per_temperature; ++s) sweep(beta);
    if (opt_.prune) prune();
    if (opt_.after_temperature) opt_.after_temperature(static_cast<int>(step), beta, bb_);
  }
}

void Sampler::sweep(double beta) {
  for (int slot = 0; slot < bb_.workingMemoryCapacity(); ++slot)
    if (bb_.slotUsed(slot)) primeLeg(slot, beta);
  if (walls()) {
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

  for (const Ref& h : order_) {
    if (h.is_wall) {
      if (bb_.wall(h.id).alive) wallMove(h.id, beta);
      continue;
    }
    const double r = rng_.uniform();
    if (h.is_table) {
      if (!bb_.table(h.id).alive) continue;
      if (r < opt_.r1) deathTable(h.id, beta);
      else if (r < opt_.r3 && r >= opt_.r2) proposeChild(h.id, beta);
      else jitterTable(h.id, beta);  // tables have only the null parent
    } else {
      if (!bb_.leg(h.id).alive) continue;
      if (r < opt_.r1) deathLeg(h.id, beta);
      else if (r < opt_.r2) parentChange(h.id, beta);
      else if (r < opt_.r3) jitterLeg(h.id, beta);  // a leg's children are observations
      else proposeParent(h.id, beta);
    }
  }
}

void Sampler::begin() {
  if (audit_) audit_before_ = bb_.totalEnergy();
}

bool Sampler::decide(double delta, double beta) {
  if (audit_) {
    const double err = std::abs((bb_.totalEnergy() - audit_before_) - delta);
    stats_.audit_max_error = std::max(stats_.audit_max_error, err);
  }
  ++stats_.proposals;
  const double a = opt_.acceptance == Acceptance::kTempered ? temperedAcceptance(delta, beta)
                                                            : literalAcceptance(delta, beta);
  const bool ok = rng_.uniform() < a;
  stats_.accepted += ok;
  return ok;
}

int32_t Sampler::sampleParent(const LegHyp& leg, int32_t exclude) {
  const ModelParams& p = bb_.params();
  constexpr int kMaxCand = 16;
  std::array<int32_t, kMaxCand> cand;
  std::array<double, kMaxCand> weight;
  int n = 0;
  cand[n] = kNone;
  weight[n++] = exclude == kNone ? 0.0 : p.c_L;
  const double reach = bb_.tableRect({}).circumradius() + p.cornerLinkRadius();
  const double cut = p.link_sigmas * p.link_sigmas;
  bb_.tablesNear(leg.pose.position(), reach, [&](int32_t t) {
    const TableHyp& tab = bb_.table(t);
    if (t == exclude || !tab.alive || n >= kMaxCand || tab.n_children >= kMaxChildren) return;
    const double d = deltaTL(tab.pose, leg, p, nullptr);
    if (d > cut) return;
    cand[n] = t;
    weight[n++] = p.alpha_L * std::exp(-d);
  });
  double total = 0.0;
  for (int i = 0; i < n; ++i) total += weight[i];
  if (total <= 0.0) return exclude;
  double u = rng_.uniform() * total;
  for (int i = 0; i < n; ++i) {
    if ((u -= weight[i]) < 0.0) return cand[i];
  }
  return cand[n - 1];
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
  if (!legCanCause(bb_.params().leg_side, s)) return;  // no leg's face is that long
  LegHyp probe;
  probe.pose = s.oriented ? legOnFace(s) : legAtPoint(s);
  probe.side = bb_.params().leg_side;
  const int32_t parent = sampleParent(probe, kNone);
  proposeLegBirth(probe.pose, parent, beta);
}

Pose2 Sampler::legOnFace(const Shapelet& s) {
  const ModelParams& p = bb_.params();
  const double half = 0.5 * p.leg_side;
  const Vec2 along{std::cos(s.phi), std::sin(s.phi)};
  const Vec2 in = inwardNormal(s);
  // Q(pa(S)): a leg whose face passes through the shapelet. Where another shapelet nearby lies on
  // a perpendicular face, place the leg touching both (a corner fit); otherwise anywhere along
  // the face.
  int partner = -1;
  if (opt_.smart_parent) {
    IdSet<64> near;
    bb_.shapeletsNear({s.x, s.y}, near);
    for (int32_t o : near.span()) {
      const Shapelet& so = bb_.shapelet(o);
      if (!so.oriented || std::abs(wrapPeriod(so.phi - s.phi, kPi)) < kPi / 4) continue;
      if (std::hypot(so.x - s.x, so.y - s.y) > 2.0 * p.leg_side) continue;
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

Pose2 Sampler::legAtPoint(const Shapelet& s) {
  // An edge or point contact (no orientation): the leg lies beyond the point as seen from the
  // whisker, its centre between a face's and a corner's distance from it, turned as the legs
  // already believed around it say (axisFromLegs), or any way.
  const ModelParams& p = bb_.params();
  const double half = 0.5 * p.leg_side;
  Vec2 away = Vec2{s.x - s.ox, s.y - s.oy};
  away = away.norm() > 0.0 ? Vec2(away.normalized()) : Vec2{1.0, 0.0};
  const Vec2 c = Vec2{s.x, s.y} + rng_.uniform(half, half * std::sqrt(2.0)) * away +
                 Vec2{rng_.normal(0, opt_.prime_sigma_r), rng_.normal(0, opt_.prime_sigma_r)};
  const double theta = axisFromLegs(c, -1, rng_.uniform(0.0, kPi / 2)) +
                       rng_.normal(0, opt_.prime_sigma_theta);
  return {c.x(), c.y(), wrapPeriod(theta, kPi / 2)};
}

double Sampler::axisFromLegs(const Vec2& c, int32_t self, double fallback) {
  // Another leg, or a point contact, at a table side's or diagonal's distance from c gives the
  // table's axes (modulo pi/2) as a table would hold both; each such partner is equally likely
  // to be chosen. Point contacts count as well as legs: they are there before their legs are.
  const ModelParams& p = bb_.params();
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
  bb_.legsNear(c, diag + tol, [&](int32_t o) {
    const LegHyp& l = bb_.leg(o);
    if (o != self && l.alive) consider(l.pose.position());
  });
  bb_.shapeletsWithin(c, diag + tol, [&](int32_t slot) {
    const Shapelet& sh = bb_.shapelet(slot);
    if (!sh.oriented) consider({sh.x, sh.y});
  });
  return axis;
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
  IdSet<64> near;
  bb_.shapeletsNear(c, near);
  bool any = false;
  for (int32_t o : near.span()) {
    if (bb_.shapelet(o).oriented) return false;
    any = true;
  }
  return any;
}

void Sampler::proposeLegBirth(const Pose2& pose, int32_t parent, double beta) {
  Touched t;
  t.tables.add(parent);
  bb_.shapeletsNear(pose.position(), t.shapelets);
  begin();
  const double e0 = bb_.localEnergy(t);
  const int32_t id = bb_.addLeg(pose, parent);
  t.legs.add(id);
  const double e1 = bb_.localEnergy(t);
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
  const double e0 = bb_.localEnergy(t);
  bb_.killLeg(id);
  const double e1 = bb_.localEnergy(t);
  if (decide(e1 - e0, beta)) bb_.releaseLeg(id);
  else bb_.reviveLeg(id);
}

void Sampler::deathTable(int32_t id, double beta) {
  Touched t;
  t.tables.add(id);
  const TableHyp& tab = bb_.table(id);
  for (int i = 0; i < tab.n_children; ++i) t.legs.add(tab.children[i]);
  begin();
  const double e0 = bb_.localEnergy(t);
  bb_.killTable(id);
  const double e1 = bb_.localEnergy(t);
  if (decide(e1 - e0, beta)) bb_.releaseTable(id);
  else bb_.reviveTable(id);
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
  const double e0 = bb_.localEnergy(t);
  bb_.setParent(leg, new_parent);
  const double e1 = bb_.localEnergy(t);
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
  const double e0 = bb_.localEnergy(t);
  bb_.moveLeg(id, moved);
  const double e1 = bb_.localEnergy(t);
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
  const double e0 = bb_.localEnergy(t);
  bb_.moveTable(id, moved);
  if (rigid)
    for (int i = 0; i < n; ++i)
      bb_.moveLeg(kids[static_cast<size_t>(i)], carried(kid_old[static_cast<size_t>(i)]));
  const double e1 = bb_.localEnergy(t);
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
  const Vec2 c = tab.pose.toWorld(bb_.params().cornerOffset(corner));
  proposeLegBirth({c.x(), c.y(), wrapPeriod(tab.pose.theta, kPi / 2)}, table, beta);
}

void Sampler::proposeParent(int32_t leg, double beta) {
  const ModelParams& p = bb_.params();
  const LegHyp l = bb_.leg(leg);
  // A leg only point contacts support has no orientation of its own: the table's axes come from
  // the legs at a side's or diagonal's distance, and the legs so supported that the table takes
  // turn with it (below).
  const bool free_turn = opt_.smart_parent && pointSupported(l.pose.position());
  const double axis = free_turn ? axisFromLegs(l.pose.position(), leg, l.pose.theta) : l.pose.theta;
  // The 8 table placements with this leg at a corner: 2 orientations (modulo pi) x 4 corners.
  std::array<Pose2, 8> place;
  std::array<double, 8> weight;
  double total = 0.0;
  for (int k = 0; k < 8; ++k) {
    const double th = wrapPeriod(axis + (k / 4) * (kPi / 2), kPi);
    const Pose2 frame{0, 0, th};
    const Vec2 off = frame.toWorld(p.cornerOffset(k % 4));
    place[static_cast<size_t>(k)] = {l.pose.x - off.x(), l.pose.y - off.y(), th};
    double w = 1.0;
    if (opt_.smart_parent) {
      for (int c = 0; c < 4; ++c) {
        if (c == k % 4) continue;
        const Vec2 corner = place[static_cast<size_t>(k)].toWorld(p.cornerOffset(c));
        bb_.legsNear(corner, p.cornerLinkRadius(), [&](int32_t o) {
          const LegHyp& ol = bb_.leg(o);
          if (o != leg && ol.alive &&
              (ol.pose.position() - corner).squaredNorm() <= std::pow(p.cornerLinkRadius(), 2))
            w += opt_.smart_parent_gain;
        });
        // A point contact on a leg at that corner (within a leg's half-diagonal of it) counts
        // as that leg would: it is the evidence a leg there will explain.
        if (free_turn && pointNear(corner, p.cornerLinkRadius())) w += opt_.smart_parent_gain;
      }
    }
    weight[static_cast<size_t>(k)] = w;
    total += w;
  }
  double u = rng_.uniform() * total;
  int k = 0;
  while (k < 7 && (u -= weight[static_cast<size_t>(k)]) >= 0.0) ++k;
  const Pose2 pose = place[static_cast<size_t>(k)];

  // Legs already at the other corners join the new table in the same move, taken from their
  // old table if they had one; an old table left without legs dies in the same move. This is the
  // jump between the rival tables T1 and T2 of Fig. 5, which single-hypothesis moves can only
  // make through a deep valley of two overlapping tables.
  IdSet<4> adopt;
  if (opt_.smart_parent) {
    for (int c = 0; c < 4; ++c) {
      const Vec2 corner = pose.toWorld(p.cornerOffset(c));
      bb_.legsNear(corner, p.cornerLinkRadius(), [&](int32_t o) {
        const LegHyp& ol = bb_.leg(o);
        if (o != leg && ol.alive &&
            (ol.pose.position() - corner).squaredNorm() <= std::pow(p.cornerLinkRadius(), 2))
          adopt.add(o);
      });
    }
  }
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
  begin();
  const double e0 = bb_.localEnergy(t);
  const int32_t table = bb_.addTable(pose);
  bb_.setParent(leg, table);
  for (int32_t o : adopt.span()) bb_.setParent(o, table);
  // Legs whose orientation nothing but their table constrains turn with it.
  IdSet<5> turned;
  std::array<Pose2, 5> turned_from;
  if (free_turn) {
    for (int32_t o : t.legs.span()) {
      if (bb_.leg(o).parent != table || !pointSupported(bb_.leg(o).pose.position())) continue;
      turned_from[static_cast<size_t>(turned.n)] = bb_.leg(o).pose;
      turned.add(o);
      Pose2 q = bb_.leg(o).pose;
      q.theta = wrapPeriod(pose.theta, kPi / 2);
      bb_.moveLeg(o, q);
    }
  }
  IdSet<8> emptied;
  for (int32_t tab : t.tables.span()) {
    if (bb_.table(tab).n_children == 0) {
      emptied.add(tab);
      bb_.killTable(tab);
    }
  }
  t.tables.add(table);
  const double e1 = bb_.localEnergy(t);
  if (decide(e1 - e0, beta)) {
    for (int32_t tab : emptied.span()) bb_.releaseTable(tab);
    return;
  }
  for (int i = 0; i < turned.n; ++i) bb_.moveLeg(turned.ids[i], turned_from[static_cast<size_t>(i)]);
  for (int32_t tab : emptied.span()) bb_.reviveTable(tab);
  bb_.setParent(leg, l.parent);
  for (int i = 0; i < adopt.n; ++i) bb_.setParent(adopt.ids[i], adopt_parent[static_cast<size_t>(i)]);
  bb_.killTable(table);
  bb_.releaseTable(table);
}

bool Sampler::legDirectlyLinked(int32_t leg) const {
  IdSet<64> near;
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

void Sampler::mapTables(std::vector<Pose2>& out) const {
  out.clear();
  for (int32_t id = 0; id < bb_.tableExtent(); ++id)
    if (bb_.table(id).alive) out.push_back(bb_.table(id).pose);
}

}  // namespace crunch
