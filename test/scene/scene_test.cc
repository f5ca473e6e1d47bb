#include "crunch/scene/scene.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <set>
#include <string>

using crunch::kPi;
using crunch::OrientedRect;
using crunch::Pose2;
using crunch::Scene;
using crunch::TableSpec;
using crunch::Vec2;

namespace {

// Coordinates computed from rotations and sums agree to well below a micrometre.
constexpr double kGeomTol = 1e-9;

std::string scenePath(const std::string& name) {
  return std::string(CRUNCH_SOURCE_DIR) + "/test/scenes/" + name;
}

// Smallest distance between two rectangles that do not overlap.
double rectDistance(const OrientedRect& a, const OrientedRect& b) {
  const auto cb = b.corners();
  double best = 1e9;
  for (int i = 0; i < 4; ++i) {
    best = std::min(best, crunch::distanceRectSegment(a, cb[i], cb[(i + 1) % 4]));
  }
  return best;
}

// Parses `text` as "scene.json" and requires an Error of the form
// "scene.json: <path>: ..." that also contains `what`.
void requireError(const std::string& text, const std::string& path, const std::string& what) {
  const auto r = crunch::parseScene(text, "scene.json");
  REQUIRE_FALSE(r.ok());
  const std::string& msg = r.error().message;
  INFO("message: " << msg);
  CHECK(msg.rfind("scene.json: " + path + ": ", 0) == 0);
  CHECK(msg.find(what) != std::string::npos);
}

// A valid document with `tables` spliced into a 4 x 4 arena.
std::string withTables(const std::string& tables) {
  return R"({"arena": {"width": 4, "depth": 4}, "tables": )" + tables + "}";
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Geometry helpers.

TEST_CASE("Scene: an arena side above 200 m is refused naming it, 200 m is fine (issue 16)",
          "[scene]") {
  requireError(R"({"arena": {"width": 1e308, "depth": 2.5}})", "arena.width",
               "more than the 200 m a side an arena may have");
  requireError(R"({"arena": {"width": 3, "depth": 200.5}})", "arena.depth", "200.5 m is more");
  CHECK(crunch::parseScene(R"({"arena": {"width": 200, "depth": 200}})", "s.json").ok());
}

TEST_CASE("Scene: legs sit flush in the four corners of the top, in corner order", "[scene]") {
  TableSpec t;
  t.pose = {1.5, 2.0, 0.7};
  t.width = 0.8;
  t.depth = 0.5;
  t.leg = 0.05;
  const auto legs = t.legs();
  const auto top = t.top().corners();
  for (int i = 0; i < 4; ++i) {
    INFO("leg " << i);
    CHECK(legs[i].size_x == Approx(0.05));
    CHECK(legs[i].size_y == Approx(0.05));
    CHECK(legs[i].pose.theta == Approx(0.7));
    // The leg's outer corner is the top's corner with the same index.
    const Vec2 outer = legs[i].corners()[i];
    CHECK(outer.x() == Approx(top[i].x()).margin(kGeomTol));
    CHECK(outer.y() == Approx(top[i].y()).margin(kGeomTol));
  }
  // Corner order in the table frame: (+x+y, -x+y, -x-y, +x-y).
  const Vec2 l0 = t.pose.toLocal(legs[0].pose.position());
  const Vec2 l2 = t.pose.toLocal(legs[2].pose.position());
  CHECK(l0.x() == Approx(0.375));
  CHECK(l0.y() == Approx(0.225));
  CHECK(l2.x() == Approx(-0.375));
  CHECK(l2.y() == Approx(-0.225));
}

TEST_CASE("Scene: allWalls lists the boundary counter-clockwise from the origin, then interior",
          "[scene]") {
  Scene s;
  s.width = 3.0;
  s.depth = 2.0;
  s.walls.push_back({Vec2{1.0, 0.0}, Vec2{1.0, 1.0}});
  const auto w = s.allWalls();
  REQUIRE(w.size() == 5);
  const std::vector<Vec2> corners = {{0, 0}, {3, 0}, {3, 2}, {0, 2}};
  for (int i = 0; i < 4; ++i) {
    INFO("wall " << i);
    CHECK(w[i].a == corners[i]);
    CHECK(w[i].b == corners[(i + 1) % 4]);
  }
  CHECK(w[4].a == Vec2(1.0, 0.0));
  CHECK(w[4].b == Vec2(1.0, 1.0));
}

TEST_CASE("Scene: the pose grid visits rows in y, then x, then heading, within the margin",
          "[scene]") {
  const auto g = crunch::poseGrid(4.0, 3.0, 10, 5, 4);
  REQUIRE(g.size() == 200);
  // First location, all four headings.
  for (int k = 0; k < 4; ++k) {
    CHECK(g[k].x == Approx(crunch::kPoseGridMargin));
    CHECK(g[k].y == Approx(crunch::kPoseGridMargin));
    CHECK(g[k].theta == Approx(k * 0.5 * kPi));
  }
  // Then the next x in the same row.
  CHECK(g[4].x == Approx(0.3 + 3.4 / 9));
  CHECK(g[4].y == Approx(0.3));
  // Then the next row.
  CHECK(g[40].x == Approx(0.3));
  CHECK(g[40].y == Approx(0.3 + 2.4 / 4));
  // Last pose: far corner, last heading.
  CHECK(g.back().x == Approx(3.7));
  CHECK(g.back().y == Approx(2.7));
  CHECK(g.back().theta == Approx(1.5 * kPi));
}

TEST_CASE("Scene: a grid of one along an axis sits at the centre", "[scene]") {
  const auto g = crunch::poseGrid(4.0, 3.0, 1, 1, 1);
  REQUIRE(g.size() == 1);
  CHECK(g[0].x == Approx(2.0));
  CHECK(g[0].y == Approx(1.5));
  CHECK(g[0].theta == 0.0);
}

// ---------------------------------------------------------------------------------------------
// The built-in arena.

TEST_CASE("Scene: the default arena has six standard tables inside the walls and apart",
          "[scene]") {
  const Scene s = crunch::defaultArena();
  CHECK(s.width == 4.0);
  CHECK(s.depth == 4.0);
  CHECK(s.source == "<built-in default arena>");
  CHECK(s.walls.empty());
  REQUIRE(s.tables.size() == 6);
  CHECK(s.poses.size() == 400);

  // Clearances promised in defaultArena(): tops 0.45 m from walls, 0.5 m from each other.
  constexpr double kWallClearance = 0.45, kTableClearance = 0.5;
  std::set<long> angles;  // distinct orientations modulo pi, in milliradians
  for (size_t i = 0; i < s.tables.size(); ++i) {
    const TableSpec& t = s.tables[i];
    INFO("table " << i);
    CHECK(t.width == crunch::kStandardTableWidth);
    CHECK(t.depth == crunch::kStandardTableDepth);
    CHECK(t.leg == crunch::kStandardLegSide);
    for (const auto& w : s.allWalls()) {
      CHECK(crunch::distanceRectSegment(t.top(), w.a, w.b) >= kWallClearance);
    }
    for (size_t j = i + 1; j < s.tables.size(); ++j) {
      INFO("and table " << j);
      CHECK_FALSE(crunch::overlaps(t.top(), s.tables[j].top()));
      CHECK(rectDistance(t.top(), s.tables[j].top()) >= kTableClearance);
    }
    angles.insert(std::lround(1000 * crunch::wrapPeriod(t.pose.theta, kPi)));
  }
  CHECK(angles.size() >= 5);  // a variety of angles, as in the paper's Fig. 6
}

TEST_CASE("Scene: the default arena's poses are the 10x10x4 grid", "[scene]") {
  const Scene s = crunch::defaultArena();
  const auto g = crunch::poseGrid(4.0, 4.0, 10, 10, 4);
  REQUIRE(s.poses.size() == g.size());
  for (size_t i = 0; i < g.size(); ++i) {
    CHECK(s.poses[i].x == g[i].x);
    CHECK(s.poses[i].y == g[i].y);
    CHECK(s.poses[i].theta == g[i].theta);
  }
}

// ---------------------------------------------------------------------------------------------
// Valid files.

TEST_CASE("Scene: a full valid scene file loads every field", "[scene]") {
  const std::string path = scenePath("two_tables.json");
  const auto r = crunch::loadScene(path);
  INFO((r.ok() ? std::string() : r.error().message));
  REQUIRE(r.ok());
  const Scene& s = r.value();
  CHECK(s.source == path);
  CHECK(s.width == 3.0);
  CHECK(s.depth == 2.5);
  REQUIRE(s.tables.size() == 2);
  CHECK(s.tables[0].pose.x == 0.9);
  CHECK(s.tables[0].pose.y == 0.8);
  CHECK(s.tables[0].pose.theta == 0.0);
  CHECK(s.tables[0].width == crunch::kStandardTableWidth);
  CHECK(s.tables[0].depth == crunch::kStandardTableDepth);
  CHECK(s.tables[0].leg == crunch::kStandardLegSide);
  CHECK(s.tables[1].pose.x == 2.0);
  CHECK(s.tables[1].pose.y == 1.6);
  CHECK(s.tables[1].pose.theta == 0.6);
  CHECK(s.tables[1].width == 0.6);
  CHECK(s.tables[1].depth == 0.6);
  CHECK(s.tables[1].leg == 0.04);
  REQUIRE(s.walls.size() == 1);
  CHECK(s.walls[0].a == Vec2(1.5, 0.0));
  CHECK(s.walls[0].b == Vec2(1.5, 0.6));
  REQUIRE(s.poses.size() == 3 * 2 * 4);
  const auto g = crunch::poseGrid(3.0, 2.5, 3, 2, 4);
  for (size_t i = 0; i < g.size(); ++i) {
    CHECK(s.poses[i].x == g[i].x);
    CHECK(s.poses[i].y == g[i].y);
    CHECK(s.poses[i].theta == g[i].theta);
  }
}

TEST_CASE("Scene: omitted sections and table sizes take the documented defaults", "[scene]") {
  const auto r = crunch::parseScene(withTables(R"([{"x": 2, "y": 2, "theta": 0.5}])"), "s.json");
  REQUIRE(r.ok());
  const Scene& s = r.value();
  REQUIRE(s.tables.size() == 1);
  CHECK(s.tables[0].width == crunch::kStandardTableWidth);
  CHECK(s.tables[0].depth == crunch::kStandardTableDepth);
  CHECK(s.tables[0].leg == crunch::kStandardLegSide);
  CHECK(s.walls.empty());
  CHECK(s.poses.size() == 400);  // default grid 10x10x4
  CHECK(s.source == "s.json");

  const auto bare = crunch::parseScene(R"({"arena": {"width": 2, "depth": 1.5}})", "bare.json");
  REQUIRE(bare.ok());
  CHECK(bare.value().tables.empty());
  CHECK(bare.value().poses.size() == 400);
}

TEST_CASE("Scene: the pose list form gives the poses in file order, unfiltered", "[scene]") {
  // The second pose is on top of the table: filtering is the simulator's job, not the parser's.
  const std::string text = R"({
    "arena": {"width": 4, "depth": 4},
    "tables": [{"x": 2, "y": 2, "theta": 0}],
    "poses": {"list": [[0.5, 0.6, 1.0], [2, 2, -0.5], [3.5, 0.5, 3]]}
  })";
  const auto r = crunch::parseScene(text, "list.json");
  REQUIRE(r.ok());
  const auto& p = r.value().poses;
  REQUIRE(p.size() == 3);
  CHECK(p[0].x == 0.5);
  CHECK(p[0].y == 0.6);
  CHECK(p[0].theta == 1.0);
  CHECK(p[1].x == 2.0);
  CHECK(p[1].theta == -0.5);
  CHECK(p[2].x == 3.5);
  CHECK(p[2].theta == 3.0);
}

TEST_CASE("Scene: a table touching the arena boundary is inside it", "[scene]") {
  // Top x extent exactly [0, 0.8].
  const auto r = crunch::parseScene(withTables(R"([{"x": 0.4, "y": 1, "theta": 0}])"), "s.json");
  CHECK(r.ok());
}

// ---------------------------------------------------------------------------------------------
// Errors: each names the file and the field.

TEST_CASE("Scene: a table outside the arena is an error naming tables[0]", "[scene]") {
  requireError(withTables(R"([{"x": 3.8, "y": 2, "theta": 0}])"), "tables[0]",
               "not fully inside the arena");
  // Rotation matters: this one fits at theta 0 but not at 45 degrees.
  requireError(withTables(R"([{"x": 2, "y": 2, "theta": 0},
                              {"x": 0.41, "y": 2, "theta": 0.785}])"),
               "tables[1]", "not fully inside");
}

TEST_CASE("Scene: an unknown key is an error naming it, at every level", "[scene]") {
  requireError(R"({"arena": {"width": 4, "depth": 4}, "colour": "red"})", "colour", "unknown key");
  requireError(R"({"arena": {"width": 4, "depth": 4, "height": 2}})", "arena.height",
               "unknown key");
  requireError(withTables(R"([{"x": 2, "y": 2, "theta": 0}, {"x": 2, "y": 1, "thetа": 0}])"),
               "tables[1].thetа", "unknown key");
  requireError(R"({"arena": {"width": 4, "depth": 4},
                   "walls": [{"x0": 0, "y0": 1, "x1": 1, "y1": 1, "z": 0}]})",
               "walls[0].z", "unknown key");
  requireError(R"({"arena": {"width": 4, "depth": 4}, "poses": {"grid": [2, 2, 2], "seed": 1}})",
               "poses.seed", "unknown key");
}

TEST_CASE("Scene: the example file with an unknown key names the file and the field", "[scene]") {
  const std::string path = scenePath("bad_unknown_key.json");
  const auto r = crunch::loadScene(path);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.rfind(path + ": tables[0].colour: unknown key", 0) == 0);
}

TEST_CASE("Scene: a wrong type is an error naming the field and the expected type", "[scene]") {
  requireError(withTables(R"([{"x": 1, "y": 1, "theta": 0}, {"x": 2, "y": 3, "theta": 0},
                              {"x": 2, "y": 2, "theta": "0.4"}])"),
               "tables[2].theta", "expected a number");
  requireError(R"({"arena": {"width": "4", "depth": 4}})", "arena.width", "expected a number");
  requireError(R"({"arena": [4, 4]})", "arena", "expected an object");
  requireError(withTables(R"({"x": 1})"), "tables", "expected an array");
  requireError(withTables(R"([[2, 2, 0]])"), "tables[0]", "expected an object");
  requireError(R"([1, 2])", "(document)", "expected an object");
  requireError(R"({"arena": {"width": 4, "depth": 4}, "poses": {"grid": [10, 10.5, 4]}})",
               "poses.grid[1]", "expected a positive integer");
  requireError(R"({"arena": {"width": 4, "depth": 4}, "poses": {"list": [[1, 1, null]]}})",
               "poses.list[0][2]", "expected a number");
}

TEST_CASE("Scene: a missing required field is an error naming it", "[scene]") {
  requireError(R"({"tables": []})", "arena", "missing");
  requireError(R"({"arena": {"width": 4}})", "arena.depth", "missing");
  requireError(withTables(R"([{"x": 2, "theta": 0}])"), "tables[0].y", "missing");
  requireError(R"({"arena": {"width": 4, "depth": 4}, "walls": [{"x0": 0, "y0": 1, "x1": 1}]})",
               "walls[0].y1", "missing");
}

TEST_CASE("Scene: a number too large for a double is an error naming its field", "[scene]") {
  requireError(withTables(R"([{"x": 2, "y": 2, "theta": 1e999}])"), "tables[0].theta", "finite");
  requireError(
      R"({"arena": {"width": 4, "depth": 4}, "poses": {"list": [[1, 1, 0], [1, -1e400, 0]]}})",
      "poses.list[1][1]", "finite");
}

TEST_CASE("Scene: non-positive sizes and counts are errors naming the field", "[scene]") {
  requireError(R"({"arena": {"width": 0, "depth": 4}})", "arena.width", "positive");
  requireError(R"({"arena": {"width": 4, "depth": -1}})", "arena.depth", "positive");
  requireError(withTables(R"([{"x": 2, "y": 2, "theta": 0, "width": 0}])"), "tables[0].width",
               "positive");
  requireError(withTables(R"([{"x": 2, "y": 2, "theta": 0, "leg": -0.05}])"), "tables[0].leg",
               "positive");
  requireError(withTables(R"([{"x": 2, "y": 2, "theta": 0, "depth": 0.5, "leg": 0.3}])"),
               "tables[0].leg", "more than half");
  requireError(R"({"arena": {"width": 4, "depth": 4}, "poses": {"grid": [10, 0, 4]}})",
               "poses.grid[1]", "positive integer");
  requireError(R"({"arena": {"width": 4, "depth": 4}, "poses": {"grid": [-2, 3, 4]}})",
               "poses.grid[0]", "positive integer");
  requireError(R"({"arena": {"width": 4, "depth": 4}, "poses": {"grid": [1000, 1000, 1000]}})",
               "poses.grid", "more than");
}

TEST_CASE("Scene: a wall outside the arena or of zero length is an error naming it", "[scene]") {
  requireError(R"({"arena": {"width": 4, "depth": 4},
                   "walls": [{"x0": 0, "y0": 2, "x1": 4.5, "y1": 2}]})",
               "walls[0].x1", "outside the arena");
  requireError(R"({"arena": {"width": 4, "depth": 4},
                   "walls": [{"x0": 1, "y0": 1, "x1": 2, "y1": 1},
                             {"x0": -0.1, "y0": 2, "x1": 1, "y1": 2}]})",
               "walls[1].x0", "outside the arena");
  requireError(R"({"arena": {"width": 4, "depth": 4},
                   "walls": [{"x0": 1, "y0": 1, "x1": 1, "y1": 1}]})",
               "walls[0]", "zero length");
}

TEST_CASE("Scene: malformed pose sections are errors naming the field", "[scene]") {
  const std::string arena = R"("arena": {"width": 4, "depth": 4})";
  requireError("{" + arena + R"(, "poses": {}})", "poses", "exactly one");
  requireError("{" + arena + R"(, "poses": {"grid": [2, 2, 2], "list": [[1, 1, 0]]}})", "poses",
               "exactly one");
  requireError("{" + arena + R"(, "poses": {"grid": [2, 2]}})", "poses.grid", "[nx, ny, ntheta]");
  requireError("{" + arena + R"(, "poses": {"list": []}})", "poses.list", "at least one");
  requireError("{" + arena + R"(, "poses": {"list": [[1, 1, 0], [1, 1]]}})", "poses.list[1]",
               "[x, y, theta]");
  requireError("{" + arena + R"(, "poses": {"list": [[5, 1, 0]]}})", "poses.list[0]",
               "outside the arena");
}

TEST_CASE("Scene: a JSON syntax error names the file, line and column", "[scene]") {
  const auto r = crunch::parseScene("{\n  \"arena\": {\"width\": 4,, \"depth\": 4}\n}", "bad.json");
  REQUIRE_FALSE(r.ok());
  const std::string& msg = r.error().message;
  INFO("message: " << msg);
  CHECK(msg.rfind("bad.json: ", 0) == 0);
  CHECK(msg.find("line 2") != std::string::npos);
  CHECK(msg.find("[json.exception") == std::string::npos);

  const auto empty = crunch::parseScene("", "empty.json");
  REQUIRE_FALSE(empty.ok());
  CHECK(empty.error().message.rfind("empty.json: ", 0) == 0);
}

TEST_CASE("Scene: an unreadable scene file is an error naming the path", "[scene]") {
  const std::string missing = scenePath("no_such_scene.json");
  const auto r = crunch::loadScene(missing);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.rfind(missing + ": ", 0) == 0);
  CHECK(r.error().message.find("No such file") != std::string::npos);

  const std::string dir = scenePath("");
  const auto d = crunch::loadScene(dir);
  REQUIRE_FALSE(d.ok());
  CHECK(d.error().message.rfind(dir + ": ", 0) == 0);
}
