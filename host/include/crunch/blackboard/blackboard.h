// The blackboard B (paper §2.7): live table and leg hypotheses, the working memory of recent
// shapelets, and the log joint of the factor graph of eq. 23 over them.
//
// The log joint is
//   J(B) =  sum_T [ logodds(delta^3 c_T) + m_T log eps_a ]                       (eqs. 7, 24, 28)
//         + sum_L   logodds(delta^3 p(L | pa(L)))                                (eqs. 9, 13, 17)
//         + sum_S   log(c_S + sum_L alpha_S exp(-Delta_LS))                       (eqs. 11, 14, 17)
//         + (#overlapping same-type pairs) log eps_b                             (eq. 25)
//         + (#leg pairs with the same parent at the same corner) log eps_c       (eq. 26)
//         + sum over legs and table corners of min(passes, cap) log p_miss     (free space)
//         + sum_T log p(size_T) + sum_L log p(side_L)   (rooms model only: the size prior,
//           0 inside its range and -infinity outside; ModelParams::logSizePrior)
// and, with walls (--model walls or rooms, docs/BLACKBOARD.md "Walls"),
//         + sum_W [ logodds(delta^3 c_W) - wall_cost_per_m |W| + free(W) ]
//         + (#table-wall and leg-wall pairs intruding into the wall's solid) log eps_b
//         + (#wall ends that meet no other wall) log(p_free / (1 - p_free))  ("Walls end at walls")
// with each wall's kernel alpha_W exp(-Delta_WS) joining the shapelets' noisy-OR sums.
// where logodds(P) = log P - log(1 - P) is each hypothesis' presence against its absence.
// A move's acceptance needs only the change of J, which localEnergy() computes over the
// hypotheses and shapelets the move touches: the Markov blankets of eq. 29.
//
// Incremental energies (issue 15). Each table's and leg's own terms (its presence odds, missing
// legs, negative evidence and size prior: everything but its pair terms) and each shapelet's
// noisy-OR term (eq. 17) are cached, and so are each wall's own terms; each table's and leg's
// negative evidence is kept with the pose it was read at, so a move that leaves a hypothesis in
// place (a new parent, a sibling moved) reads no free space for it. A move asks energyBefore()
// (the cached terms, the pair terms counted afresh) and energyAfter() (everything afresh, kept
// aside; a birth's shapelet terms, energyAfterBirth(), its cached sums plus the new kernel);
// acceptMove() makes the kept values the cache, and a refused move restores the state exactly,
// so the cache stays right.
// Between beginSweep() and endSweep() every mutation must belong to such a move; any other
// mutation, a shapelet pushed, or a negative-evidence grid that gained rays invalidates the cache
// (one generation counter), so callers other than the sampler need not know it exists. The
// brute-force audit (Sampler::setAudit) checks every move's change against totalEnergy() and
// every cached term against its fresh value.
//
// Mutations keep the spatial hashes and parent/child links consistent. Killing a hypothesis
// keeps its record so the move can be undone; release() returns the id to the pool once the
// move is committed. Nothing here allocates after warm-up (see pool.h, spatial_hash.h).
// Not thread-safe.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "crunch/blackboard/factors.h"
#include "crunch/blackboard/hypotheses.h"
#include "crunch/blackboard/params.h"
#include "crunch/blackboard/pool.h"
#include "crunch/blackboard/spatial_hash.h"
#include "crunch/blackboard/free_space.h"
#include "crunch/robot/shapelet.h"

namespace crunch {

// A small set of ids with fixed capacity (a move touches a handful of hypotheses). An id
// past the capacity is not held and sets `overflowed`.
template <int N>
struct IdSet {
  int32_t ids[N];
  int n = 0;
  bool overflowed = false;
  void add(int32_t id) {
    if (id == kNone || contains(id)) return;
    if (n < N) ids[n++] = id;
    else overflowed = true;
  }
  bool contains(int32_t id) const {
    for (int i = 0; i < n; ++i)
      if (ids[i] == id) return true;
    return false;
  }
  std::span<const int32_t> span() const { return {ids, static_cast<size_t>(n)}; }
};

// The most shapelets a move's Markov blanket holds (Touched::shapelets). A driven robot that
// whisks one leg over and over puts a hundred and more within a leg's link radius (docs/
// BLACKBOARD.md "A blanket too large to hold"); a move whose blanket holds more is refused
// (Blackboard::energyBefore), never evaluated on part of it.
inline constexpr int kMaxBlanketShapelets = 256;
using ShapeletSet = IdSet<kMaxBlanketShapelets>;

// What a move touches: tables, legs, walls, and working-memory slots of shapelets; and the
// walls whose ends may join or leave the touched walls (Blackboard::touchWallEnds): only their
// end terms change.
struct Touched {
  IdSet<8> tables;
  IdSet<4 * kMaxChildren> legs;
  ShapeletSet shapelets;
  IdSet<4> walls;
  IdSet<16> wall_ends;
};

// Walls are hashed at points this far apart along them (blackboard.cc).
inline constexpr double kWallHashStep = 0.25;

class Blackboard {
 public:
  Blackboard(const ModelParams& params, int working_memory, size_t reserve_hypotheses);

  const ModelParams& params() const { return p_; }

  // Attaches negative evidence (not owned; must outlive the blackboard, or pass nullptr).
  void setFreeSpace(const FreeSpaceGrid* grid) {
    free_ = grid;
    ++gen_;
  }
  bool hasFreeSpace() const { return free_ != nullptr; }
  long long freeSpaceRays() const { return free_ ? free_->rays() : 0; }
  // A wall's negative evidence: the wall cut into pieces one leg side long, each charged as a
  // leg core is (blackboard.cc); 0 without free space or where no ray crossed.
  double wallFreeTerm(const Vec2& a, const Vec2& b) const;
  // The negative-evidence term of a leg-sized square at `pose` (0 without a grid): what a leg of
  // side `side` there pays for the free whisker passes through its core.
  double freeTerm(const Pose2& pose, double side) const;

  // ---- Working memory (the queue of the most recent shapelets, §2.7) ----
  // Adds a shapelet, evicting the oldest when full. Returns its slot.
  int pushShapelet(const Shapelet& s);
  void clearShapelets();
  int workingMemoryCapacity() const { return static_cast<int>(wm_.size()); }
  int shapeletCount() const { return wm_count_; }
  // Changes whenever the working memory does (a shapelet pushed, the memory cleared): what is
  // computed from the shapelets alone may be kept while it stays the same.
  uint64_t workingMemoryGeneration() const { return wm_gen_; }
  // Shapelets in working memory without an orientation (point contacts).
  int pointShapeletCount() const { return wm_points_; }
  bool slotUsed(int slot) const { return wm_used_[static_cast<size_t>(slot)]; }
  const Shapelet& shapelet(int slot) const { return wm_[static_cast<size_t>(slot)]; }
  // Adds to `out` the slots of shapelets a leg at `p` could cause (eq. 30).
  void shapeletsNear(const Vec2& p, ShapeletSet& out) const;
  // Whether any shapelet in working memory is one a leg at `p` could cause (eq. 30).
  bool shapeletNear(const Vec2& p) const;

  // ---- Hypotheses ----
  // Adds a table of the paper's one size (ModelParams::table_width ...).
  int32_t addTable(const Pose2& pose);
  // Adds a table of its own size (the rooms model; any size, the prior judges it).
  int32_t addTable(const Pose2& pose, double width, double depth, double leg);
  // Adds a leg with the standard side under `parent` (or kNone).
  int32_t addLeg(const Pose2& pose, int32_t parent);
  // Adds a leg of side `side` under `parent` (or kNone).
  int32_t addLeg(const Pose2& pose, double side, int32_t parent);
  // Removes a table from B; its children become orphans but stay listed in its record so
  // reviveTable() can re-link them.
  void killTable(int32_t id);
  void reviveTable(int32_t id);
  void killLeg(int32_t id);
  void reviveLeg(int32_t id);
  void releaseTable(int32_t id) { tables_.release(id); }
  void releaseLeg(int32_t id) { legs_.release(id); }
  // Re-parents a live leg (kNone for the null prior).
  void setParent(int32_t leg, int32_t parent);
  void moveTable(int32_t id, const Pose2& pose);
  void moveLeg(int32_t id, const Pose2& pose);
  // Moves and resizes a table at once; children keep their parent, their corners are re-found.
  void reshapeTable(int32_t id, const Pose2& pose, double width, double depth, double leg);
  void setLegSide(int32_t id, double side);

  // ---- Walls (ModelParams::walled(): --model walls or rooms; none under kPaper) ----
  int32_t addWall(const Vec2& a, const Vec2& b);
  void killWall(int32_t id);
  void reviveWall(int32_t id);
  void releaseWall(int32_t id) { walls_.release(id); }
  void moveWall(int32_t id, const Vec2& a, const Vec2& b);
  const WallHyp& wall(int32_t id) const { return walls_[id]; }
  int32_t wallExtent() const { return walls_.extent(); }
  int liveWalls() const { return live_walls_; }
  // Calls f(id) once for every wall (alive or not) that may lie within `radius` of c (a
  // superset: check). Walls are hashed at points along their length.
  template <typename F>
  void wallsNear(const Vec2& c, double radius, F&& f) const {
    IdSet<64> seen;
    wall_hash_.query(c, radius + 0.5 * wall_hash_.cell(), [&](int32_t id) { seen.add(id); });
    for (int32_t id : seen.span()) f(id);
  }
  // Adds to t.wall_ends every live wall with an end within wallLinkRadius() of the segment
  // a..b: the walls whose end terms a wall moving from or to a..b can change. A wall move calls
  // it for each old and new segment before energyBefore().
  void touchWallEnds(Touched& t, const Vec2& a, const Vec2& b) const;
  // Whether end `e` of wall `self` meets another live wall (ModelParams::p_wall_end_free).
  bool wallEndJoined(const Vec2& e, int32_t self) const;
  // Appends to `out` the working-memory slots of shapelets within wallLinkRadius() of the
  // segment a..b that are not yet in it since the last beginCollect() (so the union over
  // several segments holds each slot once). `out` must have capacity for every slot.
  void beginCollect();
  void collectShapeletsNearSegment(const Vec2& a, const Vec2& b, std::vector<int32_t>& out);
  // The same for the shapelets a leg could cause (shapeletsNear).
  void collectShapeletsNearLeg(int32_t leg, std::vector<int32_t>& out);
  // Calls f(id) for every live leg that stands in `w`'s solid (inWallSolid).
  template <typename F>
  void legsInSolid(const WallHyp& w, F&& f) const {
    nearWall(leg_hash_, w, p_.leg_side + p_.wall_solid_depth,
             [&](int32_t o) { return legs_[o].pose.position(); }, [&](int32_t o) {
               const LegHyp& l = legs_[o];
               if (l.alive && inWallSolid(legRect(l), w)) f(o);
             });
  }

  const TableHyp& table(int32_t id) const { return tables_[id]; }
  const LegHyp& leg(int32_t id) const { return legs_[id]; }
  int32_t tableExtent() const { return tables_.extent(); }
  int32_t legExtent() const { return legs_.extent(); }
  int liveTables() const { return live_tables_; }
  int liveLegs() const { return live_legs_; }

  template <typename F>
  void tablesNear(const Vec2& c, double radius, F&& f) const {
    table_hash_.query(c, radius, [&](int32_t id) { f(id); });
  }
  template <typename F>
  void legsNear(const Vec2& c, double radius, F&& f) const {
    leg_hash_.query(c, radius, [&](int32_t id) { f(id); });
  }
  // Working-memory slots whose shapelet may lie within `radius` of c (a superset: check).
  template <typename F>
  void shapeletsWithin(const Vec2& c, double radius, F&& f) const {
    shapelet_hash_.query(c, radius, [&](int32_t slot) { f(slot); });
  }

  // The footprint of a table hypothesis and of a leg (for overlap, eq. 25).
  OrientedRect tableRect(const Pose2& pose) const { return {pose, p_.table_width, p_.table_depth}; }
  static OrientedRect tableRect(const TableHyp& t) { return {t.pose, t.width, t.depth}; }
  OrientedRect legRect(const LegHyp& l) const { return {l.pose, l.side, l.side}; }

  // ---- The log joint ----
  // Sum of every term of J that involves a touched hypothesis or shapelet, each term once.
  // Touched hypotheses that are dead contribute nothing, so before/after a move differ by the
  // move's change of J when `t` covers everything whose terms it changes.
  double localEnergy(const Touched& t) const;
  // The same plus the shapelet terms of `more_shapelets` (slots not in t.shapelets): a wall's
  // move changes the terms of every shapelet along it, more than Touched holds.
  double localEnergy(const Touched& t, std::span<const int32_t> more_shapelets) const;
  // J over the whole blackboard by brute force (tests only: quadratic). It uses the reference
  // form of every factor (factors.h), not the cached constants and cos/sin.
  double totalEnergy() const;

  // ---- Incremental energies (see the top) ----
  // The sampler's sweep: between the two, mutations are moves (energyBefore, energyAfter, then
  // acceptMove or an exact undo). Outside, a mutation invalidates the cache.
  void beginSweep() { in_sweep_ = true; }
  void endSweep() { in_sweep_ = false; }
  // localEnergy(t, more) of the state now, from the cache where it holds the term (computing and
  // caching it where not). Without incremental energies, localEnergy itself. A blanket whose
  // shapelets overflowed (t.shapelets.overflowed: more than kMaxBlanketShapelets) is +infinity
  // here and -infinity in energyAfter, so the move's change is -infinity and it is refused in
  // every acceptance (a birth and its death, a move and its reverse, have the same blanket, so
  // the refusal is symmetric); counted in blanketOverflows().
  double energyBefore(const Touched& t, std::span<const int32_t> more = {});
  // localEnergy(t, more) afresh; the own and shapelet terms are kept for acceptMove().
  double energyAfter(const Touched& t, std::span<const int32_t> more = {});
  // The same for a move whose only change since energyBefore(t) was adding leg `born` (a birth):
  // each shapelet's noisy-OR sum (eq. 17) gains one cause, so its term is its cached sum with the
  // new leg's kernel added (log-add, one kernel instead of one per cause), the rest afresh. Equal
  // to energyAfter(t) up to rounding (the audit's 1e-9); where the cache does not hold a term,
  // afresh.
  double energyAfterBirth(const Touched& t, int32_t born);
  // Moves refused because their blanket held more shapelets than kMaxBlanketShapelets.
  long long blanketOverflows() const { return blanket_overflows_; }
  // The state of the last energyAfter() is kept: its terms become the cache.
  void acceptMove();
  // Off: energyBefore() and energyAfter() are localEnergy() (the reference path, both sides of
  // every move evaluated afresh; benchmarks compare the two). On by default.
  void setIncremental(bool on);
  // The largest |cached - fresh| over every cached term (tests: the audit).
  double cacheError() const;
  // How well the live hypotheses explain working-memory slot `slot` against its background:
  // eq. 17's log(c_S + sum of its causes' kernels) - log(c_S), >= 0, 0 when no leg or wall
  // explains it; log 2 is where a cause is as probable as clutter (Sampler::sweep's priming,
  // SamplerOptions::prime_explained). From the cache where it holds the slot's term (computing
  // and caching it where not; afresh without incremental energies): a cached term is the fresh
  // one of the state it was kept in, summed in that state's order.
  double shapeletExplanation(int slot);

  // Removes every hypothesis and shapelet.
  void clear();

 private:
  // The corner of a table at `table` that `leg` belongs to: the argmin of eq. 10.
  int nearestCorner(const TableHyp& table, const LegHyp& leg) const;
  // Sets a record's pose with its cos/sin and circumradius (TableHyp::trig, LegHyp::trig).
  void setTablePose(TableHyp& t, const Pose2& pose);
  void setLegPose(LegHyp& l, const Pose2& pose);
  void linkChild(int32_t table, int32_t leg);
  void unlinkChild(int32_t table, int32_t leg);
  double tableTerms(int32_t id, const Touched& t) const;
  double legTerms(int32_t id, const Touched& t) const;
  // A live hypothesis' own terms (all but its pairs with others), and `own` plus its pair terms.
  double tableOwnTerm(const TableHyp& tab) const;
  double tablePairTerms(int32_t id, const Touched& t, double own) const;
  double legOwnTerm(const LegHyp& l) const;
  // The same own terms with a given negative-evidence term, and with the one cached for the
  // record's pose (computed and kept with that pose where not: TableHyp::free, LegHyp::free).
  double tableOwnTerm(const TableHyp& tab, double free) const;
  double legOwnTerm(const LegHyp& l, double free) const;
  double cachedTableFree(TableHyp& tab);
  double cachedLegFree(LegHyp& l);
  double legPairTerms(int32_t id, const Touched& t, double own) const;
  // Cached own and shapelet terms (computed and stored where not cached).
  double cachedTableOwn(int32_t id);
  double cachedLegOwn(int32_t id);
  double cachedShapeletTerm(int slot);
  double cachedWallOwn(int32_t id);
  void mutated() {
    if (!in_sweep_) ++gen_;
  }
  double shapeletTerm(int slot) const;
  // energyAfter's body; `born` as energyAfterBirth's, or kNone.
  double energyAfterImpl(const Touched& t, std::span<const int32_t> more, int32_t born);
  // Negative evidence at a table's four corners.
  double tableFreeTerm(const TableHyp& table) const;
  // The size priors of the rooms model (0 under the paper's).
  double tableSizeTerm(const TableHyp& t) const;
  double legSideTerm(const LegHyp& l) const;
  double wallTerms(int32_t id, const Touched& t) const;
  // A live wall's own terms (odds, length cost, negative evidence along it), and `own` plus the
  // tables and legs intruding into its solid.
  double wallOwnTerm(const WallHyp& w) const;
  double wallPairTerms(int32_t id, double own) const;
  // A live wall's end terms: logFreeWallEnd() for each end that meets no other wall.
  double wallEndTerms(int32_t id) const;
  // wallEndTerms over t.walls and t.wall_ends, each wall once.
  double touchedWallEndTerms(const Touched& t) const;
  // A footprint (a leg's, a table top's) intrudes into the wall's solid: its centre behind the
  // surface and the footprint into the band wall_solid_depth deep behind it.
  bool inWallSolid(const OrientedRect& r, const WallHyp& w) const;
  // Calls f(id) once for each id of `hash` (positions pos(id)) within `radius` of the wall's
  // segment (a superset: check): each id from the hash point nearest its projection only.
  template <typename Hash, typename Pos, typename F>
  void nearWall(const Hash& hash, const WallHyp& w, double radius, Pos&& pos, F&& f) const {
    const double len = w.length();
    const int n = std::max(1, static_cast<int>(std::ceil(len / kWallHashStep)));
    const Vec2 dir = len > 0 ? Vec2((w.b - w.a) / len) : Vec2{1.0, 0.0};
    for (int k = 0; k <= n; ++k) {
      const Vec2 q = w.a + (w.b - w.a) * (static_cast<double>(k) / n);
      hash.query(q, 0.5 * len / n + radius, [&](int32_t id) {
        const double t = len > 0 ? std::clamp((pos(id) - w.a).dot(dir) / len, 0.0, 1.0) : 0.0;
        if (static_cast<int>(std::lround(t * n)) == k) f(id);
      });
    }
  }
  // The points along a..b at which a wall is hashed.
  template <typename F>
  void wallHashPoints(const Vec2& a, const Vec2& b, F&& f) const;

  ModelParams p_;
  Pool<TableHyp> tables_;
  Pool<LegHyp> legs_;
  SpatialHash table_hash_;
  SpatialHash leg_hash_;
  SpatialHash shapelet_hash_;
  std::vector<Shapelet> wm_;
  std::vector<bool> wm_used_;
  int wm_next_ = 0;
  int wm_count_ = 0;
  uint64_t wm_gen_ = 1;
  int wm_points_ = 0;
  int live_tables_ = 0;
  int live_legs_ = 0;
  double log_eps_a_, log_eps_b_, log_eps_c_, table_odds_;
  // Constants of the terms, computed once (issue 15).
  FactorLogs logs_;
  double orphan_leg_odds_;     // a leg's presence odds under the null prior
  double paper_table_radius_;  // circumradius of the paper's one table size
  double max_table_radius_, max_leg_side_, shapelet_link_r_, wall_link_r_;
  const FreeSpaceGrid* free_ = nullptr;
  Pool<WallHyp> walls_;
  SpatialHash wall_hash_;
  std::vector<uint32_t> slot_stamp_;  // collectShapeletsNearSegment's marks
  uint32_t stamp_ = 0;
  int live_walls_ = 0;
  double wall_odds_ = 0.0;
  double log_free_wall_end_ = 0.0;
  // Incremental energies: the generation a cached term must carry to be valid, the shapelets'
  // cached terms, and the fresh terms of the last energyAfter() (capacity fixed up front).
  bool incremental_ = true;
  bool in_sweep_ = false;
  uint64_t gen_ = 1;
  long long rays_seen_ = -1;
  std::vector<double> slot_term_;
  std::vector<uint64_t> slot_gen_;
  struct Kept {
    int32_t id;
    double value;
  };
  std::array<Kept, 8> kept_tables_;
  std::array<Kept, 4 * kMaxChildren> kept_legs_;
  std::array<Kept, 4> kept_walls_;  // Touched::walls' capacity
  int n_kept_tables_ = 0, n_kept_legs_ = 0, n_kept_walls_ = 0;
  long long blanket_overflows_ = 0;
  std::vector<Kept> kept_slots_;
};

}  // namespace crunch
