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
