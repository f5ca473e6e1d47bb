// Counts heap allocations to prove the sampler's sweep allocates nothing after warm-up
// (ARCHITECTURE.md §3). Its own executable: it replaces the global operator new.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <new>

#include "crunch/blackboard/sampler.h"
#include "test_builders.h"
#include "support/count_allocations.h"



using namespace crunch;

TEST_CASE("Sampler: anneal() performs no heap allocation after warm-up", "[blackboard]") {
  const Acceptance acceptance =
      GENERATE(Acceptance::kTempered, Acceptance::kReversibleJump);
  INFO("acceptance " << acceptanceName(acceptance));
  ModelParams p;
  Blackboard bb(p, 7, 1024);
  Rng rng(8);
  SamplerOptions opt;
  opt.acceptance = acceptance;
  Sampler sampler(bb, opt, rng);
  const std::vector<Pose2> tables = {{1, 1, 0.2}, {2.2, 1.1, 1.0}, {1.5, 2.5, 2.0}, {3, 3, 0.7}};
  std::vector<Shapelet> stream;
  for (int round = 0; round < 3; ++round)
    for (const Pose2& t : tables)
      for (const auto& s : crunch::testing::TableShapelets(t, p, {0, 1, 2, 3})) stream.push_back(s);
  // Warm-up: the first pass over the stream.
  const size_t warm = stream.size() / 3;
  for (size_t i = 0; i < warm; ++i) {
    bb.pushShapelet(stream[i]);
    if (i % 4 == 3) sampler.anneal();
  }
  long long during = 0;
  for (size_t i = warm; i < stream.size(); ++i) {
    bb.pushShapelet(stream[i]);
    if (i % 4 == 3) {
      const long long before = g_allocations;
      sampler.anneal();
      during += g_allocations - before;
    }
  }
  CHECK(sampler.stats().proposals > 1000);
  CHECK(during == 0);
}

TEST_CASE("Sampler: the rooms model's size moves perform no heap allocation after warm-up",
          "[blackboard]") {
  ModelParams p;
  p.objects = ObjectModel::kRooms;
  // Both acceptances: the reversible jump's births draw sizes and its size kernel steps them.
  const Acceptance acceptance = GENERATE(Acceptance::kTempered, Acceptance::kReversibleJump);
  INFO("acceptance " << acceptanceName(acceptance));
  Blackboard bb(p, 9, 1024);
  FreeSpaceGrid free({0, 0}, {4, 4});
  free.addRay({{0.2, 0.2}, {3.8, 3.8}});
  bb.setFreeSpace(&free);
  Rng rng(9);
  SamplerOptions so;
  so.acceptance = acceptance;
  Sampler sampler(bb, so, rng);
  // A desk, a chair, a stool and a standard table: every size move and the sized parent
  // proposal find partners.
  struct Object {
    Pose2 pose;
    double width, depth, leg;
  };
  const std::vector<Object> objects = {{{1.2, 1.0, 0.2}, 1.4, 0.7, 0.05},
                                       {{2.9, 1.0, 0.5}, 0.45, 0.45, 0.03},
                                       {{1.3, 2.6, 0.0}, 0.6, 0.6, 0.04},
                                       {{3.0, 3.0, 1.0}, 0.8, 0.5, 0.05}};
  std::vector<Shapelet> stream;
  for (int round = 0; round < 3; ++round) {
    for (const Object& o : objects) {
      ModelParams g;
      g.table_width = o.width;
      g.table_depth = o.depth;
      g.leg_side = o.leg;
      for (const auto& s : crunch::testing::TableShapelets(o.pose, g, {0, 1, 2, 3}))
        stream.push_back(s);
    }
  }
  const size_t warm = stream.size() / 3;
  for (size_t i = 0; i < warm; ++i) {
    bb.pushShapelet(stream[i]);
    if (i % 4 == 3) sampler.anneal();
  }
  long long during = 0;
  for (size_t i = warm; i < stream.size(); ++i) {
    bb.pushShapelet(stream[i]);
    if (i % 4 == 3) {
      const long long before = g_allocations;
      sampler.anneal();
      during += g_allocations - before;
    }
  }
  CHECK(sampler.stats().proposals > 1000);
  CHECK(during == 0);
}

TEST_CASE("Sampler: anneal() with walls (--model walls) performs no heap allocation after warm-up",
          "[blackboard]") {
  // Both acceptances: the paper's wall moves, and the reversible-jump sweep's wall birth/death
  // (its per-sweep segment fits) and symmetric steps.
  const Acceptance acceptance =
      GENERATE(Acceptance::kTempered, Acceptance::kReversibleJump);
  INFO("acceptance " << acceptanceName(acceptance));
  ModelParams p;
  p.objects = ObjectModel::kWalls;
  Blackboard bb(p, 96, 1024);
  FreeSpaceGrid free({0, 0}, {4, 4});
  Rng rays(2);
  for (int i = 0; i < 300; ++i) {
    const Vec2 a{rays.uniform(0.3, 3.7), rays.uniform(0.3, 3.7)};
    const double h = rays.uniform(0, 2 * kPi);
    free.addRay({a, a + 0.14 * Vec2{std::cos(h), std::sin(h)}});
  }
  bb.setFreeSpace(&free);
  Rng rng(8);
  SamplerOptions opt;
  opt.wall_birth_rate = 0.5;
  opt.acceptance = acceptance;
  Sampler sampler(bb, opt, rng);
  // Contacts along two walls of a corner (births, extends, joins, merges, splits) and a table
  // beside one.
  std::vector<Shapelet> stream;
  for (int round = 0; round < 3; ++round) {
    for (int k = 0; k < 40; ++k) {
      Shapelet s;
      s.x = 0.3 + 0.04 * k + 0.001 * round;
      s.y = 0.3 + 0.002 * ((k + round) % 3);
      s.phi = 0.0;
      s.ox = s.x;
      s.oy = s.y + 0.1;
      stream.push_back(s);
      Shapelet v = s;
      v.x = 0.3 + 0.002 * ((k + round) % 3);
      v.y = 0.35 + 0.04 * k;
      v.phi = kPi / 2;
      v.ox = v.x + 0.1;
      v.oy = v.y;
      stream.push_back(v);
    }
    for (const auto& s : crunch::testing::TableShapelets({1.2, 1.0, 0.3}, p, {0, 1, 2, 3}))
      stream.push_back(s);
  }
  const size_t warm = stream.size() / 3;
  for (size_t i = 0; i < warm; ++i) {
    bb.pushShapelet(stream[i]);
    if (i % 8 == 7) sampler.anneal();
  }
  long long during = 0;
  int most_walls = 0;
  for (size_t i = warm; i < stream.size(); ++i) {
    bb.pushShapelet(stream[i]);
    if (i % 8 == 7) {
      const long long before = g_allocations;
      sampler.anneal();
      during += g_allocations - before;
      most_walls = std::max(most_walls, bb.liveWalls());
    }
  }
  CHECK(most_walls >= 1);
  CHECK(sampler.stats().proposals > 1000);
  CHECK(during == 0);
}

TEST_CASE("Sampler: the rooms model's table split performs no heap allocation", "[blackboard]") {
  // A 1.6 m table over the outer legs of two touching 0.8 m tables, their inner legs orphans
  // (sampler_test "a table grown over two touching tables ..."): cold sweeps split it.
  ModelParams p;
  p.objects = ObjectModel::kRooms;
  ModelParams one;
  one.table_width = 0.8;
  one.table_depth = 0.5;
  const Pose2 left{1.1, 1.5, 0.0}, right{1.9, 1.5, 0.0};
  Blackboard bb(p, 16, 128);
  for (const Pose2& t : {left, right})
    for (const auto& s : crunch::testing::TableShapelets(t, one, {0, 1, 2, 3})) bb.pushShapelet(s);
  const int32_t long_table = bb.addTable({1.5, 1.5, 0.0}, 1.6, 0.5, 0.05);
  for (int c : {1, 2}) bb.addLeg(crunch::testing::LegOf(left, one, c), 0.05, long_table);
  for (int c : {0, 3}) bb.addLeg(crunch::testing::LegOf(right, one, c), 0.05, long_table);
  for (int c : {0, 3}) bb.addLeg(crunch::testing::LegOf(left, one, c), 0.05, kNone);
  for (int c : {1, 2}) bb.addLeg(crunch::testing::LegOf(right, one, c), 0.05, kNone);
  Rng rng(3);
  Sampler sampler(bb, {}, rng);
  const long long before = g_allocations;
  for (int i = 0; i < 20; ++i) sampler.sweep(20.0);
  CHECK(g_allocations - before == 0);
  CHECK(bb.liveTables() == 2);  // the split was made
}
