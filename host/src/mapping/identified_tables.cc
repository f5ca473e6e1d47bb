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
  ShapeletSet near;
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

// Table `id` reshaped from `from` with edge e at `v`, the corner opposite the edge held
// (corner 0, +x+y, holds the -x and -y edges, corner 2 the +x and +y edges; e < 2 moves the
// width, else the depth), its carried legs with their corners. False (nothing changed) outside
// the size prior.
bool placeEdge(Blackboard& board, int32_t id, const TableHyp& from, int e, double v,
               const Children& ch) {
  const ModelParams& p = board.params();
  constexpr int kHeld[4] = {0, 2, 0, 2};
  const double w = e < 2 ? v : from.width, d = e < 2 ? from.depth : v;
  if (!std::isfinite(p.logSizePrior(w, d, from.leg))) return false;
  const Vec2 fixed = from.corner(kHeld[e]);
  const Vec2 off =
      Pose2{0, 0, from.pose.theta}.toWorld(ModelParams::cornerOffset(kHeld[e], w, d, from.leg));
  board.reshapeTable(id, {fixed.x() - off.x(), fixed.y() - off.y(), from.pose.theta}, w, d,
                     from.leg);
  for (int c = 0; c < ch.n; ++c) {
    const auto k = static_cast<size_t>(c);
    if (!ch.carried[k]) continue;
    const Vec2 at = board.table(id).corner(ch.corner[k]);
    board.moveLeg(ch.id[k], {at.x(), at.y(), ch.pose[k].theta});
  }
  return true;
}

// f(value, J given the structure) for edge e at each value of the size prior's range in steps
// of `step` (placeEdge).
template <typename F>
void scanEdge(Blackboard& board, int32_t id, const TableHyp& from, int e, double step,
              const Children& ch, const Touched& t, F&& f) {
  const ModelParams& p = board.params();
  const int n = static_cast<int>(std::floor((p.size_max_long - p.size_min_side) / step)) + 1;
  for (int i = 0; i < n; ++i) {
    const double v = p.size_min_side + i * step;
    if (placeEdge(board, id, from, e, v, ch)) f(v, energyGivenStructure(board, id, t));
  }
}

// The paper's 8 placements of table `id` (of `from`'s size) with its first touched leg `first`
// at a corner (eq. 29's smart proposal: the anchor at corner k, the axis at theta or
// theta + pi/2) that put every touched leg at a corner of its own; for each, the touched legs
// stand at their corners, the guessed legs take the corners left, and f(turn, k, J given the
// structure) is called with the board so placed.
template <typename F>
void scanPlacements(Blackboard& board, int32_t id, const TableHyp& from, int first,
                    const Children& ch, const Touched& t, F&& f) {
  const double r = board.params().cornerLinkRadius();
  const Vec2 anchor = ch.pose[static_cast<size_t>(first)].position();
  for (int turn = 0; turn < 2; ++turn) {
    const double theta = wrapPi(from.pose.theta + turn * 0.5 * kPi);
    for (int k = 0; k < 4; ++k) {
      const Vec2 off = Pose2{0, 0, theta}.toWorld(
          ModelParams::cornerOffset(k, from.width, from.depth, from.leg));
      board.reshapeTable(id, {anchor.x() - off.x(), anchor.y() - off.y(), theta}, from.width,
                         from.depth, from.leg);
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
      f(turn, k, energyGivenStructure(board, id, t));
    }
  }
}

// Each touched leg moves to its corner of a placement (a contact on a face is explained by a
// leg on either side of it: the mirror image's legs stand across its faces), so the contacts
// around the touched legs are weighed too.
void weighContactsAtTouchedLegs(const Blackboard& board, const Children& ch, Touched& t) {
  for (int c = 0; c < ch.n; ++c)
    if (!ch.carried[static_cast<size_t>(c)])
      board.shapeletsNear(ch.pose[static_cast<size_t>(c)].position(), t.shapelets);
}

// Whether every corner of `a` stands within r of a corner of `b` (the same top, whichever way
// its corners are numbered).
bool sameFootprint(const TableHyp& a, const TableHyp& b, double r) {
  for (int i = 0; i < 4; ++i) {
    bool near = false;
    for (int c = 0; c < 4 && !near; ++c) near = (a.corner(i) - b.corner(c)).norm() <= r;
    if (!near) return false;
  }
  return true;
}

// The first child that is evidence, or -1.
int firstTouched(const Children& ch) {
  for (int c = 0; c < ch.n; ++c)
    if (!ch.carried[static_cast<size_t>(c)]) return c;
  return -1;
}

}  // namespace

double sizeCertainty(Blackboard& board, int32_t id, double tolerance) {
  const TableHyp old = board.table(id);
  Touched t;
  const Children ch = childrenOf(board, id, t);
  double certainty = 1.0;
  for (int e = 0; e < 4; ++e) {
    const double now = e < 2 ? old.width : old.depth;
    double log_all = -std::numeric_limits<double>::infinity(), log_near = log_all;
    scanEdge(board, id, old, e, tolerance / 5.0, ch, t, [&](double v, double j) {
      log_all = logAddExp(log_all, j);
      if (std::abs(v - now) <= 0.5 * tolerance) log_near = logAddExp(log_near, j);
    });
    if (std::isfinite(log_all)) certainty *= std::exp(log_near - log_all);
  }
  restore(board, id, old, ch);
  return certainty;
}

double placementCertainty(Blackboard& board, int32_t id) {
  const TableHyp old = board.table(id);
  Touched t;
  const Children ch = childrenOf(board, id, t);
  const int first = firstTouched(ch);
  if (first < 0) return 1.0;  // nothing to place it by: the chain's own judgement stands
  weighContactsAtTouchedLegs(board, ch, t);
  // The chain's own placement and the others, apart: their ratio decides a tie below.
  double log_now = -std::numeric_limits<double>::infinity(), log_others = log_now;
  const int own = ch.corner[static_cast<size_t>(first)];
  const double r = board.params().cornerLinkRadius();
  scanPlacements(board, id, old, first, ch, t, [&](int turn, int k, double j) {
    // The chain's own placement (the anchor at its corner, the axis unturned), and any other
    // with the same footprint: a near-square top turned a quarter is the same object (the
    // rooms model's chairs), not a rival.
    if ((turn == 0 && k == own) || sameFootprint(board.table(id), old, r))
      log_now = logAddExp(log_now, j);
    else log_others = logAddExp(log_others, j);
  });
  restore(board, id, old, ch);
  const double log_all = logAddExp(log_now, log_others);
  if (!std::isfinite(log_all)) return 1.0;
  // Two placements the model scores alike within rounding (mirror images nothing tells apart)
  // are a tie, not a preference for the chain's: 1/2 exactly.
  if (std::abs(log_now - log_others) < 1e-9 * std::max(1.0, std::abs(log_now))) return 0.5;
  return std::exp(log_now - log_all);
}

MapTable drawOpenTable(Blackboard& board, int32_t id, double step, Rng& rng) {
  const ModelParams& p = board.params();
  const TableHyp old = board.table(id);
  if (!p.walled()) return modelTable(old.pose, p);
  Touched t;
  const Children ch = childrenOf(board, id, t);
  int touched = 0;
  for (int c = 0; c < ch.n; ++c) touched += ch.carried[static_cast<size_t>(c)] ? 0 : 1;
  const int first = firstTouched(ch);
  // Three touched legs pin the top (and its place); a table no leg pins is the chain's guess.
  if (touched >= 3 || first < 0) {
    restore(board, id, old, ch);  // as every exit: the board's look-ups keep one order
    return p.sized() ? sizedTable(old) : modelTable(old.pose, p);
  }
  std::vector<double> logw;
  MapTable out;
  if (p.sized()) {
    // A Gibbs scan: each edge in turn from its conditional given the others as drawn so far.
    TableHyp cur = old;
    std::vector<double> values;
    for (int e = 0; e < 4; ++e) {
      logw.clear();
      values.clear();
      scanEdge(board, id, cur, e, step, ch, t, [&](double v, double j) {
        values.push_back(v);
        logw.push_back(j);
      });
      if (values.empty()) continue;
      placeEdge(board, id, cur, e, values[drawLogWeighted(logw, rng)], ch);
      cur = board.table(id);
    }
    out = sizedTable(cur);
  } else {
    weighContactsAtTouchedLegs(board, ch, t);
    std::vector<Pose2> poses;
    scanPlacements(board, id, old, first, ch, t, [&](int, int, double j) {
      poses.push_back(board.table(id).pose);
      logw.push_back(j);
    });
    out = modelTable(poses.empty() ? old.pose : poses[drawLogWeighted(logw, rng)], p);
  }
  restore(board, id, old, ch);
  return out;
}

void identifiedTablesOf(Blackboard& board, double tolerance, std::vector<MapTable>& out) {
  out.clear();
  const ModelParams& p = board.params();
  for (int32_t id = 0; id < board.tableExtent(); ++id) {
    if (!board.table(id).alive) continue;
    if (p.sized()) {
      // Its size and its place: a table of the catalog's size (ModelParams::catalog_weight) on
      // the two legs of one side has a size the prior fixes and a mirror image the evidence may
      // not tell apart, as under the walls model.
      const double size = sizeCertainty(board, id, tolerance);
      if (size > 0.5 && size * placementCertainty(board, id) > 0.5)
        out.push_back(sizedTable(board.table(id)));
    } else if (!p.walled() || placementCertainty(board, id) > 0.5) {
      out.push_back(modelTable(board.table(id).pose, p));
    }
  }
}

}  // namespace crunch
