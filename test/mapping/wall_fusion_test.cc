// Walls fused across chains (wall_fusion.h) and judged against a scene (evaluateWalls).
#include "crunch/mapping/wall_fusion.h"

#include <catch2/catch.hpp>

#include "crunch/mapping/evaluation.h"

using namespace crunch;

namespace {
WallHyp wall(double x0, double y0, double x1, double y1) {
  WallHyp w;
  w.a = {x0, y0};
  w.b = {x1, y1};
  w.alive = true;
  return w;
}
}  // namespace

TEST_CASE("fuseWalls: one line agreed by the chains is one wall scored by its share",
          "[mapping]") {
  std::vector<std::vector<WallHyp>> chains(8);
  for (int c = 0; c < 8; ++c) {
    // Every chain has the wall, slightly offset and with its own ends; chain 0 in two pieces.
    const double dy = 0.003 * (c % 3), e = 0.01 * c;
    if (c == 0) {
      chains[c].push_back(wall(0.5, 1.0, 1.2, 1.0));
      chains[c].push_back(wall(1.25, 1.0, 2.0, 1.0));
    } else {
      chains[c].push_back(wall(0.5 + e, 1.0 + dy, 2.0 - e, 1.0 + dy));
    }
  }
  chains[2].push_back(wall(3.0, 0.5, 3.0, 1.5));  // in 2 of 8 chains: dropped
  chains[5].push_back(wall(3.01, 0.6, 3.01, 1.4));
  const std::vector<MapWall> fused = fuseWalls(chains);
  REQUIRE(fused.size() == 1);
  CHECK(fused[0].score == Approx(1.0));
  CHECK(std::abs(fused[0].a.y() - 1.0) < 0.01);
  CHECK(std::min(fused[0].a.x(), fused[0].b.x()) == Approx(0.5 + 0.04).margin(0.02));
  CHECK(std::max(fused[0].a.x(), fused[0].b.x()) == Approx(2.0 - 0.04).margin(0.02));
  WallFuseOptions lenient;
  lenient.min_score = 0.25;
  CHECK(fuseWalls(chains, lenient).size() == 2);
}

TEST_CASE("fuseWalls: parallel walls apart or across each other stay apart", "[mapping]") {
  std::vector<std::vector<WallHyp>> chains(2);
  for (auto& c : chains) {
    c.push_back(wall(0, 0, 1, 0));
    c.push_back(wall(0, 0.2, 1, 0.2));   // parallel, 20 cm away
    c.push_back(wall(0.5, -0.5, 0.5, 0.5));  // across
  }
  CHECK(fuseWalls(chains).size() == 3);
}

TEST_CASE("fuseWalls: ends the chains joined to another wall meet it where the lines cross",
          "[mapping]") {
  // Walls end at walls (wall_fusion.h): a corner whose two walls stop 4 and 3 cm short of each
  // other, a T whose stem stops 3 cm short, a parallel piece 5.5 cm beside a wall (apart in the
  // fusion, within the junction radius of it, but no junction), and an end 10 cm from a wall
  // (outside the 6 cm junction radius), in every chain.
  std::vector<std::vector<WallHyp>> chains(4);
  for (auto& c : chains) {
    c.push_back(wall(0.04, 0.0, 2.0, 0.0));   // the corner's bottom wall, free side +y
    c.push_back(wall(0.0, 2.0, 0.0, 0.03));   // its left wall, free side +x
    c.push_back(wall(1.0, 0.03, 1.0, 1.0));   // a T's stem on the bottom wall
    c.push_back(wall(1.5, 0.055, 3.0, 0.055));  // parallel to the bottom wall: no junction
    c.push_back(wall(0.5, 1.5, 0.1, 1.5));    // 10 cm from the left wall: stays free
  }
  WallFuseOptions opt;
  opt.junction = 0.06;
  const std::vector<MapWall> met = fuseWalls(chains, opt);
  const std::vector<MapWall> free = fuseWalls(chains);  // junction 0: the chains' medians
  REQUIRE(met.size() == 5);
  REQUIRE(free.size() == 5);
  // The wall with an end at (x, y) (each is looked up by an end that does not move).
  const auto at = [](const std::vector<MapWall>& ws, double x, double y) -> const MapWall& {
    for (const MapWall& w : ws)
      if ((w.a - Vec2{x, y}).norm() < 0.01 || (w.b - Vec2{x, y}).norm() < 0.01) return w;
    FAIL("no wall near " << x << ", " << y);
    return ws.front();
  };
  const auto near = [](const Vec2& p, double x, double y) {
    return (p - Vec2{x, y}).norm() < 1e-9;
  };
  // Each wall keeps its direction (its free side); only the joined ends move.
  const MapWall& bottom = at(met, 2.0, 0.0);
  CHECK(near(bottom.a, 0.0, 0.0));  // the corner, both ends at the crossing
  CHECK(near(bottom.b, 2.0, 0.0));  // beside the parallel piece: not a junction
  const MapWall& left = at(met, 0.0, 2.0);
  CHECK(near(left.b, 0.0, 0.0));
  CHECK(near(left.a, 0.0, 2.0));
  const MapWall& stem = at(met, 1.0, 1.0);
  CHECK(near(stem.a, 1.0, 0.0));  // the T's stem on the wall it meets
  CHECK(near(stem.b, 1.0, 1.0));
  const MapWall& piece = at(met, 3.0, 0.055);
  CHECK(near(piece.a, 1.5, 0.055));
  const MapWall& shelf = at(met, 0.5, 1.5);
  CHECK(near(shelf.b, 0.1, 1.5));  // beyond the junction radius
  // Without a junction radius the ends are where the chains left them.
  CHECK(near(at(free, 2.0, 0.0).a, 0.04, 0.0));
  CHECK(near(at(free, 1.0, 1.0).a, 1.0, 0.03));
}

TEST_CASE("evaluateWalls: coverage of touched boundary, interior found, false length",
          "[mapping]") {
  Scene scene;  // 4 x 4
  scene.walls.push_back({{2.0, 0.0}, {2.0, 1.0}});
  Map map;
  // Contacts every 2 cm along the bottom boundary from x = 0.5 to 1.5 (1 m touched, give or
  // take the 2 cm reach at the ends) and along the interior wall.
  for (int k = 0; k <= 50; ++k) {
    Shapelet s;
    s.x = 0.5 + 0.02 * k;
    s.y = 0.005;
    map.shapelets.push_back(s);
  }
  SECTION("nothing mapped") {
    const WallEvaluation ev = evaluateWalls(map, scene);
    CHECK(ev.boundary_touched == Approx(1.04).margin(0.02));
    CHECK(ev.boundary_coverage == 0.0);
    CHECK(ev.interior_length == Approx(1.0).margin(1e-9));
    CHECK(ev.interior_found == 0.0);
    CHECK(ev.false_length == 0.0);
  }
  SECTION("the touched half of the boundary and half the interior wall mapped, a false wall") {
    map.walls.push_back({{0.5, 0.03}, {1.0, 0.03}, 1.0});     // 3 cm off: covers
    map.walls.push_back({{2.02, 0.0}, {2.02, 0.5}, 1.0});     // half the interior wall
    map.walls.push_back({{1.0, 2.0}, {1.5, 2.0}, 1.0});       // nowhere near a wall
    map.walls.push_back({{1.0, 0.2}, {1.5, 0.2}, 1.0});       // 20 cm off the boundary: false
    const WallEvaluation ev = evaluateWalls(map, scene);
    CHECK(ev.mapped_walls == 4);
    CHECK(ev.boundary_coverage == Approx(0.5).margin(0.05));
    CHECK(ev.interior_found == Approx(0.55).margin(0.03));  // 5 cm reach past the end
    CHECK(ev.false_length == Approx(1.0).margin(0.02));
  }
}

TEST_CASE("straddle: how far a footprint reaches to each side of a wall, within its length",
          "[mapping]") {
  // Wall along y = 0 from x = 0 to 2, its free side (left of a->b) at y > 0.
  const Vec2 a{0.0, 0.0}, b{2.0, 0.0};
  // A 0.8 x 0.5 table centred 0.05 m in front: 0.30 m in front, 0.20 m through.
  WallStraddle s = straddle({{1.0, 0.05, 0.0}, 0.8, 0.5}, a, b);
  CHECK(s.front == Approx(0.30));
  CHECK(s.behind == Approx(0.20));
  // Flush with the face: nothing behind.
  s = straddle({{1.0, 0.25, 0.0}, 0.8, 0.5}, a, b);
  CHECK(s.front == Approx(0.50));
  CHECK(s.behind == Approx(0.0).margin(1e-12));
  // Past the wall's end (x > 2.4): nothing within its length.
  s = straddle({{2.6, 0.0, 0.0}, 0.3, 0.5}, a, b);
  CHECK(s.front == 0.0);
  CHECK(s.behind == 0.0);
  // Half past the end, turned 90 degrees: only the part within the length counts, which here
  // is the whole depth either side (a square clipped at x = 2).
  s = straddle({{2.0, 0.0, kPi / 2}, 0.4, 0.4}, a, b);
  CHECK(s.front == Approx(0.2));
  CHECK(s.behind == Approx(0.2));
}

TEST_CASE("keepOneWorld: a table through a wall goes unless it is the more probable of the two",
          "[mapping]") {
  const double band = 0.015;
  const auto table = [](double x, double y, double score) {
    MapTable t;
    t.pose = {x, y, 0.0};
    t.width = 0.8;
    t.depth = 0.5;
    t.score = score;
    return t;
  };
  std::vector<MapWall> walls{{{0.0, 0.0}, {4.0, 0.0}, 1.0}, {{0.0, 3.0}, {0.0, 0.5}, 0.5}};
  std::vector<MapTable> tables{
      table(1.0, 0.05, 0.5),    // 0.20 m through the first wall (score 1.0): dropped
      table(2.5, 0.255, 1.0),   // flush, its fit 5 mm into the face: stays
      table(3.0, 0.24, 1.0),    // 10 mm in: within the band, stays
      table(0.1, 2.0, 0.75)};   // through the second wall (score 0.5): the wall goes
  keepOneWorld(tables, walls, band);
  REQUIRE(tables.size() == 3);
  CHECK(tables[0].pose.x == 2.5);
  CHECK(tables[1].pose.x == 3.0);
  CHECK(tables[2].pose.x == 0.1);
  REQUIRE(walls.size() == 1);
  CHECK(walls[0].score == 1.0);
  // A table 2 cm through (past the band) at the wall's own score: the wall stays.
  std::vector<MapTable> deep{table(1.0, 0.23, 1.0)};
  keepOneWorld(deep, walls, band);
  CHECK(deep.empty());
}
