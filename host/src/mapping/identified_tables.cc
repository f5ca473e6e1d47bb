#include "crunch/mapping/identified_tables.h"

#include <array>
#include <cmath>
#include <limits>

#include "crunch/mapping/mapper.h"  // sizedTable, modelTable

namespace crunch {

namespace {

// Whether leg l explains a contact better than the background (eq. 14's c_S): evidence where it
// stands. A leg that explains none is its table's guess and goes with its corner.
bool explainsContact(const Blackboard& board, const LegHyp& l) {
  const ModelParams& p = board.params();
  IdSet<64> near;
  board.shapeletsNear(l.pose.position(), near);
  for (int32_t s : near.span())
    if (logShapeletKernel(l, board.shapelet(s), p) > std::log(p.c_S)) return true;
  return false;
}

// The log joint over table `id` and its legs (`t`), given the chain's structure: each child
// counts by the table's branch of eq. 9's mixture, -Delta_TL, not by c_L's (which would let
// the table leave its legs behind as orphans at a cost of a few nats).
double energyGivenStructure(const Blackboard& board, int32_t id, const Touched& t) {
  const ModelParams& p = board.params();
  const TableHyp& tab = board.table(id);
  double j = board.localEnergy(t);
  for (int c = 0; c < tab.n_children; ++c) {
    const double dtl = deltaTLSized(tab, board.leg(tab.children[c]), p, nullptr);
    j += -dtl - logPresenceOdds(logLegDensity(dtl, true, p), p);
  }
  return j;
}

// A table's children: which are evidence, and where each stood.
struct Children {
  int n = 0;
  std::array<int32_t, kMaxChildren> id{};
  std::array<bool, kMaxChildren> carried{};
  std::array<Pose2, kMaxChildren> pose{};
  std::array<int, kMaxChildren> corner{};
};

Children childrenOf(const Blackboard& board, int32_t id, Touched& t) {
  Children ch;
  const TableHyp& tab = board.table(id);
  t.tables.add(id);
  ch.n = tab.n_children;
  for (int c = 0; c < tab.n_children; ++c) {
    const LegHyp& l = board.leg(tab.children[c]);
    const auto k = static_cast<size_t>(c);
    t.legs.add(tab.children[c]);
    ch.id[k] = tab.children[c];
    ch.pose[k] = l.pose;
    ch.corner[k] = l.corner;
    ch.carried[k] = !explainsContact(board, l);
  }
  return ch;
}

void restore(Blackboard& board, int32_t id, const TableHyp& old, const Children& ch) {
  board.reshapeTable(id, old.pose, old.width, old.depth, old.leg);
  for (int c = 0; c < ch.n; ++c)
    board.moveLeg(ch.id[static_cast<size_t>(c)], ch.pose[static_cast<size_t>(c)]);
}

}  // namespace

double sizeCertainty(Blackboard& board, int32_t id, double tolerance) {
  const ModelParams& p = board.params();
  const TableHyp old = board.table(id);
  Touched t;
  const Children ch = childrenOf(board, id, t);
  const double step = tolerance / 5.0;
  const int n = static_cast<int>(std::floor((p.size_max_long - p.size_min_side) / step)) + 1;
  double certainty = 1.0;
  // Edge e moves while the opposite corner k stays: corner 0 (+x+y) holds the -x and -y edges,
  // corner 2 (-x-y) the +x and +y edges; e < 2 scans the width, else the depth.
  constexpr int kHeld[4] = {0, 2, 0, 2};
  for (int e = 0; e < 4; ++e) {
    const bool along_x = e < 2;
    const double now = along_x ? old.width : old.depth;
    const Vec2 fixed = old.corner(kHeld[e]);
    double log_all = -std::numeric_limits<double>::infinity(), log_near = log_all;
    for (int i = 0; i < n; ++i) {
      const double v = p.size_min_side + i * step;
      const double w = along_x ? v : old.width, d = along_x ? old.depth : v;
      if (!std::isfinite(p.logSizePrior(w, d, old.leg))) continue;
      const Vec2 off =
          Pose2{0, 0, old.pose.theta}.toWorld(ModelParams::cornerOffset(kHeld[e], w, d, old.leg));
      board.reshapeTable(id, {fixed.x() - off.x(), fixed.y() - off.y(), old.pose.theta}, w, d,
                         old.leg);
      for (int c = 0; c < ch.n; ++c) {
        const auto k = static_cast<size_t>(c);
        if (!ch.carried[k]) continue;
        const Vec2 at = board.table(id).corner(ch.corner[k]);
        board.moveLeg(ch.id[k], {at.x(), at.y(), ch.pose[k].theta});
      }
      const double j = energyGivenStructure(board, id, t);
      log_all = logAddExp(log_all, j);
      if (std::abs(v - now) <= 0.5 * tolerance) log_near = logAddExp(log_near, j);
    }
    if (std::isfinite(log_all)) certainty *= std::exp(log_near - log_all);
  }
  restore(board, id, old, ch);
  return certainty;
}

double placementCertainty(Blackboard& board, int32_t id) {
  const ModelParams& p = board.params();
  const TableHyp old = board.table(id);
  Touched t;
  const Children ch = childrenOf(board, id, t);
  int first = -1;  // the first child that is evidence
  for (int c = 0; c < ch.n && first < 0; ++c)
    if (!ch.carried[static_cast<size_t>(c)]) first = c;
  if (first < 0) return 1.0;  // nothing to place it by: the chain's own judgement stands
  const Vec2 anchor = ch.pose[static_cast<size_t>(first)].position();
  const double r = p.cornerLinkRadius();
  // Each touched leg moves to its corner of a placement (a contact on a face is explained by a
  // leg on either side of it: the mirror image's legs stand across its faces), so the contacts
  // around the touched legs are weighed too.
  for (int c = 0; c < ch.n; ++c)
    if (!ch.carried[static_cast<size_t>(c)])
      board.shapeletsNear(ch.pose[static_cast<size_t>(c)].position(), t.shapelets);
  // The chain's own placement and the others, apart: their ratio decides a tie below.
  double log_now = -std::numeric_limits<double>::infinity(), log_others = log_now;
  // The paper's 8 placements of a table with a given leg at a corner (eq. 29's smart proposal):
  // the anchor leg at corner k, the table's axis at theta or theta + pi/2.
  for (int turn = 0; turn < 2; ++turn) {
    const double theta = wrapPi(old.pose.theta + turn * 0.5 * kPi);
    for (int k = 0; k < 4; ++k) {
      const Vec2 off = Pose2{0, 0, theta}.toWorld(
          ModelParams::cornerOffset(k, old.width, old.depth, old.leg));
      board.reshapeTable(id, {anchor.x() - off.x(), anchor.y() - off.y(), theta}, old.width,
                         old.depth, old.leg);
      const TableHyp& tab = board.table(id);
      // Every leg that is evidence must stand at a corner, each at its own.
      std::array<bool, 4> taken{};
      bool fits = true;
      for (int c = 0; c < ch.n && fits; ++c) {
        const auto ck = static_cast<size_t>(c);
        if (ch.carried[ck]) continue;
        const int at = board.leg(ch.id[ck]).corner;
        fits = !taken[static_cast<size_t>(at)] &&
               (tab.corner(at) - ch.pose[ck].position()).norm() <= r;
        taken[static_cast<size_t>(at)] = true;
      }
      if (!fits) continue;
      // The touched legs stand at their corners; the guessed legs take the corners left.
      int next = 0;
      for (int c = 0; c < ch.n; ++c) {
        const auto ck = static_cast<size_t>(c);
        if (!ch.carried[ck]) {
          const Vec2 at = tab.corner(board.leg(ch.id[ck]).corner);
          board.moveLeg(ch.id[ck], {at.x(), at.y(), ch.pose[ck].theta});
          continue;
        }
        while (next < 3 && taken[static_cast<size_t>(next)]) ++next;
        taken[static_cast<size_t>(next)] = true;
        const Vec2 at = tab.corner(next);
        board.moveLeg(ch.id[ck], {at.x(), at.y(), theta});
      }
      const double j = energyGivenStructure(board, id, t);
      // The chain's own placement: the anchor at its corner, the axis unturned.
      if (turn == 0 && k == ch.corner[static_cast<size_t>(first)]) log_now = j;
      else log_others = logAddExp(log_others, j);
    }
  }
  restore(board, id, old, ch);
  const double log_all = logAddExp(log_now, log_others);
  if (!std::isfinite(log_all)) return 1.0;
  // Two placements the model scores alike within rounding (mirror images nothing tells apart)
  // are a tie, not a preference for the chain's: 1/2 exactly.
  if (std::abs(log_now - log_others) < 1e-9 * std::max(1.0, std::abs(log_now))) return 0.5;
  return std::exp(log_now - log_all);
}

void identifiedTablesOf(Blackboard& board, double tolerance, std::vector<MapTable>& out) {
  out.clear();
  const ModelParams& p = board.params();
  for (int32_t id = 0; id < board.tableExtent(); ++id) {
    if (!board.table(id).alive) continue;
    if (p.sized()) {
      if (sizeCertainty(board, id, tolerance) > 0.5) out.push_back(sizedTable(board.table(id)));
    } else if (!p.walled() || placementCertainty(board, id) > 0.5) {
      out.push_back(modelTable(board.table(id).pose, p));
    }
  }
}

}  // namespace crunch
