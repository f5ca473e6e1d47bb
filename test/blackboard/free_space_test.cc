#include "crunch/blackboard/free_space.h"

#include <catch2/catch.hpp>

using namespace crunch;

TEST_CASE("FreeSpace: a ray through a leg's core counts, one grazing its outline does not",
          "[mapping]") {
  FreeSpaceGrid g({0, 0}, {1, 1}, 0.01);
  const Pose2 leg{0.5, 0.5, 0.3};
  g.addRay({{0.2, 0.5}, {0.8, 0.5}});  // straight through the centre
  CHECK(g.maxInSquare(leg, 0.05, 0.015) == 1);
  FreeSpaceGrid graze({0, 0}, {1, 1}, 0.01);
  // 1.5 cm above the centre: inside the 5 cm outline, outside the 2 cm core however turned.
  graze.addRay({{0.2, 0.515}, {0.8, 0.515}});
  CHECK(graze.maxInSquare(leg, 0.05, 0.015) == 0);
  CHECK(graze.maxInSquare(leg, 0.05, 0.0) >= 1);  // the unshrunk square does see it
}

TEST_CASE("FreeSpace: each ray counts once per cell, outside the grid is zero", "[mapping]") {
  FreeSpaceGrid g({0, 0}, {1, 1}, 0.01);
  for (int i = 0; i < 3; ++i) g.addRay({{0.1, 0.1}, {0.9, 0.9}});
  CHECK(g.count({0.5, 0.5}) == 3);
  CHECK(g.count({0.5, 0.2}) == 0);
  CHECK(g.count({-1.0, 0.5}) == 0);
  CHECK(g.count({0.5, 7.0}) == 0);
  CHECK(g.rays() == 3);
  g.addRay({{-5, -5}, {-4, -4}});  // wholly outside: harmless
  CHECK(g.rays() == 4);
}
