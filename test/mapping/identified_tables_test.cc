// Tests of identified_tables.h: a table is reported only where the evidence fixes its size
// (rooms model) or its place (walls model), and the board is left as it was.
#include "crunch/mapping/identified_tables.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

using namespace crunch;

namespace {

// A 0.8 x 0.5 m table (the standard size) at `pose` with a leg at every corner and a contact on
// the leg at each corner of `touched` (a leg with no contact is the table's guess).
int32_t tableWithLegs(Blackboard& bb, const Pose2& pose, std::initializer_list<int> touched) {
  const int32_t id = bb.addTable(pose, 0.8, 0.5, 0.05);
  for (int c = 0; c < 4; ++c) {
    const Vec2 at = bb.table(id).corner(c);
    bb.addLeg({at.x(), at.y(), wrapPeriod(pose.theta, kPi / 2)}, 0.05, id);
  }
  for (int c : touched) {
    const Vec2 at = bb.table(id).corner(c);
    Shapelet s;
    s.x = at.x() + 0.025 * std::cos(pose.theta);
    s.y = at.y() + 0.025 * std::sin(pose.theta);
    s.oriented = false;
    bb.pushShapelet(s);
  }
  return id;
}

}  // namespace

TEST_CASE("sizeCertainty: legs at both ends of each side pin a table's size, the two legs of one "
          "side leave its depth open and such a table is not reported",
          "[mapping][mapper]") {
  // The rooms model (issue 13): a table touched on the two legs of one side could have its other
  // side anywhere nothing swept, so no size within 5 cm has a posterior above one half. Without
  // the catalog: with it, the catalog's size is fixed by the prior (the next test).
  ModelParams p;
  p.objects = ObjectModel::kRooms;
  p.catalog_weight = 0.0;
  Blackboard board(p, 8, 64);
  const Pose2 pose{1.0, 1.0, 0.3};
  const int32_t id = board.addTable(pose, 0.8, 0.5, 0.05);
  // A leg at corner c, and a contact on its face that it explains (a leg nothing touched is the
  // table's guess, carried with its corner: see the last section).
  const auto legAt = [&](int c, bool touched = true) {
    const Vec2 at = board.table(id).corner(c);
    board.addLeg({at.x(), at.y(), wrapPeriod(pose.theta, kPi / 2)}, 0.05, id);
    if (!touched) return;
    Shapelet s;
    s.x = at.x() + 0.025 * std::cos(pose.theta);
    s.y = at.y() + 0.025 * std::sin(pose.theta);
    s.oriented = false;
    board.pushShapelet(s);
  };
  legAt(2);  // -x-y
  legAt(3);  // +x-y: the -y side's two legs
  const double before = board.totalEnergy();
  const double open = sizeCertainty(board, id, 0.10);
  INFO("two legs of one side: " << open);
  // The +y edge is free over the prior's 1.7 m of depth: about 0.1 / 1.7 of its mass is near.
  CHECK(open < 0.2);
  // The board is as it was.
  CHECK(board.table(id).pose.x == pose.x);
  CHECK(board.table(id).pose.y == pose.y);
  CHECK(board.table(id).width == 0.8);
  CHECK(board.table(id).depth == 0.5);
  CHECK(board.totalEnergy() == Approx(before).margin(1e-12));
  std::vector<MapTable> out;
  identifiedTablesOf(board, 0.10, out);
  CHECK(out.empty());

  legAt(0);  // +x+y: a leg on the +y side pins the depth too
  const double pinned = sizeCertainty(board, id, 0.10);
  INFO("three legs: " << pinned);
  CHECK(pinned > 0.9);
  identifiedTablesOf(board, 0.10, out);
  REQUIRE(out.size() == 1);
  CHECK(out[0].width == Approx(0.8));
  CHECK(out[0].depth == Approx(0.5));

  // A fourth leg nothing touched does not pin anything: it goes with its corner. Without the
  // third leg's contact the depth is open again, whatever legs the table holds.
  Blackboard guessed(p, 8, 64);
  const int32_t g = guessed.addTable(pose, 0.8, 0.5, 0.05);
  for (int c = 0; c < 4; ++c) {
    const Vec2 at = guessed.table(g).corner(c);
    guessed.addLeg({at.x(), at.y(), wrapPeriod(pose.theta, kPi / 2)}, 0.05, g);
    if (c < 2) continue;  // the +y side's legs untouched
    Shapelet s;
    s.x = at.x() + 0.025 * std::cos(pose.theta);
    s.y = at.y() + 0.025 * std::sin(pose.theta);
    s.oriented = false;
    guessed.pushShapelet(s);
  }
  const double before_guessed = guessed.totalEnergy();
  CHECK(sizeCertainty(guessed, g, 0.10) < 0.2);
  CHECK(guessed.totalEnergy() == Approx(before_guessed).margin(1e-12));
  CHECK(guessed.leg(guessed.table(g).children[0]).pose.x == guessed.table(g).corner(0).x());
}

TEST_CASE("identifiedTablesOf, rooms model with the catalog: a table of the catalog's size on the "
          "two legs of one side is not reported, its other side or its mirror image open",
          "[mapping][mapper]") {
  ModelParams p;
  p.objects = ObjectModel::kRooms;
  REQUIRE(p.catalog_weight > 0.0);
  // The catalog over the sides the evidence fixes (the default): nothing near corners 0 and 1,
  // so the depth is the uniform's, free.
  REQUIRE(p.catalog_fixed_sides);
  {
    Blackboard board(p, 8, 64);
    const int32_t id = tableWithLegs(board, {1.5, 1.5, 0.3}, {2, 3});
    CHECK(sizeCertainty(board, id, 0.10) < 0.2);
    std::vector<MapTable> out;
    identifiedTablesOf(board, 0.10, out);
    CHECK(out.empty());
  }
  // The catalog over every side: the prior's spike fixes the other side, the mirror image stays.
  ModelParams all = p;
  all.catalog_fixed_sides = false;
  Blackboard board(all, 8, 64);
  const int32_t id = tableWithLegs(board, {1.5, 1.5, 0.3}, {2, 3});
  CHECK(sizeCertainty(board, id, 0.10) > 0.9);
  const double mirror = placementCertainty(board, id);
  INFO("placement " << mirror);
  CHECK(mirror == Approx(0.5).margin(0.05));
  std::vector<MapTable> out;
  identifiedTablesOf(board, 0.10, out);
  CHECK(out.empty());
  // Three legs in an L fix both, either way.
  for (const ModelParams& q : {p, all}) {
    Blackboard three(q, 8, 64);
    tableWithLegs(three, {1.5, 1.5, 0.3}, {0, 2, 3});
    out.clear();
    identifiedTablesOf(three, 0.10, out);
    REQUIRE(out.size() == 1);
    CHECK(out[0].width == Approx(0.8));
  }
}

TEST_CASE("placementCertainty: a square top turned a quarter is the same object, not a rival",
          "[mapping][mapper]") {
  // A 0.45 m chair touched on three legs: its placements turned by pi/2 about the first touched
  // leg put the same top over the same legs, and count as the chain's own.
  ModelParams p;
  p.objects = ObjectModel::kRooms;
  Blackboard board(p, 8, 64);
  const Pose2 pose{1.0, 1.0, 0.2};
  const int32_t id = board.addTable(pose, 0.45, 0.45, 0.03);
  for (int c = 0; c < 4; ++c) {
    const Vec2 at = board.table(id).corner(c);
    board.addLeg({at.x(), at.y(), wrapPeriod(pose.theta, kPi / 2)}, 0.03, id);
    if (c == 1) continue;
    Shapelet s;
    s.x = at.x() + 0.015 * std::cos(pose.theta);
    s.y = at.y() + 0.015 * std::sin(pose.theta);
    s.oriented = false;
    board.pushShapelet(s);
  }
  const double certain = placementCertainty(board, id);
  INFO("placement " << certain);
  CHECK(certain > 0.9);
  std::vector<MapTable> out;
  identifiedTablesOf(board, 0.10, out);
  CHECK(out.size() == 1);
}

TEST_CASE("placementCertainty: three touched legs place a table of the one size, two legs of one "
          "side leave its mirror image as likely",
          "[mapping][mapper]") {
  // The walls model (issue 13): the table's size is the model's, so the two legs of one side fix
  // it up to its reflection across that side. When nothing tells the two apart, neither is a
  // table the map can report.
  ModelParams p;
  p.objects = ObjectModel::kWalls;
  const Pose2 pose{1.5, 1.5, 0.3};
  Blackboard side(p, 8, 64);
  const int32_t a = tableWithLegs(side, pose, {0, 1});  // the +y side's two legs
  const double before = side.totalEnergy();
  const Pose2 leg0 = side.leg(side.table(a).children[0]).pose;
  CHECK(placementCertainty(side, a) == 0.5);
  CHECK(side.totalEnergy() == Approx(before).margin(1e-12));
  CHECK(side.leg(side.table(a).children[0]).pose.x == leg0.x);
  std::vector<MapTable> out;
  identifiedTablesOf(side, 0.10, out);
  CHECK(out.empty());

  Blackboard three(p, 8, 64);
  const int32_t b = tableWithLegs(three, pose, {0, 1, 2});
  CHECK(placementCertainty(three, b) > 0.99);
  identifiedTablesOf(three, 0.10, out);
  CHECK(out.size() == 1);

  // The paper's model reports what its chains hold, as its figures always did.
  ModelParams paper;
  Blackboard old(paper, 8, 64);
  old.addTable(pose);
  identifiedTablesOf(old, 0.10, out);
  CHECK(out.size() == 1);
}

TEST_CASE("drawOpenTable: an open side is drawn from its conditional, a mirror tie splits the "
          "draws, a pinned table is drawn as held, and the board is left as it was",
          "[mapping][mapper]") {
  const Pose2 pose{1.5, 1.5, 0.3};
  Rng rng(17);

  // Rooms: the -y side's two legs touched. The width is pinned by them; the depth is open, so
  // the draws spread over the prior's range, and the touched legs stay at their corners.
  ModelParams rooms;
  rooms.objects = ObjectModel::kRooms;
  Blackboard open(rooms, 8, 64);
  const int32_t a = tableWithLegs(open, pose, {2, 3});
  const double before = open.totalEnergy();
  const Vec2 c2 = open.table(a).corner(2), c3 = open.table(a).corner(3);
  double dmin = 10.0, dmax = 0.0, wmin = 10.0, wmax = 0.0;
  for (int i = 0; i < 200; ++i) {
    const MapTable t = drawOpenTable(open, a, 0.02, rng);
    // sizedTable writes width >= depth: the side along the legs' line is the 0.8 m one unless
    // the drawn depth is longer.
    const double along = std::abs(std::remainder(t.pose.theta - pose.theta, kPi)) < 0.1
                             ? t.width : t.depth;
    const double across = along == t.width ? t.depth : t.width;
    wmin = std::min(wmin, along), wmax = std::max(wmax, along);
    dmin = std::min(dmin, across), dmax = std::max(dmax, across);
    // Both touched legs stand at corners of the drawn table.
    for (const Vec2& leg : {c2, c3}) {
      double best = 1e9;
      for (int c = 0; c < 4; ++c) {
        const Vec2 q =
            t.pose.toWorld(ModelParams::cornerOffset(c, t.width, t.depth, t.leg));
        best = std::min(best, (q - leg).norm());
      }
      CHECK(best < 0.03);
    }
  }
  INFO("along " << wmin << ".." << wmax << ", across " << dmin << ".." << dmax);
  CHECK(wmax - wmin < 0.05);   // pinned by the two touched legs
  CHECK(dmax - dmin > 0.5);    // open: nothing touched or swept on the far side
  CHECK(open.totalEnergy() == Approx(before).margin(1e-12));
  CHECK(open.table(a).depth == 0.5);

  // Three touched legs pin the table: every draw is the chain's.
  Blackboard pinned(rooms, 8, 64);
  const int32_t b = tableWithLegs(pinned, pose, {1, 2, 3});
  for (int i = 0; i < 20; ++i) {
    const MapTable t = drawOpenTable(pinned, b, 0.02, rng);
    CHECK(t.pose.x == pinned.table(b).pose.x);
    CHECK(t.width == Approx(0.8));
    CHECK(t.depth == Approx(0.5));
  }

  // Walls: the two legs of one side and nothing else: the table and its mirror image across that
  // side score alike, so the draws split between them.
  ModelParams walls;
  walls.objects = ObjectModel::kWalls;
  Blackboard side(walls, 8, 64);
  const int32_t s = tableWithLegs(side, pose, {0, 1});
  const Vec2 centre = side.table(s).pose.position();
  int same = 0, mirrored = 0;
  for (int i = 0; i < 400; ++i) {
    const MapTable t = drawOpenTable(side, s, 0.02, rng);
    const double d = (t.pose.position() - centre).norm();
    if (d < 1e-6) ++same;
    else if (std::abs(d - 0.45) < 1e-6) ++mirrored;  // reflected across the +y side: depth - leg
  }
  INFO("same " << same << ", mirrored " << mirrored);
  CHECK(same + mirrored == 400);
  CHECK(std::abs(same - 200) < 60);  // 1/2 each: sd 10, 6 sd

  // The paper's model: the chain's table.
  ModelParams paper;
  Blackboard old(paper, 8, 64);
  const int32_t o = old.addTable(pose);
  CHECK(drawOpenTable(old, o, 0.02, rng).pose.x == pose.x);
}
