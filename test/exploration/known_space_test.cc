// KnownSpace (crunch/exploration/known_space.h): rays free cells, contacts occupy them for good,
// occupied wins over free, the map's obstacles are replaced, frontier cells border free ones.
#include "crunch/exploration/known_space.h"

#include <catch2/catch.hpp>

using namespace crunch;
using namespace crunch::exploration;
using Cell = KnownSpace::Cell;

TEST_CASE("KnownSpace: a free ray frees the cells it crosses, nothing else", "[exploration]") {
  KnownSpace k({0, 0}, {1, 1}, 0.1);
  REQUIRE(k.nx() == 10);
  REQUIRE(k.ny() == 10);
  CHECK(k.at(Vec2(0.55, 0.55)) == Cell::kUnknown);
  k.markFreeRay({Vec2(0.05, 0.55), Vec2(0.95, 0.55)});
  for (int ix = 0; ix < 10; ++ix) CHECK(k.at(ix, 5) == Cell::kFree);
  CHECK(k.at(5, 4) == Cell::kUnknown);
  CHECK(k.at(5, 6) == Cell::kUnknown);
  CHECK(k.knownFraction() == Approx(0.1));
}

TEST_CASE("KnownSpace: a contact stays occupied under later free rays", "[exploration]") {
  KnownSpace k({0, 0}, {1, 1}, 0.1);
  k.markContact({0.55, 0.55});
  k.markFreeRay({Vec2(0.05, 0.55), Vec2(0.95, 0.55)});
  CHECK(k.at(Vec2(0.55, 0.55)) == Cell::kOccupied);
  CHECK(k.at(Vec2(0.45, 0.55)) == Cell::kFree);
  CHECK(k.at(Vec2(-0.1, 0.5)) == Cell::kOccupied);  // outside counts as blocked
  CHECK(k.outside({1.2, 0.5}));
}

TEST_CASE("KnownSpace: the map's legs occupy cells until the next map replaces them",
          "[exploration]") {
  KnownSpace k({0, 0}, {2, 2}, 0.05);
  MapTable t;
  t.pose = {1.0, 1.0, 0.0};
  std::vector<MapTable> tables{t};
  k.setMapObstacles(tables, {});
  const TableSpec spec{t.pose, t.width, t.depth, t.leg};
  for (const OrientedRect& leg : spec.legs()) CHECK(k.at(leg.pose.position()) == Cell::kOccupied);
  CHECK(k.at(Vec2(1.0, 1.0)) == Cell::kUnknown);  // under the top, between the legs
  k.setMapObstacles({}, {});
  for (const OrientedRect& leg : spec.legs()) CHECK(k.at(leg.pose.position()) == Cell::kUnknown);
}

TEST_CASE("KnownSpace: a frontier cell is unknown next to a free one", "[exploration]") {
  KnownSpace k({0, 0}, {1, 1}, 0.1);
  k.markBody({0.5, 0.5}, 0.12);
  CHECK(k.at(Vec2(0.55, 0.55)) == Cell::kFree);
  int ix, iy;
  REQUIRE(k.index({0.55, 0.65}, ix, iy));
  CHECK(k.at(ix, iy) == Cell::kUnknown);
  CHECK(k.frontier(ix, iy));
  REQUIRE(k.index({0.05, 0.05}, ix, iy));
  CHECK_FALSE(k.frontier(ix, iy));  // unknown, but far from anything free
}
