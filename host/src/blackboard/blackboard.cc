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
      table_odds_(logPresenceOdds(std::log(params.c_T), params)) {
  assert(working_memory > 0);
}

// ---------------------------------------------------------------- working memory

int Blackboard::pushShapelet(const Shapelet& s) {
  const int slot = wm_next_;
  const auto i = static_cast<size_t>(slot);
  if (wm_used_[i]) {
    shapelet_hash_.remove(slot, {wm_[i].x, wm_[i].y});
  } else {
    ++wm_count_;
  }
  wm_[i] = s;
  wm_used_[i] = true;
  shapelet_hash_.insert(slot, {s.x, s.y});
  wm_next_ = (wm_next_ + 1) % static_cast<int>(wm_.size());
  return slot;
}

void Blackboard::clearShapelets() {
  shapelet_hash_.clear();
  std::fill(wm_used_.begin(), wm_used_.end(), false);
  wm_next_ = 0;
  wm_count_ = 0;
}

void Blackboard::shapeletsNear(const Vec2& p, IdSet<64>& out) const {
  const double r = p_.shapeletLinkRadius();
  shapelet_hash_.query(p, r, [&](int32_t slot) {
    const Shapelet& s = wm_[static_cast<size_t>(slot)];
    if ((Vec2{s.x, s.y} - p).squaredNorm() <= r * r) out.add(slot);
  });
}

// ---------------------------------------------------------------- hypotheses

int32_t Blackboard::addTable(const Pose2& pose) {
  return addTable(pose, p_.table_width, p_.table_depth, p_.leg_side);
}

int32_t Blackboard::addTable(const Pose2& pose, double width, double depth, double leg) {
  const int32_t id = tables_.acquire();
  TableHyp& t = tables_[id];
  t.pose = pose;
  t.width = width;
  t.depth = depth;
  t.leg = leg;
  t.alive = true;
  table_hash_.insert(id, pose.position());
  ++live_tables_;
  return id;
}

int32_t Blackboard::addLeg(const Pose2& pose, int32_t parent) {
  return addLeg(pose, p_.leg_side, parent);
}

int32_t Blackboard::addLeg(const Pose2& pose, double side, int32_t parent) {
  const int32_t id = legs_.acquire();
  LegHyp& l = legs_[id];
  l.pose = pose;
  l.side = side;
  l.alive = true;
  leg_hash_.insert(id, pose.position());
  ++live_legs_;
  if (parent != kNone) linkChild(parent, id);
  return id;
}

int Blackboard::nearestCorner(const TableHyp& table, const LegHyp& leg) const {
  int corner = 0;
  deltaTLSized(table, leg, p_, &corner);
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
  TableHyp& t = tables_[id];
  table_hash_.remove(id, t.pose.position());
  t.pose = pose;
  t.width = width;
  t.depth = depth;
  t.leg = leg;
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
  LegHyp& l = legs_[id];
  leg_hash_.remove(id, l.pose.position());
  l.pose = pose;
  leg_hash_.insert(id, pose.position());
  if (l.parent != kNone) {
    TableHyp& t = tables_[l.parent];
    --t.corner_count[static_cast<size_t>(l.corner)];
    l.corner = static_cast<int8_t>(nearestCorner(t, l));
    ++t.corner_count[static_cast<size_t>(l.corner)];
  }
}

void Blackboard::clear() {
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
  return std::min(passes, p_.free_pass_cap) * std::log(p_.p_miss);
}

double Blackboard::tableFreeTerm(const TableHyp& table) const {
  if (!free_) return 0.0;
  double e = 0.0;
  for (int i = 0; i < 4; ++i) {
    const Vec2 c = table.corner(i);
    e += freeTerm({c.x(), c.y(), table.pose.theta}, table.leg);
  }
  return e;
}

double Blackboard::tableSizeTerm(const TableHyp& t) const {
  return p_.sized() ? p_.logSizePrior(t.width, t.depth, t.leg) : 0.0;
}

double Blackboard::legSideTerm(const LegHyp& l) const {
  return p_.sized() && !p_.legSideAllowed(l.side) ? -std::numeric_limits<double>::infinity()
                                                  : 0.0;
}

double Blackboard::tableTerms(int32_t id, const Touched& t) const {
  const TableHyp& tab = tables_[id];
  if (!tab.alive) return 0.0;
  double e = table_odds_ + tab.missingLegs() * log_eps_a_ + tableFreeTerm(tab);
  if (p_.sized()) e += tableSizeTerm(tab);
  const OrientedRect rect = tableRect(tab);
  const double reach = p_.sized() ? rect.circumradius() + p_.maxTableCircumradius()
                                  : 2.0 * rect.circumradius();
  table_hash_.query(tab.pose.position(), reach, [&](int32_t o) {
    if (o == id || !tables_[o].alive) return;
    if (o < id && t.tables.contains(o)) return;  // pair counted from o's side
    if (overlaps(rect, tableRect(tables_[o]))) e += log_eps_b_;
  });
  return e;
}

double Blackboard::legTerms(int32_t id, const Touched& t) const {
  const LegHyp& l = legs_[id];
  if (!l.alive) return 0.0;
  const bool has_parent = l.parent != kNone;
  const double dtl = has_parent ? deltaTLSized(tables_[l.parent], l, p_, nullptr) : 0.0;
  double e = logPresenceOdds(logLegDensity(dtl, has_parent, p_), p_) + freeTerm(l.pose, l.side);
  if (p_.sized()) e += legSideTerm(l);
  const OrientedRect rect = legRect(l);
  const double reach = p_.sized() ? rect.circumradius() + 0.5 * std::sqrt(2.0) * p_.maxLegSide()
                                  : 2.0 * rect.circumradius();
  leg_hash_.query(l.pose.position(), reach, [&](int32_t o) {
    if (o == id || !legs_[o].alive) return;
    if (o < id && t.legs.contains(o)) return;
    if (overlaps(rect, legRect(legs_[o]))) e += log_eps_b_;
  });
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
  const double r = p_.shapeletLinkRadius();
  double acc = std::log(p_.c_S);
  leg_hash_.query({s.x, s.y}, r, [&](int32_t o) {
    const LegHyp& l = legs_[o];
    if (!l.alive || (l.pose.position() - Vec2{s.x, s.y}).squaredNorm() > r * r) return;
    acc = logAddExp(acc, logShapeletKernel(l, s, p_));
  });
  return acc;
}

double Blackboard::localEnergy(const Touched& t) const {
  double e = 0.0;
  for (int32_t id : t.tables.span()) e += tableTerms(id, t);
  for (int32_t id : t.legs.span()) e += legTerms(id, t);
  for (int32_t slot : t.shapelets.span()) e += shapeletTerm(slot);
  return e;
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
    e += acc;
  }
  return e;
}

}  // namespace crunch
