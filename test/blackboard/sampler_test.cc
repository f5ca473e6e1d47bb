#include "crunch/blackboard/sampler.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <string>
#include <tuple>
#include <cmath>
#include <utility>
#include <vector>

#include "crunch/blackboard/blackboard.h"
#include "test_builders.h"

using namespace crunch;
using crunch::testing::LegOf;
using crunch::testing::MakeShapelet;
using crunch::testing::TableShapelets;

namespace {
// Tolerances for "found the table": a third of the evaluation's 0.15 m / 15 deg, since the
// shapelets here are exact.
constexpr double kPosTol = 0.05;
constexpr double kAngTol = 5.0 * kPi / 180;

bool hasTableNear(const std::vector<Pose2>& tables, const Pose2& want) {
  for (const Pose2& t : tables)
    if (std::hypot(t.x - want.x, t.y - want.y) < kPosTol &&
        std::abs(wrapPeriod(t.theta - want.theta, kPi)) < kAngTol)
      return true;
  return false;
}

// One annealing of a working memory of `shapelets` (up to 7) with `seed`: its MAP, and the legs
// left live.
std::pair<std::vector<Pose2>, int> annealOnce(const std::vector<Shapelet>& shapelets,
                                              uint64_t seed) {
  ModelParams p;
  Blackboard bb(p, 7, 256);
  for (const Shapelet& s : shapelets)
    if (bb.shapeletCount() < 7) bb.pushShapelet(s);
  Rng rng(seed);
  Sampler sampler(bb, {}, rng);
  sampler.anneal();
  std::vector<Pose2> map;
  sampler.mapTables(map);
  return {map, bb.liveLegs()};
}
}  // namespace

TEST_CASE("Blackboard: every move's local energy change equals the brute-force change",
          "[blackboard]") {
  ModelParams p;
  Blackboard bb(p, 16, 256);
  const Pose2 a{1.0, 1.0, 0.3}, b{1.6, 1.5, 1.2};
  for (const auto& s : TableShapelets(a, p, {0, 1, 3})) bb.pushShapelet(s);
  for (const auto& s : TableShapelets(b, p, {0, 2})) bb.pushShapelet(s);
  Rng rng(11);
  SamplerOptions opt;
  opt.prime_sigma_r = 0.02;  // sloppy proposals: more overlaps, rivals and shared corners
  Sampler sampler(bb, opt, rng);
  sampler.setAudit(true);
  for (double beta : {0.05, 0.3, 1.0, 5.0}) {
    for (int i = 0; i < 6; ++i) sampler.sweep(beta);
    sampler.prune();
  }
  CHECK(sampler.stats().proposals > 500);
  CHECK(sampler.stats().audit_max_error < 1e-9);
  CHECK(sampler.stats().audit_cache_max_error < 1e-9);  // every cached term is its fresh value
}

TEST_CASE("Blackboard: energy audit holds with negative evidence attached", "[blackboard]") {
  ModelParams p;
  Blackboard bb(p, 16, 256);
  FreeSpaceGrid free({0, 0}, {3, 3});
  Rng rays(21);
  for (int i = 0; i < 400; ++i) {
    const Vec2 a{rays.uniform(0.5, 2.5), rays.uniform(0.5, 2.5)};
    const double h = rays.uniform(0, 2 * kPi);
    free.addRay({a, a + 0.14 * Vec2{std::cos(h), std::sin(h)}});
  }
  bb.setFreeSpace(&free);
  for (const auto& s : TableShapelets({1.4, 1.5, 0.2}, p, {0, 1, 2})) bb.pushShapelet(s);
  Rng rng(12);
  SamplerOptions opt;
  opt.prime_sigma_r = 0.02;
  Sampler sampler(bb, opt, rng);
  sampler.setAudit(true);
  for (double beta : {0.1, 1.0, 10.0}) {
    for (int i = 0; i < 6; ++i) sampler.sweep(beta);
    sampler.prune();
  }
  CHECK(sampler.stats().proposals > 200);  // enough moves of every kind to mean something
  CHECK(sampler.stats().audit_max_error < 1e-9);
  CHECK(sampler.stats().audit_cache_max_error < 1e-9);  // every cached term is its fresh value
}

TEST_CASE("Sampler: under reversible jump a table of the model's one size is born whatever the "
          "rooms model's size prior says",
          "[blackboard]") {
  // The paper's model with a 2.4 x 1.2 m table (beyond the rooms model's prior of at most
  // 2.0 x 1.0 m, which does not apply to it) and 10 cm legs (beyond its leg range): the births
  // through a leg and the whole-table births must still make tables of that size.
  ModelParams p;
  p.table_width = 2.4;
  p.table_depth = 1.2;
  p.leg_side = 0.1;
  Blackboard bb(p, 16, 256);
  for (const auto& s : TableShapelets({1.5, 1.5, 0.2}, p, {0, 1, 2, 3})) bb.pushShapelet(s);
  Rng rng(3);
  SamplerOptions opt;
  opt.acceptance = Acceptance::kReversibleJump;
  opt.rj_moves.table_birth_death = 0.0;  // only the births that draw a size
  Sampler sampler(bb, opt, rng);
  int max_tables = 0;
  for (double beta : {0.3, 1.0, 5.0}) {
    for (int i = 0; i < 20; ++i) {
      sampler.sweep(beta);
      max_tables = std::max(max_tables, bb.liveTables());
    }
  }
  CHECK(max_tables > 0);
  for (int32_t id = 0; id < bb.tableExtent(); ++id) {
    if (!bb.table(id).alive) continue;
    CHECK(bb.table(id).width == p.table_width);
    CHECK(bb.table(id).leg == p.leg_side);
  }
}

TEST_CASE("Sampler: every reversible-jump move's local energy change equals the brute force",
          "[blackboard]") {
  // The same two partly touched tables and negative evidence as above, under
  // Acceptance::kReversibleJump: its births, deaths, parent changes, table births/deaths through
  // a leg and jitters must each change J by what localEnergy() says.
  ModelParams p;
  Blackboard bb(p, 16, 256);
  FreeSpaceGrid free({0, 0}, {3, 3});
  Rng rays(21);
  for (int i = 0; i < 400; ++i) {
    const Vec2 a{rays.uniform(0.5, 2.5), rays.uniform(0.5, 2.5)};
    const double h = rays.uniform(0, 2 * kPi);
    free.addRay({a, a + 0.14 * Vec2{std::cos(h), std::sin(h)}});
  }
  bb.setFreeSpace(&free);
  for (const auto& s : TableShapelets({1.0, 1.0, 0.3}, p, {0, 1, 3})) bb.pushShapelet(s);
  for (const auto& s : TableShapelets({1.6, 1.5, 1.2}, p, {0, 2})) bb.pushShapelet(s);
  Rng rng(13);
  SamplerOptions opt;
  opt.acceptance = Acceptance::kReversibleJump;
  Sampler sampler(bb, opt, rng);
  sampler.setAudit(true);
  int max_tables = 0;
  for (double beta : {0.3, 1.0, 5.0, 50.0}) {
    for (int i = 0; i < 20; ++i) {
      sampler.sweep(beta);
      max_tables = std::max(max_tables, bb.liveTables());
    }
  }
  CHECK(sampler.stats().proposals > 1000);
  CHECK(max_tables > 0);  // the table moves fired
  CHECK(sampler.stats().audit_max_error < 1e-9);
  CHECK(sampler.stats().audit_cache_max_error < 1e-9);  // every cached term is its fresh value
}

TEST_CASE("Blackboard: the energy cache follows changes made outside the sampler's sweeps",
          "[blackboard]") {
  // Incremental energies keep own and shapelet terms cached between moves. Between sweeps the
  // board is changed by hand (a leg moved, a table killed, a shapelet pushed) and the grid gains
  // rays: the next sweep's moves must still change J by what the brute force says.
  ModelParams p;
  Blackboard bb(p, 16, 256);
  FreeSpaceGrid free({0, 0}, {3, 3});
  bb.setFreeSpace(&free);
  const Pose2 a{1.0, 1.0, 0.3}, b{1.6, 1.5, 1.2};
  for (const auto& s : TableShapelets(a, p, {0, 1, 3})) bb.pushShapelet(s);
  const int32_t table = bb.addTable(b);
  int32_t leg = kNone;
  for (int c = 0; c < 4; ++c) leg = bb.addLeg(LegOf(b, p, c), table);
  Rng rng(14);
  SamplerOptions opt;
  opt.prime_sigma_r = 0.02;
  opt.prune = false;
  Sampler sampler(bb, opt, rng);
  sampler.setAudit(true);
  Rng rays(22);
  for (int round = 0; round < 6; ++round) {
    for (int i = 0; i < 4; ++i) sampler.sweep(1.0);
    if (bb.leg(leg).alive) bb.moveLeg(leg, LegOf(b, p, round % 4));
    if (round == 2 && bb.table(table).alive) bb.killTable(table);
    for (const auto& s : TableShapelets(b, p, {round % 4})) bb.pushShapelet(s);
    for (int i = 0; i < 50; ++i) {
      const Vec2 q{rays.uniform(0.5, 2.5), rays.uniform(0.5, 2.5)};
      const double h = rays.uniform(0, 2 * kPi);
      free.addRay({q, q + 0.14 * Vec2{std::cos(h), std::sin(h)}});
    }
  }
  CHECK(sampler.stats().proposals > 300);
  CHECK(sampler.stats().audit_max_error < 1e-9);
  CHECK(sampler.stats().audit_cache_max_error < 1e-9);
}

TEST_CASE("Sampler: incremental and reference energies run the same chain", "[blackboard]") {
  // The cache changes how the before side of a move is found, not its value: for a seed the two
  // paths accept the same moves and end on the same map (here exactly; in general up to the last
  // bits of a sum taken in another order).
  ModelParams p;
  auto run = [&](bool incremental) {
    Blackboard bb(p, 16, 256);
    for (const auto& s : TableShapelets({1.0, 1.0, 0.3}, p, {0, 1, 3})) bb.pushShapelet(s);
    for (const auto& s : TableShapelets({1.6, 1.5, 1.2}, p, {0, 2})) bb.pushShapelet(s);
    Rng rng(15);
    SamplerOptions opt;
    opt.sweeps_per_temperature = 8;  // enough moves of every kind to part the two if they could
    opt.incremental_energy = incremental;
    Sampler sampler(bb, opt, rng);
    sampler.anneal();
    std::vector<Pose2> map;
    sampler.mapTables(map);
    return std::make_tuple(sampler.stats().proposals, sampler.stats().accepted, map);
  };
  const auto [n_inc, acc_inc, map_inc] = run(true);
  const auto [n_ref, acc_ref, map_ref] = run(false);
  CHECK(n_inc > 1000);
  CHECK(n_inc == n_ref);
  CHECK(acc_inc == acc_ref);
  REQUIRE(map_inc.size() == map_ref.size());
  REQUIRE(!map_inc.empty());
  for (size_t i = 0; i < map_inc.size(); ++i) {
    CHECK(map_inc[i].x == map_ref[i].x);
    CHECK(map_inc[i].y == map_ref[i].y);
    CHECK(map_inc[i].theta == map_ref[i].theta);
  }
}

TEST_CASE("Sampler: reversible-jump options are validated, acceptance names round-trip",
          "[blackboard]") {
  SamplerOptions o;
  o.rj_moves = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0};  // every kernel, the sizes too
  REQUIRE_FALSE(o.validate());
  CHECK(o.validate().error().message.find("rj_moves") != std::string::npos);
  o = {};
  o.rj_box_theta = 1.0;  // above pi/4: a box could wrap onto itself modulo pi/2
  CHECK(o.validate().error().message.find("rj_box_theta") != std::string::npos);
  o = {};
  o.rj_cell = 0.0;
  CHECK(o.validate().error().message.find("rj_cell") != std::string::npos);
  o = {};
  o.rj_wall_cell = -1.0;
  CHECK(o.validate().error().message.find("rj_wall_cell") != std::string::npos);
  o = {};
  o.side_prior_draws = 1.5;  // a share of the side steps
  CHECK(o.validate().error().message.find("side_prior_draws") != std::string::npos);
  o.side_prior_draws = 1.0;
  CHECK(o.validate());
  o = {};
  o.wall_join_reach = -0.1;
  CHECK(o.validate().error().message.find("wall_join_reach") != std::string::npos);
  o = {};
  o.wall_grow_gap_unseen = 11.0;  // beyond any room
  CHECK(o.validate().error().message.find("wall_grow_gap_unseen") != std::string::npos);
  o.wall_grow_gap_unseen = 0.0;  // at most wall_grow_gap: off
  CHECK(o.validate());
  o = {};
  o.rj_moves = {0, 0, 0, 0, 0, 0, 0, 1, 0};  // walls' births alone: a valid (walls model) mix
  CHECK(o.validate());
  for (Acceptance a : {Acceptance::kTempered, Acceptance::kLiteral, Acceptance::kReversibleJump})
    CHECK(acceptanceByName(acceptanceName(a)).value() == a);
  CHECK(std::string(acceptanceName(Acceptance::kTempered)) == "paper");
  CHECK_FALSE(acceptanceByName("metropolis"));
}

TEST_CASE("Sampler: free space where a rival table's legs would stand picks the real table",
          "[blackboard]") {
  // Fig. 7: two touched legs along a short side fit the true table and its mirror image. Whiskers
  // that swept the mirror's other corners untouched rule it out.
  ModelParams p;
  const Pose2 truth{2.0, 2.0, 0.0};
  // Touched: the truth's corners 2 and 3 (-y side). The mirror has them as its corners 0 and 1.
  const Pose2 mirror{2.0, 2.0 - (p.table_depth - p.leg_side), 0.0};
  FreeSpaceGrid free({0, 0}, {4, 4});
  for (int corner : {2, 3}) {
    const Pose2 leg = LegOf(mirror, p, corner);
    for (int k = 0; k < 3; ++k)
      free.addRay({{leg.x - 0.1, leg.y - 0.004 * k}, {leg.x + 0.1, leg.y - 0.004 * k}});
  }
  auto count = [&](const FreeSpaceGrid* grid) {
    std::pair<int, int> wins{0, 0};  // truth, mirror
    for (uint64_t seed = 1; seed <= 20; ++seed) {
      Blackboard bb(p, 7, 256);
      bb.setFreeSpace(grid);
      for (const auto& s : TableShapelets(truth, p, {2, 3})) bb.pushShapelet(s);
      Rng rng(seed);
      Sampler sampler(bb, {}, rng);
      sampler.anneal();
      std::vector<Pose2> map;
      sampler.mapTables(map);
      wins.first += hasTableNear(map, truth);
      wins.second += hasTableNear(map, mirror);
    }
    return wins;
  };
  const auto blind = count(nullptr);
  const auto seeing = count(&free);
  INFO("without free space: truth " << blind.first << ", mirror " << blind.second
                                    << "; with: truth " << seeing.first << ", mirror "
                                    << seeing.second);
  CHECK(blind.second >= 3);   // the ambiguity is real without negative evidence
  CHECK(seeing.second == 0);  // and gone with it
  CHECK(seeing.first >= blind.first);
}

TEST_CASE("Sampler: finds a table from shapelets on three of its legs", "[blackboard]") {
  // One annealing is a stochastic search: count successes over seeds. Measured: 36 of 40 seeds
  // put the table within 1 cm; the rest settle on a rival placement sharing two of the legs
  // (Fig. 5's T2). Require 16 of 20 within the tolerance.
  ModelParams p;
  const Pose2 truth{2.0, 1.5, 0.4};
  int found = 0;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    const auto [map, legs] = annealOnce(TableShapelets(truth, p, {0, 1, 2}), seed);
    CHECK(map.size() <= 2);
    found += hasTableNear(map, truth);
  }
  CHECK(found >= 16);
}

TEST_CASE("Sampler: contacts on faces longer than a leg prime no leg and make no table",
          "[blackboard]") {
  // The shapelets of three legs that found a table above, each now known to lie on a face 0.3 m
  // long (ContactReport::face_span): no leg can cause them, so nothing is proposed for them.
  ModelParams p;
  const Pose2 truth{2.0, 1.5, 0.4};
  std::vector<Shapelet> faces = TableShapelets(truth, p, {0, 1, 2});
  for (Shapelet& s : faces) s.face_span = 0.3;
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    const auto [map, legs] = annealOnce(faces, seed);
    CHECK(map.empty());
    CHECK(legs == 0);
  }
}

TEST_CASE("Sampler: same seed, same MAP, another seed may differ but stays valid",
          "[blackboard]") {
  auto run = [](uint64_t seed) {
    ModelParams p;
    Blackboard bb(p, 7, 256);
    for (const auto& s : TableShapelets({1.0, 2.0, 1.0}, p, {0, 3})) bb.pushShapelet(s);
    Rng rng(seed);
    Sampler sampler(bb, {}, rng);
    sampler.anneal();
    std::vector<Pose2> map;
    sampler.mapTables(map);
    return std::make_pair(map, sampler.stats().proposals);
  };
  const auto [m1, n1] = run(5);
  const auto [m2, n2] = run(5);
  REQUIRE(m1.size() == m2.size());
  CHECK(n1 == n2);
  for (size_t i = 0; i < m1.size(); ++i) {
    CHECK(m1[i].x == m2[i].x);
    CHECK(m1[i].theta == m2[i].theta);
  }
}

TEST_CASE("Sampler: no shapelets gives an empty MAP", "[blackboard]") {
  Blackboard bb(ModelParams{}, 7, 16);
  Rng rng(1);
  Sampler sampler(bb, {}, rng);
  sampler.anneal();
  std::vector<Pose2> map{{1, 1, 1}};
  sampler.mapTables(map);
  CHECK(map.empty());
  CHECK(bb.liveLegs() == 0);
}

TEST_CASE("Sampler: a single shapelet cannot make a table", "[blackboard]") {
  ModelParams p;
  Blackboard bb(p, 7, 16);
  bb.pushShapelet(MakeShapelet({1, 1, 0}, p.leg_side, 0));
  Rng rng(2);
  Sampler sampler(bb, {}, rng);
  sampler.anneal();
  std::vector<Pose2> map;
  sampler.mapTables(map);
  // One touch explains at most a leg: a table needs the evidence of two (docs/BLACKBOARD.md).
  CHECK(map.empty());
  CHECK(bb.liveLegs() <= 1);
}

TEST_CASE("Sampler: hundreds of shapelets in one spot give a valid, bounded MAP",
          "[blackboard]") {
  ModelParams p;
  Blackboard bb(p, 7, 64);
  Rng rng(4), noise(9);
  Sampler sampler(bb, {}, rng);
  for (int i = 0; i < 300; ++i) {
    Shapelet s = MakeShapelet({2, 2, 0}, p.leg_side, i % 4, noise.uniform(-0.02, 0.02));
    bb.pushShapelet(s);
    if (i % 7 == 6) sampler.anneal();
  }
  std::vector<Pose2> map;
  sampler.mapTables(map);
  CHECK(bb.shapeletCount() == 7);
  CHECK(bb.liveLegs() < 20);
  for (const Pose2& t : map) CHECK((std::isfinite(t.x) && std::isfinite(t.y) && std::isfinite(t.theta)));
}

TEST_CASE("Blackboard: a leg whisked a hundred times over: every move's blanket holds all its "
          "shapelets, and one too large to hold is refused", "[blackboard]") {
  // A driven robot that whisks one leg again and again puts more shapelets within the leg's link
  // radius than a blanket of 64 held; the moves then evaluated part of their blanket and the
  // audit saw changes that were not the brute force's.
  ModelParams p;
  const Pose2 leg{2, 2, 0};
  for (const int n : {150, kMaxBlanketShapelets + 40}) {
    Blackboard bb(p, 2 * n, 256);
    Rng noise(9);
    for (int i = 0; i < n; ++i)
      bb.pushShapelet(MakeShapelet(leg, p.leg_side, i % 4, noise.uniform(-0.02, 0.02)));
    ShapeletSet near;
    bb.shapeletsNear(leg.position(), near);
    Rng rng(4);
    Sampler sampler(bb, {}, rng);
    sampler.setAudit(true);
    for (double beta : {0.3, 1.0, 5.0}) sampler.sweep(beta);
    INFO(n << " shapelets on the leg");
    if (n <= kMaxBlanketShapelets) {
      CHECK(near.n == n);
      CHECK_FALSE(near.overflowed);
      CHECK(bb.blanketOverflows() == 0);
      CHECK(bb.liveLegs() > 0);  // the leg is found
      CHECK(sampler.stats().audit_max_error < 1e-9);
      CHECK(sampler.stats().audit_cache_max_error < 1e-9);
    } else {
      CHECK(near.n == kMaxBlanketShapelets);
      CHECK(near.overflowed);
      // Every move at the leg is refused, none is evaluated on part of its blanket.
      CHECK(bb.blanketOverflows() > 0);
      CHECK(bb.liveLegs() == 0);
      CHECK(sampler.stats().audit_max_error < 1e-9);
    }
  }
}

TEST_CASE("Sampler: pruning removes hypotheses whose shapelets left working memory",
          "[blackboard]") {
  ModelParams p;
  Blackboard bb(p, 7, 256);
  for (const auto& s : TableShapelets({1, 1, 0}, p, {0, 1, 2})) bb.pushShapelet(s);
  Rng rng(6);
  Sampler sampler(bb, {}, rng);
  sampler.anneal();
  REQUIRE(bb.liveTables() >= 1);
  // Seven shapelets far away push the table's evidence out of working memory.
  for (const auto& s : TableShapelets({3.5, 3.5, 0}, p, {0, 1, 2, 3})) {
    bb.pushShapelet(s);
  }
  sampler.prune();
  for (int32_t id = 0; id < bb.tableExtent(); ++id)
    if (bb.table(id).alive) CHECK(bb.table(id).pose.x > 2.5);
  for (int32_t id = 0; id < bb.legExtent(); ++id)
    if (bb.leg(id).alive) CHECK(bb.leg(id).pose.x > 2.5);
}

TEST_CASE("Sampler: options validate themselves", "[blackboard]") {
  SamplerOptions o;
  CHECK(o.validate().ok());
  o.r1 = 0.5;
  o.r2 = 0.2;
  CHECK_FALSE(o.validate().ok());
}

TEST_CASE("Sampler: an explained shapelet is primed at prime_explained, an unexplained one every "
          "sweep, and the move counts add up",
          "[blackboard]") {
  ModelParams p;
  const Pose2 table{1.0, 1.0, 0.3};
  const std::vector<Shapelet> on_table = TableShapelets(table, p, {0, 1, 2, 3});
  // Two contacts far from the table and from each other, no leg at either (and a leg born at
  // one cannot explain the other).
  const std::vector<Shapelet> lone = {MakeShapelet({3.0, 3.0, 0.0}, p.leg_side, 0),
                                      MakeShapelet({3.0, 0.5, 0.0}, p.leg_side, 1)};
  auto board = [&](Blackboard& bb) {
    for (const Shapelet& s : on_table) bb.pushShapelet(s);
    for (const Shapelet& s : lone) bb.pushShapelet(s);
    const int32_t id = bb.addTable(table);
    for (int c = 0; c < 4; ++c) bb.addLeg(LegOf(table, p, c), id);
  };
  const int n = static_cast<int>(on_table.size() + lone.size());
  {
    Blackboard bb(p, n, 256);
    board(bb);
    for (int slot = 0; slot < n; ++slot) {
      const bool on_leg = slot < static_cast<int>(on_table.size());
      CHECK((bb.shapeletExplanation(slot) >= std::log(2.0)) == on_leg);
      if (!on_leg) CHECK(bb.shapeletExplanation(slot) == 0.0);  // only the background: log 1
    }
  }
  const double cold = std::exp(7.5);
  for (double share : {0.0, 1.0}) {  // one sweep: exactly the unexplained, or every shapelet
    Blackboard bb(p, n, 256);
    board(bb);
    Rng rng(3);
    SamplerOptions opt;
    opt.prime_explained = share;
    Sampler sampler(bb, opt, rng);
    sampler.sweep(cold);
    const MoveCounts& m = sampler.stats().by_move;
    CHECK(m[static_cast<size_t>(MoveKind::kPrime)].proposals ==
          (share == 0.0 ? static_cast<long long>(lone.size()) : n));
    long long total = 0, taken = 0;
    for (const MoveCount& c : m) {
      total += c.proposals;
      taken += c.accepted;
      CHECK(c.accepted <= c.proposals);
    }
    CHECK(total == sampler.stats().proposals);
    CHECK(taken == sampler.stats().accepted);
  }
  // Over many cold sweeps of the explained table alone, each shapelet is primed in a share of
  // them (binomial: within 5 sd), and the table stays: its shapelets stay explained.
  Blackboard bb(p, static_cast<int>(on_table.size()), 256);
  for (const Shapelet& s : on_table) bb.pushShapelet(s);
  const int32_t id = bb.addTable(table);
  for (int c = 0; c < 4; ++c) bb.addLeg(LegOf(table, p, c), id);
  Rng rng(5);
  SamplerOptions opt;
  opt.prime_explained = 0.3;
  Sampler sampler(bb, opt, rng);
  constexpr int kSweeps = 400;
  for (int i = 0; i < kSweeps; ++i) sampler.sweep(cold);
  const double trials = static_cast<double>(kSweeps * on_table.size());
  const double primes =
      static_cast<double>(sampler.stats().by_move[static_cast<size_t>(MoveKind::kPrime)].proposals);
  CHECK(std::abs(primes - 0.3 * trials) < 5.0 * std::sqrt(trials * 0.3 * 0.7));
  for (int slot = 0; slot < static_cast<int>(on_table.size()); ++slot)
    CHECK(bb.shapeletExplanation(slot) >= std::log(2.0));
  opt.prime_explained = 1.5;
  CHECK_FALSE(opt.validate().ok());
}

// ---------------------------------------------------------------- the rooms model (issue 13)

namespace {
// The model's geometry for one object of its own size (the builders read it from ModelParams).
ModelParams objectOfSize(double width, double depth, double leg) {
  ModelParams o;
  o.table_width = width;
  o.table_depth = depth;
  o.leg_side = leg;
  return o;
}

ModelParams roomsModel() {
  ModelParams p;
  p.objects = ObjectModel::kRooms;
  return p;
}
}  // namespace

TEST_CASE("Rooms model: every move's local energy change equals the brute-force change, sizes "
          "and negative evidence included",
          "[blackboard]") {
  ModelParams p = roomsModel();
  // The catalog over every side, or over the sides the evidence fixes (its term then changes
  // with the contacts and passes near each corner).
  p.catalog_fixed_sides = GENERATE(false, true);
  INFO("catalog_fixed_sides " << p.catalog_fixed_sides);
  Blackboard bb(p, 32, 512);
  FreeSpaceGrid free({0, 0}, {4, 4});
  Rng rays(31);
  for (int i = 0; i < 400; ++i) {
    const Vec2 a{rays.uniform(0.5, 3.5), rays.uniform(0.5, 3.5)};
    const double h = rays.uniform(0, 2 * kPi);
    free.addRay({a, a + 0.14 * Vec2{std::cos(h), std::sin(h)}});
  }
  bb.setFreeSpace(&free);
  // A desk, a chair tucked against it, and a stool: three sizes, close enough to overlap.
  for (const auto& s : TableShapelets({1.5, 1.5, 0.1}, objectOfSize(1.4, 0.7, 0.05), {0, 1, 2}))
    bb.pushShapelet(s);
  for (const auto& s : TableShapelets({1.6, 2.2, 0.15}, objectOfSize(0.45, 0.45, 0.03), {0, 1, 3}))
    bb.pushShapelet(s);
  for (const auto& s : TableShapelets({2.8, 2.6, 0.0}, objectOfSize(0.6, 0.6, 0.04), {0, 2}))
    bb.pushShapelet(s);
  // Both acceptances: the reversible jump's births of sized tables and its size kernel.
  const Acceptance acceptance = GENERATE(Acceptance::kTempered, Acceptance::kReversibleJump);
  INFO("acceptance " << acceptanceName(acceptance));
  Rng rng(13);
  SamplerOptions opt;
  opt.acceptance = acceptance;
  opt.prime_sigma_r = 0.02;  // sloppy proposals: more overlaps, rivals and shared corners
  opt.side_prior_draws = 0.5;  // leg sides from the prior too: larger steps of every side move
  Sampler sampler(bb, opt, rng);
  sampler.setAudit(true);
  if (acceptance == Acceptance::kReversibleJump) sampler.enterReversibleSpace();
  bool resized = false;
  for (double beta : {0.05, 0.3, 1.0, 5.0}) {
    for (int i = 0; i < 10; ++i) {
      sampler.sweep(beta);
      for (int32_t id = 0; id < bb.tableExtent(); ++id)
        resized |= bb.table(id).alive && std::abs(bb.table(id).width - p.table_width) > 1e-6;
    }
    if (acceptance != Acceptance::kReversibleJump) sampler.prune();  // rj never prunes
  }
  CHECK(resized);  // tables of other sizes than the paper's were proposed and kept
  CHECK(sampler.stats().proposals > 1000);
  CHECK(sampler.stats().audit_max_error < 1e-9);
  CHECK(sampler.stats().audit_cache_max_error < 1e-9);  // every cached term is its fresh value
}

TEST_CASE("Rooms model: the catalog counts the sides whose both ends the evidence reaches",
          "[blackboard]") {
  // Two boards with one catalog-size table, the catalog over every side on one and over the
  // fixed sides on the other: their log joints differ by the size terms alone.
  ModelParams all = roomsModel(), fixed = roomsModel();
  all.catalog_fixed_sides = false;
  fixed.catalog_fixed_sides = true;
  Blackboard a(all, 32, 64), b(fixed, 32, 64);
  const Pose2 table{1.5, 1.5, 0.3};
  for (Blackboard* bb : {&a, &b}) bb->addTable(table, 0.8, 0.5, 0.05);
  const double both = all.logCatalogFactor(0.8, 0.5);
  const double one = all.logCatalogFactor(0.8, 0.5, true, false);
  // Nothing near any corner: nothing fixed.
  CHECK(b.totalEnergy() - a.totalEnergy() == Approx(-both));
  // Contacts off corners 0 and 1 (the width's ends): the width alone.
  for (const auto& s : TableShapelets(table, all, {0, 1}))
    for (Blackboard* bb : {&a, &b}) bb->pushShapelet(s);
  CHECK(b.totalEnergy() - a.totalEnergy() == Approx(one - both));
  // Whisker passes by corner 2 as well (negative evidence attached): the depth too, 1 to 2.
  FreeSpaceGrid free({0, 0}, {3, 3});
  const Vec2 c2 = table.toWorld(all.cornerOffset(2));
  free.addRay({c2 + Vec2{0.06, -0.08}, c2 + Vec2{0.12, -0.08}});
  for (Blackboard* bb : {&a, &b}) bb->setFreeSpace(&free);
  CHECK(b.totalEnergy() - a.totalEnergy() == Approx(0.0).margin(1e-9));
}

TEST_CASE("Rooms model: annealing finds a chair's and a desk's size from their legs",
          "[blackboard]") {
  const ModelParams p = roomsModel();
  struct Object {
    Pose2 pose;
    double width, depth, leg;
  };
  const Object objects[] = {{{1.2, 1.2, 0.2}, 1.4, 0.7, 0.05}, {{3.0, 1.3, 0.4}, 0.45, 0.45, 0.03}};
  int found[2] = {0, 0};
  constexpr int kSeeds = 5;
  for (uint64_t seed = 1; seed <= kSeeds; ++seed) {
    Blackboard bb(p, 16, 512);
    for (const Object& o : objects)
      for (const auto& s :
           TableShapelets(o.pose, objectOfSize(o.width, o.depth, o.leg), {0, 1, 2, 3}))
        bb.pushShapelet(s);
    Rng rng(seed);
    Sampler sampler(bb, {}, rng);
    sampler.anneal();
    std::vector<TableHyp> map;
    sampler.mapTables(map);
    for (int k = 0; k < 2; ++k) {
      const Object& o = objects[k];
      for (const TableHyp& t : map) {
        // Either way round: a w x d table at theta is the d x w one at theta + pi/2.
        const bool same = std::abs(t.width - o.width) < 0.03 && std::abs(t.depth - o.depth) < 0.03;
        const bool swapped =
            std::abs(t.width - o.depth) < 0.03 && std::abs(t.depth - o.width) < 0.03;
        // The leg side is not judged: shapelets on a leg's two outer faces fix its outer edges,
        // not its side (a thicker leg with its centre further in fits them as well).
        if (std::hypot(t.pose.x - o.pose.x, t.pose.y - o.pose.y) < kPosTol && (same || swapped)) {
          ++found[k];
          break;
        }
      }
    }
  }
  // The desk: 4 of 5 seeds before walls joined the rooms model, 3 of 5 with them. Its legs'
  // faces along a side lie in one line and a wall birth can take them (docs/BLACKBOARD.md,
  // "Walls": tables lost to walls, the open failure of the merged model); the bound says so
  // rather than hiding it. The chair has no such line.
  CHECK(found[0] >= kSeeds - 2);
  CHECK(found[1] >= kSeeds - 1);
}

TEST_CASE("Rooms model: a table grown over two touching tables splits at their inner legs",
          "[blackboard]") {
  // Two 0.8 x 0.5 tables side by side, every leg touched; the chain holds one 1.6 x 0.5 table on
  // the pair's four outer legs and the four inner legs as orphans (what the rooms model's chains
  // fall into on adjacent_tables). Splitting is uphill by every other single move: a new table on
  // the inner legs overlaps the long one (eps_b), and shrinking the long one leaves its far legs.
  // Cold (beta 20), the split at an inner orphan reaches the pair in one move.
  const ModelParams p = roomsModel();
  const ModelParams one = objectOfSize(0.8, 0.5, 0.05);
  const Pose2 frame{1.5, 1.5, 0.4};
  const Pose2 left{frame.toWorld({-0.4, 0.0}).x(), frame.toWorld({-0.4, 0.0}).y(), frame.theta};
  const Pose2 right{frame.toWorld({0.4, 0.0}).x(), frame.toWorld({0.4, 0.0}).y(), frame.theta};
  const auto split_on = [&](bool split) {
    int n = 0;
    for (uint64_t seed = 1; seed <= 10; ++seed) {
      Blackboard bb(p, 16, 128);
      for (const Pose2& t : {left, right})
        for (const auto& s : TableShapelets(t, one, {0, 1, 2, 3})) bb.pushShapelet(s);
      const int32_t long_table = bb.addTable(frame, 1.6, 0.5, 0.05);
      for (int c : {1, 2}) bb.addLeg(LegOf(left, one, c), 0.05, long_table);
      for (int c : {0, 3}) bb.addLeg(LegOf(right, one, c), 0.05, long_table);
      for (int c : {0, 3}) bb.addLeg(LegOf(left, one, c), 0.05, kNone);
      for (int c : {1, 2}) bb.addLeg(LegOf(right, one, c), 0.05, kNone);
      Rng rng(seed);
      SamplerOptions opt;
      opt.split_tables = split;
      Sampler sampler(bb, opt, rng);
      sampler.setAudit(true);
      for (int i = 0; i < 20; ++i) sampler.sweep(20.0);
      CHECK(sampler.stats().audit_max_error < 1e-9);
      CHECK(sampler.stats().audit_cache_max_error < 1e-9);
      std::vector<TableHyp> map;
      sampler.mapTables(map);
      int pair = 0;
      for (const TableHyp& t : map)
        for (const Pose2& want : {left, right})
          pair += std::hypot(t.pose.x - want.x, t.pose.y - want.y) < kPosTol &&
                  std::abs(std::max(t.width, t.depth) - 0.8) < 0.03;
      n += pair == 2 && map.size() == 2;
    }
    return n;
  };
  const int with = split_on(true), without = split_on(false);
  INFO("the pair found on " << with << " of 10 seeds with the split, " << without << " without");
  CHECK(with >= 8);
  CHECK(without <= 2);
}

TEST_CASE("Rooms model: the paper's model keeps its one size", "[blackboard]") {
  // Under kPaper no move changes a size: every table is the paper's, every leg its side.
  ModelParams p;
  Blackboard bb(p, 16, 256);
  for (const auto& s : TableShapelets({1.0, 1.0, 0.3}, p, {0, 1, 3})) bb.pushShapelet(s);
  Rng rng(5);
  Sampler sampler(bb, {}, rng);
  sampler.anneal();
  for (double beta : {0.1, 1.0}) sampler.sweep(beta);
  for (int32_t id = 0; id < bb.tableExtent(); ++id) {
    if (!bb.table(id).alive) continue;
    CHECK(bb.table(id).width == p.table_width);
    CHECK(bb.table(id).depth == p.table_depth);
    CHECK(bb.table(id).leg == p.leg_side);
  }
  for (int32_t id = 0; id < bb.legExtent(); ++id)
    if (bb.leg(id).alive) CHECK(bb.leg(id).side == p.leg_side);
}

TEST_CASE("Blackboard: the point contacts in working memory are counted as they come and go",
          "[blackboard]") {
  // Sampler::partnersNear scans the shapelets around a leg for point contacts only when there
  // are any (the gaussian sensor's are all oriented).
  ModelParams p;
  Blackboard bb(p, 3, 16);
  Shapelet point = MakeShapelet({1, 1, 0}, p.leg_side, 0, 0.0);
  point.oriented = false;
  const Shapelet face = MakeShapelet({1, 1, 0}, p.leg_side, 1, 0.0);
  bb.pushShapelet(point);
  bb.pushShapelet(face);
  bb.pushShapelet(point);
  CHECK(bb.pointShapeletCount() == 2);
  bb.pushShapelet(face);  // evicts the first point
  CHECK(bb.pointShapeletCount() == 1);
  bb.pushShapelet(face);
  bb.pushShapelet(face);  // evicts the second
  CHECK(bb.pointShapeletCount() == 0);
  bb.pushShapelet(point);
  bb.clearShapelets();
  CHECK(bb.pointShapeletCount() == 0);
}
