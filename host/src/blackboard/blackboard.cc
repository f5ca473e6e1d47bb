#include "crunch/blackboard/blackboard.h"

#include <cassert>
#include <algorithm>
#include <cmath>
#include <limits>

namespace crunch {

namespace {
// Buckets: at least 4096, and about two per expected item, so distinct cells rarely share one
// as the floor grows (docs/BENCHMARKS.md: a fixed 4096 doubled the cost per proposal at 1e4).
int log2Buckets(size_t expected) {
  int b = 12;
  while (b < 24 && (size_t{1} << b) < 2 * expected) ++b;
  return b;
}
// Cell sides: about the reach of the look-ups each hash serves.
constexpr double kTableCell = 1.0;
constexpr double kLegCell = 0.2;
constexpr double kShapeletCell = 0.2;
// Walls are hashed at points this far apart along them.
constexpr double kWallCell = kWallHashStep;
}  // namespace

Blackboard::Blackboard(const ModelParams& params, int working_memory, size_t reserve)
    : p_(params),
      tables_(reserve),
      legs_(reserve),
      table_hash_(kTableCell, log2Buckets(reserve)),
      leg_hash_(kLegCell, log2Buckets(reserve)),
      shapelet_hash_(kShapeletCell, log2Buckets(static_cast<size_t>(working_memory))),
      wm_(static_cast<size_t>(working_memory)),
      wm_used_(static_cast<size_t>(working_memory), false),

      log_eps_a_(std::log(params.eps_a)),
      log_eps_b_(std::log(params.eps_b)),
      log_eps_c_(std::log(params.eps_c)),
      table_odds_(logPresenceOdds(std::log(params.c_T), params)),
      logs_(params),
      orphan_leg_odds_(logPresenceOdds(logs_.c_L, logs_)),
      paper_table_radius_(OrientedRect{{}, params.table_width, params.table_depth}.circumradius()),
      max_table_radius_(params.maxTableCircumradius()),
      max_leg_side_(params.maxLegSide()),
      shapelet_link_r_(params.shapeletLinkRadius()),
      wall_link_r_(params.wallLinkRadius()),
      walls_(params.walled() ? 256 : 0),
      wall_hash_(kWallCell, params.walled() ? 11 : 4,
                 params.walled() ? 8 : 0),
      slot_stamp_(static_cast<size_t>(working_memory), 0),
      wall_odds_(logPresenceOdds(std::log(params.c_W), params)),
      log_free_wall_end_(params.walled() ? params.logFreeWallEnd() : 0.0),
      slot_term_(static_cast<size_t>(working_memory), 0.0),
      slot_gen_(static_cast<size_t>(working_memory), 0) {
  assert(working_memory > 0);
  // A move's shapelets: its Touched set and, for a wall's move, up to every slot besides.
  kept_slots_.reserve(static_cast<size_t>(working_memory) + kMaxBlanketShapelets);
}

// ---------------------------------------------------------------- working memory

int Blackboard::pushShapelet(const Shapelet& s) {
  ++wm_gen_;
  const int slot = wm_next_;
  const auto i = static_cast<size_t>(slot);
  if (wm_used_[i]) {
    shapelet_hash_.remove(slot, {wm_[i].x, wm_[i].y});
    wm_points_ -= !wm_[i].oriented;
  } else {
    ++wm_count_;
  }
  wm_points_ += !s.oriented;
  wm_[i] = s;
  wm_used_[i] = true;
  slot_gen_[i] = 0;  // its cached term, if any, was the evicted shapelet's
  shapelet_hash_.insert(slot, {s.x, s.y});
  wm_next_ = (wm_next_ + 1) % static_cast<int>(wm_.size());
  return slot;
}

void Blackboard::clearShapelets() {
  ++gen_;
  ++wm_gen_;
  shapelet_hash_.clear();
  std::fill(wm_used_.begin(), wm_used_.end(), false);
  wm_next_ = 0;
  wm_count_ = 0;
  wm_points_ = 0;
}

void Blackboard::shapeletsNear(const Vec2& p, ShapeletSet& out) const {
  const double r = shapelet_link_r_;
  shapelet_hash_.query(p, r, [&](int32_t slot) {
    const Shapelet& s = wm_[static_cast<size_t>(slot)];
    if ((Vec2{s.x, s.y} - p).squaredNorm() <= r * r) out.add(slot);
  });
}

bool Blackboard::shapeletNear(const Vec2& p) const {
  const double r = shapelet_link_r_;
  bool found = false;
  shapelet_hash_.query(p, r, [&](int32_t slot) {
    const Shapelet& s = wm_[static_cast<size_t>(slot)];
    found = found || (Vec2{s.x, s.y} - p).squaredNorm() <= r * r;
  });
  return found;
}

// ---------------------------------------------------------------- hypotheses

void Blackboard::setTablePose(TableHyp& t, const Pose2& pose) {
  t.pose = pose;
  t.trig = {std::cos(pose.theta), std::sin(pose.theta), tableRect(t).circumradius()};
}

void Blackboard::setLegPose(LegHyp& l, const Pose2& pose) {
  l.pose = pose;
  l.trig = {std::cos(pose.theta), std::sin(pose.theta), legRect(l).circumradius()};
}

void Blackboard::setLegSide(int32_t id, double side) {
  mutated();
  LegHyp& l = legs_[id];
  l.side = side;
  l.trig.radius = legRect(l).circumradius();
}

int32_t Blackboard::addTable(const Pose2& pose) {
  return addTable(pose, p_.table_width, p_.table_depth, p_.leg_side);
}

int32_t Blackboard::addTable(const Pose2& pose, double width, double depth, double leg) {
  mutated();
  const int32_t id = tables_.acquire();
  TableHyp& t = tables_[id];
  t.width = width;
  t.depth = depth;
  t.leg = leg;
  setTablePose(t, pose);
  t.alive = true;
  table_hash_.insert(id, pose.position());
  ++live_tables_;
  return id;
}

int32_t Blackboard::addLeg(const Pose2& pose, int32_t parent) {
  return addLeg(pose, p_.leg_side, parent);
}

int32_t Blackboard::addLeg(const Pose2& pose, double side, int32_t parent) {
  mutated();
  const int32_t id = legs_.acquire();
  LegHyp& l = legs_[id];
  l.side = side;
  setLegPose(l, pose);
  l.alive = true;
  leg_hash_.insert(id, pose.position());
  ++live_legs_;
  if (parent != kNone) linkChild(parent, id);
  return id;
}

int Blackboard::nearestCorner(const TableHyp& table, const LegHyp& leg) const {
  int corner = 0;
  deltaTLHeld(table, leg, p_, &corner);
  return corner;
}

void Blackboard::linkChild(int32_t table, int32_t leg) {
  TableHyp& t = tables_[table];
  LegHyp& l = legs_[leg];
  assert(t.alive && t.n_children < kMaxChildren);
  const int corner = nearestCorner(t, l);
  l.parent = table;
  l.corner = static_cast<int8_t>(corner);
  t.children[t.n_children++] = leg;
  ++t.corner_count[static_cast<size_t>(corner)];
}

void Blackboard::unlinkChild(int32_t table, int32_t leg) {
  TableHyp& t = tables_[table];
  LegHyp& l = legs_[leg];
  for (int i = 0; i < t.n_children; ++i) {
    if (t.children[i] == leg) {
      t.children[i] = t.children[--t.n_children];
      break;
    }
  }
  --t.corner_count[static_cast<size_t>(l.corner)];
  l.parent = kNone;
  l.corner = -1;
}

void Blackboard::killTable(int32_t id) {
  mutated();
  TableHyp& t = tables_[id];
  assert(t.alive);
  t.alive = false;
  table_hash_.remove(id, t.pose.position());
  --live_tables_;
  // Orphan the children but keep the list for reviveTable().
  for (int i = 0; i < t.n_children; ++i) {
    LegHyp& l = legs_[t.children[i]];
    l.parent = kNone;
    l.corner = -1;
  }
}

void Blackboard::reviveTable(int32_t id) {
  mutated();
  TableHyp& t = tables_[id];
  assert(!t.alive);
  t.alive = true;
  table_hash_.insert(id, t.pose.position());
  ++live_tables_;
  const int n = t.n_children;
  t.n_children = 0;
  t.corner_count = {};
  for (int i = 0; i < n; ++i) linkChild(id, t.children[i]);
}

void Blackboard::killLeg(int32_t id) {
  mutated();
  LegHyp& l = legs_[id];
  assert(l.alive);
  const int32_t parent = l.parent;
  if (parent != kNone) unlinkChild(parent, id);
  l.parent = parent;  // remembered for reviveLeg()
  l.alive = false;
  leg_hash_.remove(id, l.pose.position());
  --live_legs_;
}

void Blackboard::reviveLeg(int32_t id) {
  mutated();
  LegHyp& l = legs_[id];
  assert(!l.alive);
  l.alive = true;
  leg_hash_.insert(id, l.pose.position());
  ++live_legs_;
  const int32_t parent = l.parent;
  l.parent = kNone;
  if (parent != kNone) linkChild(parent, id);
}

void Blackboard::setParent(int32_t leg, int32_t parent) {
  mutated();
  LegHyp& l = legs_[leg];
  if (l.parent == parent) return;
  if (l.parent != kNone) unlinkChild(l.parent, leg);
  if (parent != kNone) linkChild(parent, leg);
}

void Blackboard::moveTable(int32_t id, const Pose2& pose) {
  const TableHyp& t = tables_[id];
  reshapeTable(id, pose, t.width, t.depth, t.leg);
}

void Blackboard::reshapeTable(int32_t id, const Pose2& pose, double width, double depth,
                              double leg) {
  mutated();
  TableHyp& t = tables_[id];
  table_hash_.remove(id, t.pose.position());
  t.width = width;
  t.depth = depth;
  t.leg = leg;
  setTablePose(t, pose);
  table_hash_.insert(id, pose.position());
  // Children keep their parent; their nearest corners may change.
  t.corner_count = {};
  for (int i = 0; i < t.n_children; ++i) {
    LegHyp& l = legs_[t.children[i]];
    l.corner = static_cast<int8_t>(nearestCorner(t, l));
    ++t.corner_count[static_cast<size_t>(l.corner)];
  }
}

void Blackboard::moveLeg(int32_t id, const Pose2& pose) {
  mutated();
  LegHyp& l = legs_[id];
  leg_hash_.remove(id, l.pose.position());
  setLegPose(l, pose);
  leg_hash_.insert(id, pose.position());
  if (l.parent != kNone) {
    TableHyp& t = tables_[l.parent];
    --t.corner_count[static_cast<size_t>(l.corner)];
    l.corner = static_cast<int8_t>(nearestCorner(t, l));
    ++t.corner_count[static_cast<size_t>(l.corner)];
  }
}

// ---------------------------------------------------------------- walls

template <typename F>
void Blackboard::wallHashPoints(const Vec2& a, const Vec2& b, F&& f) const {
  const double len = (b - a).norm();
  const int n = std::max(1, static_cast<int>(std::ceil(len / kWallCell)));
  for (int k = 0; k <= n; ++k) f(Vec2(a + (b - a) * (static_cast<double>(k) / n)));
}

int32_t Blackboard::addWall(const Vec2& a, const Vec2& b) {
  mutated();
  const int32_t id = walls_.acquire();
  WallHyp& w = walls_[id];
  w.a = a;
  w.b = b;
  w.alive = true;
  wallHashPoints(a, b, [&](const Vec2& q) { wall_hash_.insert(id, q); });
  ++live_walls_;
  return id;
}

void Blackboard::killWall(int32_t id) {
  mutated();
  WallHyp& w = walls_[id];
  assert(w.alive);
  w.alive = false;
  wallHashPoints(w.a, w.b, [&](const Vec2& q) { wall_hash_.remove(id, q); });
  --live_walls_;
}

void Blackboard::reviveWall(int32_t id) {
  mutated();
  WallHyp& w = walls_[id];
  assert(!w.alive);
  w.alive = true;
  wallHashPoints(w.a, w.b, [&](const Vec2& q) { wall_hash_.insert(id, q); });
  ++live_walls_;
}

void Blackboard::moveWall(int32_t id, const Vec2& a, const Vec2& b) {
  mutated();
  WallHyp& w = walls_[id];
  assert(w.alive);
  wallHashPoints(w.a, w.b, [&](const Vec2& q) { wall_hash_.remove(id, q); });
  w.a = a;
  w.b = b;
  wallHashPoints(a, b, [&](const Vec2& q) { wall_hash_.insert(id, q); });
}

void Blackboard::beginCollect() {
  if (++stamp_ == 0) {  // wrapped: clear the marks once
    std::fill(slot_stamp_.begin(), slot_stamp_.end(), 0u);
    stamp_ = 1;
  }
}

void Blackboard::collectShapeletsNearSegment(const Vec2& a, const Vec2& b,
                                             std::vector<int32_t>& out) {
  const double r = wall_link_r_;
  const double len = (b - a).norm();
  const int n = std::max(1, static_cast<int>(std::ceil(len / kShapeletCell)));
  const double reach = 0.5 * len / n + r;
  for (int k = 0; k <= n; ++k) {
    const Vec2 c = a + (b - a) * (static_cast<double>(k) / n);
    shapelet_hash_.query(c, reach, [&](int32_t slot) {
      uint32_t& mark = slot_stamp_[static_cast<size_t>(slot)];
      if (mark == stamp_) return;
      const Shapelet& s = wm_[static_cast<size_t>(slot)];
      if (distanceToSegment({s.x, s.y}, a, b) > r) return;
      mark = stamp_;
      assert(out.size() < out.capacity());
      out.push_back(slot);
    });
  }
}

void Blackboard::collectShapeletsNearLeg(int32_t leg, std::vector<int32_t>& out) {
  const Vec2 c = legs_[leg].pose.position();
  const double r = shapelet_link_r_;
  shapelet_hash_.query(c, r, [&](int32_t slot) {
    uint32_t& mark = slot_stamp_[static_cast<size_t>(slot)];
    if (mark == stamp_) return;
    const Shapelet& s = wm_[static_cast<size_t>(slot)];
    if ((Vec2{s.x, s.y} - c).squaredNorm() > r * r) return;
    mark = stamp_;
    assert(out.size() < out.capacity());
    out.push_back(slot);
  });
}

double Blackboard::wallFreeTerm(const Vec2& a, const Vec2& b) const {
  if (!free_) return 0.0;
  // A piece of wall is crossed by a ray that passed both lines free_margin either side of it
  // (a whisker whose tip stopped within the margin, or grazed the wall, does not count).
  const double len = (b - a).norm();
  if (len <= 0.0) return 0.0;
  const Vec2 dir = (b - a) / len;
  const Vec2 nrm{-dir.y(), dir.x()};
  const double m = std::max(p_.free_margin, free_->cell());
  const int pieces = std::max(1, static_cast<int>(std::ceil(len / p_.leg_side)));
  const double piece = len / pieces;
  const int steps = std::max(1, static_cast<int>(std::ceil(piece / free_->cell())));
  double e = 0.0;
  const double log_miss = logs_.p_miss;
  const int cap = p_.free_pass_cap;
  for (int i = 0; i < pieces; ++i) {
    int best = 0;
    // The piece's term reads min(best, cap): stop once it reaches the cap. Each sample reads
    // the solid side first (right of a->b, -nrm: behind a real wall no ray passed, so mostly
    // 0), and the free side only when the solid side could raise best.
    for (int k = 0; k < steps && best < cap; ++k) {
      const Vec2 q = a + dir * (piece * (i + (k + 0.5) / steps));
      const int behind = free_->count(q - m * nrm);
      if (behind <= best) continue;
      best = std::max(best, std::min(free_->count(q + m * nrm), behind));
    }
    e += std::min(best, cap) * log_miss;
  }
  return e;
}

bool Blackboard::inWallSolid(const OrientedRect& r, const WallHyp& w) const {
  const double len = w.length();
  if (len <= 0.0) return false;
  // Two ways to share space with a wall, both within its extent:
  //  - behind its surface (the centre on the solid side) and reaching into the band
  //    [0, wall_solid_depth] behind it: a thing beyond a thin wall does not count;
  //  - in front of it (the centre on the free side) and reaching past that band: through the
  //    wall's least thickness, which no table top or leg can do. A thing standing against the
  //    free face with a fit a little too deep (the two fits' noise, millimetres) is not charged.
  // The second rule closes what the first left open: a table whose near legs were touched and
  // whose far half stands through the arena's wall (its far legs never touchable, so nothing
  // denied them) kept its centre in front and paid nothing.
  const Vec2 n = w.solidNormal();
  const double d = p_.wall_solid_depth;
  const double centre_depth = (r.pose.position() - w.a).dot(n);
  if (centre_depth > 0.0) {
    const Vec2 c = 0.5 * (w.a + w.b) + (0.5 * d) * n;
    return overlaps(r, OrientedRect{{c.x(), c.y(), w.angle()}, len, d});
  }
  // Past the band: from depth d to the deepest r can reach (its half-diagonal past its centre).
  const double deepest = centre_depth + 0.5 * std::hypot(r.size_x, r.size_y);
  if (deepest <= d) return false;
  const Vec2 c = 0.5 * (w.a + w.b) + (0.5 * (d + deepest)) * n;
  return overlaps(r, OrientedRect{{c.x(), c.y(), w.angle()}, len, deepest - d});
}

double Blackboard::wallTerms(int32_t id, const Touched& t) const {
  (void)t;
  const WallHyp& w = walls_[id];
  if (!w.alive) return 0.0;
  return wallPairTerms(id, wallOwnTerm(w));
}

double Blackboard::wallOwnTerm(const WallHyp& w) const {
  return wall_odds_ - p_.wall_cost_per_m * w.length() + wallFreeTerm(w.a, w.b);
}

double Blackboard::wallPairTerms(int32_t id, double own) const {
  const WallHyp& w = walls_[id];
  double e = own;
  // Tables and legs intruding into its solid, counted here for every one; tableTerms() and
  // legTerms() skip the walls a move touches.
  const double band = p_.wall_solid_depth;
  const double table_reach = p_.sized() ? max_table_radius_ : paper_table_radius_;
  nearWall(table_hash_, w, table_reach + band,
           [&](int32_t o) { return tables_[o].pose.position(); }, [&](int32_t o) {
             if (tables_[o].alive && inWallSolid(tableRect(tables_[o]), w)) e += log_eps_b_;
           });
  nearWall(leg_hash_, w, max_leg_side_ + band,
           [&](int32_t o) { return legs_[o].pose.position(); }, [&](int32_t o) {
             if (legs_[o].alive && inWallSolid(legRect(legs_[o]), w)) e += log_eps_b_;
           });
  return e;
}

bool Blackboard::wallEndJoined(const Vec2& e, int32_t self) const {
  const double r = wall_link_r_;
  const double th = walls_[self].angle();
  bool joined = false;
  wallsNear(e, r, [&](int32_t o) {
    if (joined || o == self) return;
    const WallHyp& w = walls_[o];
    joined = w.alive && wallEndMeets(e, th, w.a, w.b, r);
  });
  return joined;
}

double Blackboard::wallEndTerms(int32_t id) const {
  const WallHyp& w = walls_[id];
  if (!w.alive) return 0.0;
  return (wallEndJoined(w.a, id) ? 0.0 : log_free_wall_end_) +
         (wallEndJoined(w.b, id) ? 0.0 : log_free_wall_end_);
}

double Blackboard::touchedWallEndTerms(const Touched& t) const {
  if (log_free_wall_end_ == 0.0) return 0.0;
  double e = 0.0;
  for (int32_t id : t.walls.span()) e += wallEndTerms(id);
  for (int32_t id : t.wall_ends.span())
    if (!t.walls.contains(id)) e += wallEndTerms(id);
  return e;
}

void Blackboard::touchWallEnds(Touched& t, const Vec2& a, const Vec2& b) const {
  if (log_free_wall_end_ == 0.0) return;
  const double r = wall_link_r_, len = (b - a).norm();
  // Points along a..b no further apart than a hash step: every point within r of the segment
  // is within r + half a step of one of them.
  const int n = std::max(1, static_cast<int>(std::ceil(len / kWallHashStep)));
  for (int k = 0; k <= n; ++k) {
    const Vec2 q = a + (b - a) * (static_cast<double>(k) / n);
    wallsNear(q, r + 0.5 * len / n, [&](int32_t o) {
      const WallHyp& w = walls_[o];
      if (w.alive && (distanceToSegment(w.a, a, b) <= r || distanceToSegment(w.b, a, b) <= r))
        t.wall_ends.add(o);
    });
  }
}

void Blackboard::clear() {
  ++gen_;
  walls_.reset();
  wall_hash_.clear();
  live_walls_ = 0;
  tables_.reset();
  legs_.reset();
  table_hash_.clear();
  leg_hash_.clear();
  clearShapelets();
  live_tables_ = 0;
  live_legs_ = 0;
}

// ---------------------------------------------------------------- the log joint

double Blackboard::freeTerm(const Pose2& pose, double side) const {
  if (!free_) return 0.0;
  const int passes = free_->maxInSquare(pose, side, p_.free_margin);
  return std::min(passes, p_.free_pass_cap) * logs_.p_miss;
}

double Blackboard::tableFreeTerm(const TableHyp& table) const {
  if (!free_) return 0.0;
  double e = 0.0;
  for (int i = 0; i < 4; ++i) {
    const Vec2 c = table.pose.toWorld(table.cornerOffset(i), table.trig.c, table.trig.s);
    e += freeTerm({c.x(), c.y(), table.pose.theta}, table.leg);
  }
  return e;
}

double Blackboard::tableSizeTerm(const TableHyp& t) const {
  if (!p_.sized()) return 0.0;
  if (p_.catalog_weight <= 0.0 || !p_.catalog_fixed_sides)
    return p_.logSizePrior(t.width, t.depth, t.leg);
  // The catalog counts a side only where the evidence bears on both ends of one of its two
  // edges: a leg there would have caused a contact in working memory, or (with negative
  // evidence) whiskers came within its link radius (eq. 30), where it would have been touched
  // or ruled out. Corners 0 and 1 (and 3 and 2) span the width, 0 and 3 (and 1 and 2) the depth.
  bool near[4];
  const double reach = p_.shapeletLinkRadius();
  for (int i = 0; i < 4; ++i) {
    const Vec2 c = t.pose.toWorld(t.cornerOffset(i), t.trig.c, t.trig.s);
    near[i] = shapeletNear(c) || (free_ && free_->sweptNear(c, reach));
  }
  const bool width_fixed = (near[0] && near[1]) || (near[3] && near[2]);
  const bool depth_fixed = (near[0] && near[3]) || (near[1] && near[2]);
  return p_.logSizePrior(t.width, t.depth, t.leg, width_fixed, depth_fixed);
}

double Blackboard::legSideTerm(const LegHyp& l) const {
  return p_.sized() && !p_.legSideAllowed(l.side) ? -std::numeric_limits<double>::infinity()
                                                  : 0.0;
}

double Blackboard::tableTerms(int32_t id, const Touched& t) const {
  const TableHyp& tab = tables_[id];
  if (!tab.alive) return 0.0;
  return tablePairTerms(id, t, tableOwnTerm(tab));
}

double Blackboard::tableOwnTerm(const TableHyp& tab) const {
  return tableOwnTerm(tab, tableFreeTerm(tab));
}

double Blackboard::tableOwnTerm(const TableHyp& tab, double free) const {
  double e = table_odds_ + tab.missingLegs() * log_eps_a_ + free;
  if (p_.sized()) e += tableSizeTerm(tab);
  return e;
}

double Blackboard::tablePairTerms(int32_t id, const Touched& t, double own) const {
  const TableHyp& tab = tables_[id];
  double e = own;
  const OrientedRect rect = tableRect(tab);
  const double radius = tab.trig.radius;
  const double reach = p_.sized() ? radius + max_table_radius_ : 2.0 * radius;
  table_hash_.query(tab.pose.position(), reach, [&](int32_t o) {
    if (o == id || !tables_[o].alive) return;
    if (o < id && t.tables.contains(o)) return;  // pair counted from o's side
    if (overlaps(rect, tab.trig, tableRect(tables_[o]), tables_[o].trig)) e += log_eps_b_;
  });
  if (p_.walled()) {
    wallsNear(tab.pose.position(), radius + p_.wall_solid_depth, [&](int32_t w) {
      if (!walls_[w].alive || t.walls.contains(w)) return;  // a touched wall counts the pair
      if (inWallSolid(rect, walls_[w])) e += log_eps_b_;
    });
  }
  return e;
}

double Blackboard::legTerms(int32_t id, const Touched& t) const {
  const LegHyp& l = legs_[id];
  if (!l.alive) return 0.0;
  return legPairTerms(id, t, legOwnTerm(l));
}

double Blackboard::legOwnTerm(const LegHyp& l) const {
  return legOwnTerm(l, freeTerm(l.pose, l.side));
}

double Blackboard::legOwnTerm(const LegHyp& l, double free) const {
  const bool has_parent = l.parent != kNone;
  const double odds =
      has_parent ? logPresenceOdds(logLegDensity(deltaTLHeld(tables_[l.parent], l, p_, nullptr),
                                                 true, logs_),
                                   logs_)
                 : orphan_leg_odds_;
  double e = odds + free;
  if (p_.sized()) e += legSideTerm(l);
  return e;
}

double Blackboard::legPairTerms(int32_t id, const Touched& t, double own) const {
  const LegHyp& l = legs_[id];
  const bool has_parent = l.parent != kNone;
  double e = own;
  const OrientedRect rect = legRect(l);
  const double radius = l.trig.radius;
  const double reach =
      p_.sized() ? radius + 0.5 * std::sqrt(2.0) * max_leg_side_ : 2.0 * radius;
  leg_hash_.query(l.pose.position(), reach, [&](int32_t o) {
    if (o == id || !legs_[o].alive) return;
    if (o < id && t.legs.contains(o)) return;
    if (overlaps(rect, l.trig, legRect(legs_[o]), legs_[o].trig)) e += log_eps_b_;
  });
  if (p_.walled()) {
    wallsNear(l.pose.position(), radius + p_.wall_solid_depth, [&](int32_t w) {
      if (!walls_[w].alive || t.walls.contains(w)) return;  // a touched wall counts the pair
      if (inWallSolid(rect, walls_[w])) e += log_eps_b_;
    });
  }
  if (has_parent) {
    const TableHyp& parent = tables_[l.parent];
    for (int i = 0; i < parent.n_children; ++i) {
      const int32_t o = parent.children[i];
      if (o == id || legs_[o].corner != l.corner) continue;
      if (o < id && t.legs.contains(o)) continue;
      e += log_eps_c_;
    }
  }
  return e;
}

double Blackboard::shapeletTerm(int slot) const {
  if (!wm_used_[static_cast<size_t>(slot)]) return 0.0;
  const Shapelet& s = wm_[static_cast<size_t>(slot)];
  const double r = shapelet_link_r_;
  double acc = logs_.c_S;
  leg_hash_.query({s.x, s.y}, r, [&](int32_t o) {
    const LegHyp& l = legs_[o];
    if (!l.alive || (l.pose.position() - Vec2{s.x, s.y}).squaredNorm() > r * r) return;
    acc = logAddExp(acc, logShapeletKernelHeld(l, s, p_, logs_));
  });
  if (p_.walled()) {
    const double rw = wall_link_r_;
    wallsNear({s.x, s.y}, rw, [&](int32_t o) {
      const WallHyp& w = walls_[o];
      if (!w.alive || distanceToSegment({s.x, s.y}, w.a, w.b) > rw) return;
      acc = logAddExp(acc, logWallKernel(w, s, p_, logs_));
    });
  }
  return acc;
}

double Blackboard::localEnergy(const Touched& t) const {
  double e = 0.0;
  for (int32_t id : t.tables.span()) e += tableTerms(id, t);
  for (int32_t id : t.legs.span()) e += legTerms(id, t);
  for (int32_t slot : t.shapelets.span()) e += shapeletTerm(slot);
  for (int32_t id : t.walls.span()) e += wallTerms(id, t);
  return e + touchedWallEndTerms(t);
}

double Blackboard::localEnergy(const Touched& t, std::span<const int32_t> more_shapelets) const {
  double e = localEnergy(t);
  for (int32_t slot : more_shapelets) e += shapeletTerm(slot);
  return e;
}

// ---------------------------------------------------------------- incremental energies

namespace {
// A record's own terms from its cache, computed by fresh(record) and stored where stale.
template <typename Record, typename Fresh>
double cachedOwn(Record& r, uint64_t gen, Fresh&& fresh) {
  if (r.own_gen != gen) {
    r.own = fresh(r);
    r.own_gen = gen;
  }
  return r.own;
}
}  // namespace

double Blackboard::cachedTableOwn(int32_t id) {
  TableHyp& tab = tables_[id];
  return cachedOwn(tab, gen_,
                   [&](const TableHyp& t) { return tableOwnTerm(t, cachedTableFree(tab)); });
}

double Blackboard::cachedLegOwn(int32_t id) {
  LegHyp& l = legs_[id];
  return cachedOwn(l, gen_, [&](const LegHyp& r) { return legOwnTerm(r, cachedLegFree(l)); });
}

namespace {
bool samePose(const Pose2& a, const Pose2& b) {
  return a.x == b.x && a.y == b.y && a.theta == b.theta;
}

// Whether a record's kept free term is still its own: read in this generation (the grid gains
// no ray within one) at the pose and sizes it has now.
bool freeHolds(const TableHyp& t, uint64_t gen) {
  return t.free_gen == gen && samePose(t.free_pose, t.pose) && t.free_width == t.width &&
         t.free_depth == t.depth && t.free_leg == t.leg;
}
bool freeHolds(const LegHyp& l, uint64_t gen) {
  return l.free_gen == gen && samePose(l.free_pose, l.pose) && l.free_side == l.side;
}
}  // namespace

// A record's free term is a function of its pose and sizes and of the grid (the generation
// changes with every ray): kept with them, it holds whatever moves came between.
double Blackboard::cachedTableFree(TableHyp& tab) {
  const Pose2& q = tab.pose;
  if (!freeHolds(tab, gen_)) {
    tab.free = tableFreeTerm(tab);
    tab.free_gen = gen_;
    tab.free_pose = q;
    tab.free_width = tab.width;
    tab.free_depth = tab.depth;
    tab.free_leg = tab.leg;
  }
  return tab.free;
}

double Blackboard::cachedLegFree(LegHyp& l) {
  const Pose2& q = l.pose;
  if (!freeHolds(l, gen_)) {
    l.free = freeTerm(l.pose, l.side);
    l.free_gen = gen_;
    l.free_pose = q;
    l.free_side = l.side;
  }
  return l.free;
}

double Blackboard::cachedWallOwn(int32_t id) {
  return cachedOwn(walls_[id], gen_, [&](const WallHyp& w) { return wallOwnTerm(w); });
}

double Blackboard::cachedShapeletTerm(int slot) {
  const auto i = static_cast<size_t>(slot);
  if (slot_gen_[i] != gen_) {
    slot_term_[i] = shapeletTerm(slot);
    slot_gen_[i] = gen_;
  }
  return slot_term_[i];
}

double Blackboard::energyBefore(const Touched& t, std::span<const int32_t> more) {
  if (t.shapelets.overflowed || t.wall_ends.overflowed) {
    ++blanket_overflows_;
    return std::numeric_limits<double>::infinity();
  }
  if (!incremental_) return localEnergy(t, more);
  if (free_ && free_->rays() != rays_seen_) {  // new negative evidence: every own term changed
    rays_seen_ = free_->rays();
    ++gen_;
  }
  // The sum localEnergy() makes, in its order, with the own and shapelet terms from the cache.
  double e = 0.0;
  for (int32_t id : t.tables.span())
    if (tables_[id].alive) e += tablePairTerms(id, t, cachedTableOwn(id));
  for (int32_t id : t.legs.span())
    if (legs_[id].alive) e += legPairTerms(id, t, cachedLegOwn(id));
  for (int32_t slot : t.shapelets.span())
    if (wm_used_[static_cast<size_t>(slot)]) e += cachedShapeletTerm(slot);
  for (int32_t id : t.walls.span())
    if (walls_[id].alive) e += wallPairTerms(id, cachedWallOwn(id));
  e += touchedWallEndTerms(t);
  for (int32_t slot : more)
    if (wm_used_[static_cast<size_t>(slot)]) e += cachedShapeletTerm(slot);
  return e;
}

double Blackboard::energyAfter(const Touched& t, std::span<const int32_t> more) {
  return energyAfterImpl(t, more, kNone);
}

double Blackboard::energyAfterBirth(const Touched& t, int32_t born) {
  return energyAfterImpl(t, {}, born);
}

double Blackboard::energyAfterImpl(const Touched& t, std::span<const int32_t> more,
                                   int32_t born) {
  n_kept_tables_ = n_kept_legs_ = n_kept_walls_ = 0;
  kept_slots_.clear();
  if (t.shapelets.overflowed || t.wall_ends.overflowed)
    return -std::numeric_limits<double>::infinity();
  if (!incremental_) return localEnergy(t, more);
  double e = 0.0;
  for (int32_t id : t.tables.span()) {
    if (!tables_[id].alive) continue;
    const double own = tableOwnTerm(tables_[id], cachedTableFree(tables_[id]));
    kept_tables_[static_cast<size_t>(n_kept_tables_++)] = {id, own};
    e += tablePairTerms(id, t, own);
  }
  for (int32_t id : t.legs.span()) {
    if (!legs_[id].alive) continue;
    const double own = legOwnTerm(legs_[id], cachedLegFree(legs_[id]));
    kept_legs_[static_cast<size_t>(n_kept_legs_++)] = {id, own};
    e += legPairTerms(id, t, own);
  }
  const auto keep = [&](int32_t slot) {
    const auto i = static_cast<size_t>(slot);
    if (!wm_used_[i]) return 0.0;
    double term;
    if (born != kNone && slot_gen_[i] == gen_) {
      // The cached sum over the causes before the birth, plus the new leg's kernel where
      // shapeletTerm would count it (within the link radius).
      term = slot_term_[i];
      const LegHyp& l = legs_[born];
      const Shapelet& sh = wm_[i];
      const double r = shapelet_link_r_;
      if (l.alive && (l.pose.position() - Vec2{sh.x, sh.y}).squaredNorm() <= r * r)
        term = logAddExp(term, logShapeletKernelHeld(l, sh, p_, logs_));
    } else {
      term = shapeletTerm(slot);
    }
    assert(kept_slots_.size() < kept_slots_.capacity());
    kept_slots_.push_back({slot, term});
    return term;
  };
  for (int32_t slot : t.shapelets.span()) e += keep(slot);
  for (int32_t id : t.walls.span()) {
    if (!walls_[id].alive) continue;
    const double own = wallOwnTerm(walls_[id]);
    kept_walls_[static_cast<size_t>(n_kept_walls_++)] = {id, own};
    e += wallPairTerms(id, own);
  }
  e += touchedWallEndTerms(t);
  for (int32_t slot : more) e += keep(slot);
  return e;
}

void Blackboard::acceptMove() {
  for (int i = 0; i < n_kept_tables_; ++i) {
    TableHyp& tab = tables_[kept_tables_[static_cast<size_t>(i)].id];
    tab.own = kept_tables_[static_cast<size_t>(i)].value;
    tab.own_gen = gen_;
  }
  for (int i = 0; i < n_kept_legs_; ++i) {
    LegHyp& l = legs_[kept_legs_[static_cast<size_t>(i)].id];
    l.own = kept_legs_[static_cast<size_t>(i)].value;
    l.own_gen = gen_;
  }
  for (int i = 0; i < n_kept_walls_; ++i) {
    WallHyp& w = walls_[kept_walls_[static_cast<size_t>(i)].id];
    w.own = kept_walls_[static_cast<size_t>(i)].value;
    w.own_gen = gen_;
  }
  for (const Kept& k : kept_slots_) {
    slot_term_[static_cast<size_t>(k.id)] = k.value;
    slot_gen_[static_cast<size_t>(k.id)] = gen_;
  }
  n_kept_tables_ = n_kept_legs_ = n_kept_walls_ = 0;
  kept_slots_.clear();
}

double Blackboard::shapeletExplanation(int slot) {
  if (!wm_used_[static_cast<size_t>(slot)]) return 0.0;
  return (incremental_ ? cachedShapeletTerm(slot) : shapeletTerm(slot)) - logs_.c_S;
}

void Blackboard::setIncremental(bool on) {
  incremental_ = on;
  ++gen_;
}

namespace {
double termError(double cached, double fresh) {
  return cached == fresh ? 0.0 : std::abs(cached - fresh);  // equal infinities: no error
}
}  // namespace

double Blackboard::cacheError() const {
  double err = 0.0;
  for (int32_t id = 0; id < tables_.extent(); ++id) {
    const TableHyp& tab = tables_[id];
    if (tab.alive && tab.own_gen == gen_) err = std::max(err, termError(tab.own, tableOwnTerm(tab)));
    if (tab.alive && freeHolds(tab, gen_))
      err = std::max(err, termError(tab.free, tableFreeTerm(tab)));
  }
  for (int32_t id = 0; id < legs_.extent(); ++id) {
    const LegHyp& l = legs_[id];
    if (l.alive && l.own_gen == gen_) err = std::max(err, termError(l.own, legOwnTerm(l)));
    if (l.alive && freeHolds(l, gen_))
      err = std::max(err, termError(l.free, freeTerm(l.pose, l.side)));
  }
  for (int32_t id = 0; id < walls_.extent(); ++id) {
    const WallHyp& w = walls_[id];
    if (w.alive && w.own_gen == gen_) err = std::max(err, termError(w.own, wallOwnTerm(w)));
  }
  for (size_t i = 0; i < wm_.size(); ++i)
    if (wm_used_[i] && slot_gen_[i] == gen_)
      err = std::max(err, termError(slot_term_[i], shapeletTerm(static_cast<int>(i))));
  return err;
}

double Blackboard::totalEnergy() const {
  double e = 0.0;
  for (int32_t i = 0; i < tables_.extent(); ++i) {
    const TableHyp& a = tables_[i];
    if (!a.alive) continue;
    e += table_odds_ + a.missingLegs() * log_eps_a_ + tableFreeTerm(a) + tableSizeTerm(a);
    for (int32_t j = i + 1; j < tables_.extent(); ++j)
      if (tables_[j].alive && overlaps(tableRect(a), tableRect(tables_[j])))
        e += log_eps_b_;
  }
  for (int32_t i = 0; i < legs_.extent(); ++i) {
    const LegHyp& a = legs_[i];
    if (!a.alive) continue;
    const bool has_parent = a.parent != kNone;
    const double dtl = has_parent ? deltaTLSized(tables_[a.parent], a, p_, nullptr) : 0.0;
    e += logPresenceOdds(logLegDensity(dtl, has_parent, p_), p_) + freeTerm(a.pose, a.side) +
         legSideTerm(a);
    for (int32_t j = i + 1; j < legs_.extent(); ++j) {
      const LegHyp& b = legs_[j];
      if (!b.alive) continue;
      if (overlaps(legRect(a), legRect(b))) e += log_eps_b_;
      if (has_parent && b.parent == a.parent && b.corner == a.corner) e += log_eps_c_;
    }
  }
  const double r = p_.shapeletLinkRadius();
  for (size_t s = 0; s < wm_.size(); ++s) {
    if (!wm_used_[s]) continue;
    double acc = std::log(p_.c_S);
    for (int32_t i = 0; i < legs_.extent(); ++i) {
      const LegHyp& l = legs_[i];
      if (l.alive && (l.pose.position() - Vec2{wm_[s].x, wm_[s].y}).squaredNorm() <= r * r)
        acc = logAddExp(acc, logShapeletKernel(l, wm_[s], p_));
    }
    for (int32_t i = 0; i < walls_.extent(); ++i) {
      const WallHyp& w = walls_[i];
      if (w.alive && distanceToSegment({wm_[s].x, wm_[s].y}, w.a, w.b) <= p_.wallLinkRadius())
        acc = logAddExp(acc, logWallKernel(w, wm_[s], p_));
    }
    e += acc;
  }
  for (int32_t i = 0; i < walls_.extent(); ++i) {
    const WallHyp& w = walls_[i];
    if (!w.alive) continue;
    e += wall_odds_ - p_.wall_cost_per_m * w.length() + wallFreeTerm(w.a, w.b);
    // Walls end at walls: each end that no other wall's segment passes near at an angle.
    for (const Vec2& end : {w.a, w.b}) {
      bool joined = false;
      for (int32_t j = 0; j < walls_.extent(); ++j) {
        const WallHyp& o = walls_[j];
        joined = joined || (j != i && o.alive &&
                            wallEndMeets(end, w.angle(), o.a, o.b, p_.wallLinkRadius()));
      }
      if (!joined) e += p_.logFreeWallEnd();
    }
    for (int32_t j = 0; j < tables_.extent(); ++j)
      if (tables_[j].alive && inWallSolid(tableRect(tables_[j]), w)) e += log_eps_b_;
    for (int32_t j = 0; j < legs_.extent(); ++j)
      if (legs_[j].alive && inWallSolid(legRect(legs_[j]), w)) e += log_eps_b_;
  }
  return e;
}

}  // namespace crunch
