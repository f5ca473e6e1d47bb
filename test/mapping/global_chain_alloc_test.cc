// Counts heap allocations to prove the global inference's chains anneal without allocating
// (ARCHITECTURE.md §3), as Mapper::finish runs them: built first, then annealed on two threads
// at once. Each thread counts its own allocations (support/count_allocations.h t_allocations),
// so one chain's count is not another's. Its own executable: it replaces the global operator new.
#include <catch2/catch.hpp>
#include <cmath>
#include <memory>
#include <vector>

#include "blackboard/test_builders.h"
#include "crunch/core/parallel.h"
#include "crunch/mapping/global_chain.h"
#include "support/count_allocations.h"

using namespace crunch;

TEST_CASE("GlobalChain: chains annealing on two threads perform no heap allocation",
          "[mapping]") {
  const ObjectModel model = GENERATE(ObjectModel::kPaper, ObjectModel::kWalls, ObjectModel::kRooms);
  INFO("model " << objectModelName(model));
  MappingOptions o;
  o.model.objects = model;
  o.global_sweeps = 2;
  // Evidence of four tables and a wall, and free space around them.
  std::vector<Shapelet> run;
  for (int round = 0; round < 2; ++round) {
    for (const Pose2& t : {Pose2{1.0, 1.0, 0.2}, Pose2{2.2, 1.1, 1.0}, Pose2{1.5, 2.5, 2.0},
                           Pose2{3.0, 3.0, 0.7}})
      for (const Shapelet& s : crunch::testing::TableShapelets(t, o.model, {0, 1, 2, 3}))
        run.push_back(s);
    for (int k = 0; k < 30; ++k) {
      Shapelet s;
      s.x = 0.3 + 0.05 * k + 0.002 * round;
      s.y = 0.2;
      s.phi = 0.0;
      s.ox = s.x;
      s.oy = 0.3;
      run.push_back(s);
    }
  }
  FreeSpaceGrid free({0, 0}, {4, 4});
  Rng rays(3);
  for (int i = 0; i < 300; ++i) {
    const Vec2 a{rays.uniform(0.3, 3.7), rays.uniform(0.3, 3.7)};
    const double h = rays.uniform(0, 2 * kPi);
    free.addRay({a, a + 0.14 * Vec2{std::cos(h), std::sin(h)}});
  }
  constexpr int kChains = 4;
  const std::vector<Rng> streams = globalChainStreams(o.seed, kChains);
  std::vector<std::unique_ptr<GlobalChain>> chains;
  for (const Rng& s : streams) chains.push_back(std::make_unique<GlobalChain>(run, &free, o, s));

  std::vector<long long> during(kChains, -1);
  std::vector<long long> probe(kChains, -1);
  parallelFor(kChains, 2, [&](int c) {
    // The counter counts on this thread: one allocation shows as one.
    const long long p0 = t_allocations;
    int* volatile escaped = new int(c);  // volatile: the pair cannot be elided
    delete escaped;
    probe[static_cast<size_t>(c)] = t_allocations - p0;
    const long long before = t_allocations;
    chains[static_cast<size_t>(c)]->anneal();
    during[static_cast<size_t>(c)] = t_allocations - before;
  });
  for (int c = 0; c < kChains; ++c) {
    INFO("chain " << c);
    CHECK(probe[static_cast<size_t>(c)] == 1);
    CHECK(during[static_cast<size_t>(c)] == 0);
    const ChainResult r = chains[static_cast<size_t>(c)]->result();
    CHECK(r.proposals > 1000);
    CHECK(r.live_legs >= 1);
  }
}
