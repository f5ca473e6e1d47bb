// Counts heap allocations to prove the sampler's sweep allocates nothing after warm-up
// (ARCHITECTURE.md §3). Its own executable: it replaces the global operator new.
#include <catch2/catch.hpp>
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
  Blackboard bb(p, 9, 1024);
  FreeSpaceGrid free({0, 0}, {4, 4});
  free.addRay({{0.2, 0.2}, {3.8, 3.8}});
  bb.setFreeSpace(&free);
  Rng rng(9);
  Sampler sampler(bb, {}, rng);
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
