// Tests of the orphan-leg completion (crunch/exploration/draw_completion.h): every completed
// table holds the orphan at a corner with its axes along the leg's faces and a size from the
// prior; on unknown floor the eight placements are equally likely; no completed leg stands in
// swept floor or outside the region, no top overlaps the draw's tables; a leg boxed in by swept
// floor stays an orphan; and the completions make infogain's draws disagree where the orphan's
// other legs may stand.
#include "crunch/exploration/draw_completion.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <vector>

#include "crunch/exploration/infogain_policy.h"

using namespace crunch;
using namespace crunch::exploration;

namespace {

const MapLeg kOrphan{{2.0, 2.0, 0.3}, 0.05};

// The corner of `t` nearest `p` and its distance.
int cornerAt(const MapTable& t, const Vec2& p, double* distance) {
  int best = -1;
  double d = 1e9;
  for (int i = 0; i < 4; ++i) {
    const double di =
        (t.pose.toWorld(ModelParams::cornerOffset(i, t.width, t.depth, t.leg)) - p).norm();
    if (di < d) d = di, best = i;
  }
  *distance = d;
  return best;
}

// The table's turn relative to the leg's faces, in quarter turns modulo a half turn (0 or 1).
int quarterTurns(const MapTable& t, const MapLeg& leg) {
  const double q = (t.pose.theta - leg.pose.theta) / (0.5 * kPi);
  const long n = std::lround(q);
  REQUIRE(std::abs(q - static_cast<double>(n)) < 1e-9);  // axes along the leg's faces
  return static_cast<int>(((n % 2) + 2) % 2);
}

MapSample orphanDraw() {
  MapSample s;
  s.legs.push_back(kOrphan);
  return s;
}

}  // namespace

TEST_CASE("Orphan completion: the leg stands at a corner of a prior-sized table, the eight "
          "placements equally likely on unknown floor",
          "[exploration][completion]") {
  KnownSpace known({0.0, 0.0}, {4.0, 4.0}, 0.05);
  ModelParams model;  // the paper's one size
  Rng rng(7);
  std::map<std::pair<int, int>, int> placements;
  const int n = 4000;
  for (int i = 0; i < n; ++i) {
    MapSample s = orphanDraw();
    REQUIRE(completeOrphanLegs(s, known, model, rng) == 1);
    REQUIRE(s.legs.empty());
    REQUIRE(s.tables.size() == 1);
    const MapTable& t = s.tables[0];
    CHECK(t.width == model.table_width);
    CHECK(t.depth == model.table_depth);
    CHECK(t.leg == model.leg_side);
    double d;
    const int k = cornerAt(t, kOrphan.pose.position(), &d);
    CHECK(d < 1e-9);
    ++placements[{k, quarterTurns(t, kOrphan)}];
  }
  REQUIRE(placements.size() == 8);
  // Each placement 1/8: 500 expected, sd ~21; 6 sd either side.
  for (const auto& [key, count] : placements) CHECK(std::abs(count - n / 8) < 130);
}

TEST_CASE("Orphan completion: no completed leg in swept floor or outside, no overlap with the "
          "draw's tables",
          "[exploration][completion]") {
  KnownSpace known({0.0, 0.0}, {4.0, 4.0}, 0.05);
  // Everything west of x = 1.9 has been swept free: the table must extend east.
  for (double y = 0.025; y < 4.0; y += 0.05) known.markFreeRay({Vec2(0.01, y), Vec2(1.88, y)});
  ModelParams model;
  model.objects = ObjectModel::kRooms;
  // A table of the draw north of the leg: no completion may overlap it.
  MapTable north;
  north.pose = {2.6, 3.0, 0.0};
  north.width = 1.2;
  north.depth = 0.8;
  Rng rng(11);
  double min_w = 10.0, max_w = 0.0;
  for (int i = 0; i < 2000; ++i) {
    MapSample s = orphanDraw();
    s.tables.push_back(north);
    REQUIRE(completeOrphanLegs(s, known, model, rng) == 1);
    REQUIRE(s.tables.size() == 2);
    const MapTable& t = s.tables[1];
    CHECK(std::isfinite(model.logSizePrior(t.width, t.depth, t.leg)));
    CHECK(t.leg == kOrphan.side);
    for (int c = 0; c < 4; ++c) {
      const Vec2 q = t.pose.toWorld(ModelParams::cornerOffset(c, t.width, t.depth, t.leg));
      CHECK_FALSE(known.outside(q));
      CHECK(known.at(q) != KnownSpace::Cell::kFree);
      CHECK(q.x() > 1.85);
    }
    CHECK_FALSE(overlaps(OrientedRect{t.pose, t.width, t.depth},
                         OrientedRect{north.pose, north.width, north.depth}));
    min_w = std::min(min_w, std::max(t.width, t.depth));
    max_w = std::max(max_w, std::max(t.width, t.depth));
  }
  // Sizes from the whole prior that fits (the longer side up to the region's room for it).
  CHECK(min_w < 0.45);
  CHECK(max_w > 1.5);
}

TEST_CASE("Orphan completion: sizes from the rooms model's own prior, the catalog's at its "
          "weight", "[exploration][completion]") {
  // On unknown floor every proposal is admissible, so the completed sizes are the prior's: the
  // catalog's size (each side within 5 sigma of it) in a share catalog_weight of the draws, the
  // uniform part otherwise (where a side within 2.5 cm of the catalog's has probability < 5 %).
  KnownSpace known({0.0, 0.0}, {4.0, 4.0}, 0.05);
  ModelParams model;
  model.objects = ObjectModel::kRooms;
  const auto catalog = [&](const MapTable& t) {
    const double tol = 5.0 * model.catalog_sigma;
    return (std::abs(t.width - model.table_width) < tol && std::abs(t.depth - model.table_depth) < tol) ||
           (std::abs(t.depth - model.table_width) < tol && std::abs(t.width - model.table_depth) < tol);
  };
  for (const double w : {0.0, 0.5, 0.9}) {
    model.catalog_weight = w;
    Rng rng(13);
    const int n = 2000;
    int hits = 0;
    for (int i = 0; i < n; ++i) {
      MapSample s = orphanDraw();
      REQUIRE(completeOrphanLegs(s, known, model, rng) == 1);
      hits += catalog(s.tables[0]);
    }
    INFO("catalog_weight " << w << ": " << hits << " of " << n);
    // Binomial sd at most sqrt(n / 4) ~ 22; 6 sd either side.
    CHECK(std::abs(hits - w * n) < 135);
  }
  // In a corner 0.85 x 0.55 m against two walls, the floor around swept, with the leg at its
  // inner corner: one placement of eight fits, by the catalog's top or by the uniform part's
  // few small ones (about 6 % of its mass), so about 94 % of the completions are the catalog's.
  KnownSpace corner({0.0, 0.0}, {4.0, 4.0}, 0.05);
  for (double y = 0.025; y < 4.0; y += 0.05)
    for (double x = 0.025; x < 4.0; x += 0.05)
      if (!(x > 3.15 && y < 0.55)) corner.markBody({x, y}, 0.01);
  model.catalog_weight = 0.5;
  Rng rng(17);
  int completed = 0, of_catalog = 0;
  for (int i = 0; i < 400; ++i) {
    MapSample s;
    s.legs.push_back(MapLeg{{3.225, 0.475, 0.0}, 0.05});
    completed += completeOrphanLegs(s, corner, model, rng);
    for (const MapTable& t : s.tables) {
      of_catalog += catalog(t);
      CHECK(t.pose.x > 3.2);
      CHECK(t.pose.y < 0.5);
    }
  }
  INFO(of_catalog << " of " << completed << " completions the catalog's");
  CHECK(completed > 300);  // 64 tries each, about 1 in 15 of the proposals fits
  CHECK(of_catalog > 0.85 * completed);
}

TEST_CASE("Orphan completion: a leg boxed in by swept floor stays an orphan, deterministically",
          "[exploration][completion]") {
  KnownSpace known({0.0, 0.0}, {4.0, 4.0}, 0.05);
  known.markBody({2.0, 2.0}, 3.0);  // everything free ...
  known.markContact(kOrphan.pose.position());  // ... but the touched leg
  ModelParams model;
  model.objects = ObjectModel::kWalls;
  Rng rng(3);
  MapSample s = orphanDraw();
  CHECK(completeOrphanLegs(s, known, model, rng, 256) == 0);
  CHECK(s.tables.empty());
  REQUIRE(s.legs.size() == 1);
  CHECK(s.legs[0].pose.x == kOrphan.pose.x);

  KnownSpace open({0.0, 0.0}, {4.0, 4.0}, 0.05);
  Rng a(5), b(5);
  MapSample sa = orphanDraw(), sb = orphanDraw();
  completeOrphanLegs(sa, open, model, a);
  completeOrphanLegs(sb, open, model, b);
  REQUIRE(sa.tables.size() == 1);
  REQUIRE(sb.tables.size() == 1);
  CHECK(sa.tables[0].pose.x == sb.tables[0].pose.x);
  CHECK(sa.tables[0].pose.y == sb.tables[0].pose.y);
  CHECK(sa.tables[0].pose.theta == sb.tables[0].pose.theta);
}

TEST_CASE("Orphan completion: completed draws disagree where the orphan's other legs may stand",
          "[exploration][completion][infogain]") {
  // The leg was touched; the floor around it is unknown. Draws that keep it an orphan agree
  // everywhere (0 bits from the draws); completed, they disagree at a standard table's reach.
  KnownSpace known({0.0, 0.0}, {4.0, 4.0}, 0.05);
  known.markContact(kOrphan.pose.position());
  ModelParams model;
  model.objects = ObjectModel::kWalls;
  std::vector<MapSample> raw(16, orphanDraw()), completed = raw;
  Rng rng(9);
  for (MapSample& s : completed) REQUIRE(completeOrphanLegs(s, known, model, rng) == 1);
  // Scored as if the floor were open to drive (every candidate reachable).
  known.markBody({2.0, 2.0}, 3.0);
  PlannerOptions planner;
  Costmap costmap(known, planner);
  DistanceField travel(costmap, {0.3, 0.3});
  const std::vector<WhiskerMount> mounts = defaultWhiskerArray();
  ExploreState raw_state{{0.3, 0.3, 0.0}, known, costmap, travel, raw, mounts, model, {}, 1, 0.0};
  ExploreState completed_state = raw_state;
  completed_state.samples = completed;
  InfogainPolicy raw_policy(PolicyOptions{}), completed_policy(PolicyOptions{});
  // The poses facing each completion's other legs, scored against either set of draws.
  double raw_best = 0.0, completed_best = 0.0;
  for (const MapSample& s : completed) {
    for (int c = 0; c < 4; ++c) {
      const MapTable& t = s.tables[0];
      const Vec2 q = t.pose.toWorld(ModelParams::cornerOffset(c, t.width, t.depth, t.leg));
      if ((q - kOrphan.pose.position()).norm() < 0.1) continue;
      for (int h = 0; h < 8; ++h) {
        const double a = 2.0 * kPi * h / 8;
        const Pose2 pose{q.x() - 0.235 * std::cos(a), q.y() - 0.235 * std::sin(a), a};
        raw_best = std::max(raw_best, raw_policy.value(raw_state, pose).sample_bits);
        completed_best =
            std::max(completed_best, completed_policy.value(completed_state, pose).sample_bits);
      }
    }
  }
  CHECK(raw_best == 0.0);
  CHECK(completed_best > 0.5);
}

TEST_CASE("Orphan completion: repeats merged: a table held twice is one, an orphan on a table's "
          "leg is that leg, an orphan elsewhere stays",
          "[exploration][completion]") {
  MapTable t;
  t.pose = {1.5, 1.5, 0.4};
  MapTable twin = t;
  twin.pose.x += 0.004;
  MapTable beside = t;  // side by side with t, 5 mm apart: pushed together, not overlapping
  const Vec2 next_to = t.pose.toWorld(Vec2{t.width + 0.005, 0.0});
  beside.pose = {next_to.x(), next_to.y(), t.pose.theta};
  const Vec2 corner = t.pose.toWorld(ModelParams::cornerOffset(2, t.width, t.depth, t.leg));
  MapSample draw;
  draw.tables = {t, twin, beside};
  draw.legs.push_back({{corner.x() + 0.01, corner.y() - 0.01, t.pose.theta}, 0.05});  // t's leg
  draw.legs.push_back(kOrphan);  // (2.0, 2.0): no table's leg there
  const FuseOptions fuse;
  CHECK(mergeRepeats(draw, fuse) == 2);
  REQUIRE(draw.tables.size() == 2);
  CHECK(draw.tables[0].pose.x == t.pose.x);  // the first of the twins stays
  CHECK(draw.tables[1].pose.x == beside.pose.x);
  REQUIRE(draw.legs.size() == 1);
  CHECK(draw.legs[0].pose.x == kOrphan.pose.x);
  // Nothing repeated: nothing removed.
  CHECK(mergeRepeats(draw, fuse) == 0);
}
