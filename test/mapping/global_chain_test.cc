// Tests of one global-inference chain (crunch/mapping/global_chain.h): its result is a function
// of its stream alone, the streams are split from the seed, and the per-pose hooks stay out.
#include "crunch/mapping/global_chain.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "blackboard/test_builders.h"
#include "crunch/core/parallel.h"

using namespace crunch;

namespace {

// Shapelets off every corner of three tables, twice over (a run's worth of evidence).
std::vector<Shapelet> threeTables(const ModelParams& p) {
  std::vector<Shapelet> run;
  for (int round = 0; round < 2; ++round)
    for (const Pose2& t : {Pose2{1.0, 1.0, 0.2}, Pose2{2.4, 1.2, 1.1}, Pose2{1.6, 2.6, -0.4}})
      for (const Shapelet& s : crunch::testing::TableShapelets(t, p, {0, 1, 2, 3})) run.push_back(s);
  return run;
}

MappingOptions chainOptions() {
  MappingOptions o;
  o.global_sweeps = 2;
  return o;
}

bool sameResult(const ChainResult& a, const ChainResult& b) {
  if (a.tables.size() != b.tables.size() || a.walls.size() != b.walls.size()) return false;
  for (size_t i = 0; i < a.tables.size(); ++i) {
    const Pose2& x = a.tables[i].pose;
    const Pose2& y = b.tables[i].pose;
    if (x.x != y.x || x.y != y.y || x.theta != y.theta) return false;
  }
  return a.proposals == b.proposals && a.live_tables == b.live_tables &&
         a.live_legs == b.live_legs && a.sample_count == b.sample_count &&
         a.samples.size() == b.samples.size();
}

ChainResult runOne(const std::vector<Shapelet>& run, const MappingOptions& o, Rng stream) {
  GlobalChain chain(run, nullptr, o, stream);
  chain.anneal();
  return chain.result();
}

}  // namespace

TEST_CASE("globalChainStreams: one generator per chain, the same for any chain count",
          "[mapping]") {
  const std::vector<Rng> three = globalChainStreams(5, 3);
  const std::vector<Rng> five = globalChainStreams(5, 5);
  REQUIRE(three.size() == 3);
  REQUIRE(five.size() == 5);
  for (size_t c = 0; c < 3; ++c) CHECK(three[c].state() == five[c].state());
  for (size_t c = 1; c < 5; ++c) CHECK(five[c].state() != five[c - 1].state());
  CHECK(globalChainStreams(6, 1)[0].state() != five[0].state());  // from the seed
}

TEST_CASE("GlobalChain: the result depends on its stream only, not on chains beside it",
          "[mapping]") {
  const MappingOptions o = chainOptions();
  const std::vector<Shapelet> run = threeTables(o.model);
  const std::vector<Rng> streams = globalChainStreams(o.seed, 4);
  // Alone, one after the other.
  std::vector<ChainResult> alone;
  for (const Rng& s : streams) alone.push_back(runOne(run, o, s));
  // Four at once on four threads.
  std::vector<ChainResult> together(streams.size());
  parallelFor(4, 4, [&](int c) {
    together[static_cast<size_t>(c)] = runOne(run, o, streams[static_cast<size_t>(c)]);
  });
  for (size_t c = 0; c < streams.size(); ++c) {
    INFO("chain " << c);
    // Not a trivial chain (about 800 proposals since the chains prime an explained shapelet in
    // one sweep of ten, MappingOptions::global_prime_explained; 2,500 before).
    CHECK(alone[c].proposals > 500);
    CHECK(sameResult(alone[c], together[c]));
  }
  // Not vacuous: the chains' own streams make them differ.
  CHECK(alone[0].proposals != alone[1].proposals);
  // The tables of the evidence are found.
  CHECK(alone[0].tables.size() >= 3);
}

TEST_CASE("GlobalChain: kMarginal samples number this chain's sweeps from 0", "[mapping]") {
  MappingOptions o = chainOptions();
  o.chain_fusion = ChainFusion::kMarginal;
  const ChainResult r = runOne(threeTables(o.model), o, globalChainStreams(o.seed, 1)[0]);
  CHECK(r.sample_count == o.marginal_steps * o.global_sweeps);
  REQUIRE_FALSE(r.samples.empty());
  for (const ObjectSample& s : r.samples) {
    CHECK(s.sample >= 0);
    CHECK(s.sample < r.sample_count);
  }
}

TEST_CASE("GlobalChain: the per-pose hooks are not called by a global chain", "[mapping]") {
  MappingOptions o = chainOptions();
  int calls = 0;
  o.sampler.after_temperature = [&calls](int, double, const Blackboard&) { ++calls; };
  o.sampler.after_sweep = [&calls](int, int, double, const Blackboard&) { ++calls; };
  const SamplerOptions so = globalSamplerOptions(o);
  CHECK(so.sweeps_per_temperature == o.global_sweeps);
  CHECK_FALSE(so.after_temperature);
  CHECK_FALSE(so.after_sweep);
  const ChainResult r = runOne(threeTables(o.model), o, globalChainStreams(o.seed, 1)[0]);
  CHECK(r.proposals > 0);
  CHECK(calls == 0);
}

TEST_CASE("GlobalChain: under kRooms a kMarginal sample carries its table's own size",
          "[mapping]") {
  // A 0.45 m chair with 3 cm legs: samples written as the map writes tables (width >= depth,
  // mapper.h's sizedTable), not at the paper's 0.80 x 0.50 m.
  MappingOptions o = chainOptions();
  o.chain_fusion = ChainFusion::kMarginal;
  o.model.objects = ObjectModel::kRooms;
  ModelParams chair = o.model;
  chair.table_width = chair.table_depth = 0.45;
  chair.leg_side = 0.03;
  const Pose2 at{1.0, 1.0, 0.3};
  std::vector<Shapelet> run;
  for (int round = 0; round < 2; ++round)
    for (const Shapelet& s : crunch::testing::TableShapelets(at, chair, {0, 1, 2, 3})) run.push_back(s);
  // Whiskers swept under the chair between its legs, along both of its axes: without them four
  // walls boxing the legs' outer faces explain the same shapelets.
  FreeSpaceGrid free({0, 0}, {2, 2});
  for (int pass = 0; pass < 3; ++pass) {
    free.addRay({at.toWorld({-0.4, 0.0}), at.toWorld({0.4, 0.0})});
    free.addRay({at.toWorld({0.0, -0.4}), at.toWorld({0.0, 0.4})});
  }
  GlobalChain chain(run, &free, o, globalChainStreams(o.seed, 1)[0]);
  chain.anneal();
  const ChainResult r = chain.result();
  int near = 0;
  for (const ObjectSample& s : r.samples) {
    if (std::hypot(s.pose.x - at.x, s.pose.y - at.y) > 0.05) continue;
    ++near;
    CHECK(s.shape[0] >= s.shape[1]);
    CHECK(s.shape[0] == Approx(0.45).margin(0.05));
    CHECK(s.shape[1] == Approx(0.45).margin(0.05));
    CHECK(s.shape[2] < 0.08);
  }
  CHECK(near > r.sample_count / 2);  // the chair is held in most samples
}
