#include "crunch/scene/scene.h"
#include "crunch/core/json_input.h"

#include "core/json_fields.h"

#include <algorithm>
#include <cassert>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <string_view>

namespace crunch {

std::array<OrientedRect, 4> TableSpec::legs() const {
  // Leg centres sit half a leg in from each corner of the top, so the legs are flush with it.
  const double hx = 0.5 * (width - leg), hy = 0.5 * (depth - leg);
  const std::array<Vec2, 4> local = {Vec2{hx, hy}, Vec2{-hx, hy}, Vec2{-hx, -hy}, Vec2{hx, -hy}};
  std::array<OrientedRect, 4> out;
  for (int i = 0; i < 4; ++i) {
    const Vec2 c = pose.toWorld(local[i]);
    out[i] = OrientedRect{Pose2{c.x(), c.y(), pose.theta}, leg, leg};
  }
  return out;
}

std::vector<WallSpec> Scene::allWalls() const {
  std::vector<WallSpec> out;
  out.reserve(4 + walls.size());
  out.push_back({Vec2{0.0, 0.0}, Vec2{width, 0.0}});
  out.push_back({Vec2{width, 0.0}, Vec2{width, depth}});
  out.push_back({Vec2{width, depth}, Vec2{0.0, depth}});
  out.push_back({Vec2{0.0, depth}, Vec2{0.0, 0.0}});
  out.insert(out.end(), walls.begin(), walls.end());
  return out;
}

namespace {
// Grid coordinate i of n along [0, extent]. An arena narrower than twice the margin shrinks the
// margin to the centre rather than producing poses outside the arena.
double gridCoordinate(int i, int n, double extent) {
  if (n == 1) return 0.5 * extent;
  const double margin = std::min(kPoseGridMargin, 0.5 * extent);
  return margin + (extent - 2.0 * margin) * static_cast<double>(i) / static_cast<double>(n - 1);
}
}  // namespace

std::vector<Pose2> poseGrid(double width, double depth, int nx, int ny, int ntheta) {
  assert(nx > 0 && ny > 0 && ntheta > 0);
  if (nx <= 0 || ny <= 0 || ntheta <= 0) return {};
  std::vector<Pose2> out;
  out.reserve(static_cast<size_t>(nx) * static_cast<size_t>(ny) * static_cast<size_t>(ntheta));
  for (int iy = 0; iy < ny; ++iy) {
    const double y = gridCoordinate(iy, ny, depth);
    for (int ix = 0; ix < nx; ++ix) {
      const double x = gridCoordinate(ix, nx, width);
      for (int k = 0; k < ntheta; ++k) {
        out.push_back({x, y, 2.0 * kPi * static_cast<double>(k) / static_cast<double>(ntheta)});
      }
    }
  }
  return out;
}

Scene defaultArena() {
  Scene s;
  s.width = 4.0;
  s.depth = 4.0;
  // Six standard tables spread over the arena at assorted angles, after the paper's Fig. 6.
  // Every top is >= 0.48 m from the walls and >= 0.52 m from every other top, so the robot
  // (0.33 m across) can pass between any two of them (checked in scene_test).
  const std::array<Pose2, 6> poses = {Pose2{0.95, 0.85, 0.3},       Pose2{3.05, 1.00, 0.25 * kPi},
                                      Pose2{1.95, 1.70, 2.5},       Pose2{3.10, 2.45, 0.0},
                                      Pose2{0.80, 3.00, 0.5 * kPi}, Pose2{2.00, 3.05, 1.2}};
  for (const Pose2& p : poses) {
    TableSpec t;
    t.pose = p;
    s.tables.push_back(t);
  }
  s.poses = poseGrid(s.width, s.depth, 10, 10, 4);
  s.source = "<built-in default arena>";
  return s;
}

// ---------------------------------------------------------------------------------------------
// Scene file parsing.

namespace {

using json = json_fields::Json;
using namespace json_fields;

std::string fmt(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

double positive(double v, const std::string& path) {
  if (!(v > 0.0)) fail(path, "expected a positive size, got " + fmt(v));
  return v;
}

int positiveInteger(const json& j, const std::string& path) {
  if (!j.is_number_integer()) {
    fail(path, std::string("expected a positive integer, got ") + j.type_name());
  }
  // Positive JSON integers parse as unsigned, negative ones as signed.
  const bool is_positive = j.is_number_unsigned() ? j.get<uint64_t>() > 0 : j.get<int64_t>() > 0;
  if (!is_positive) fail(path, "expected a positive integer, got " + j.dump());
  if (j.get<uint64_t>() > static_cast<uint64_t>(kMaxScenePoses)) {
    fail(path, "expected at most " + std::to_string(kMaxScenePoses) + ", got " + j.dump());
  }
  return static_cast<int>(j.get<uint64_t>());
}

// Points may lie on the boundary; the tolerance absorbs rounding in rotated corners.
constexpr double kInsideTolerance = 1e-9;
// Shorter interior walls are treated as a mistake in the file, not as a wall.
constexpr double kMinWallLength = 1e-6;

bool insideArena(const Vec2& p, double width, double depth) {
  return p.x() >= -kInsideTolerance && p.x() <= width + kInsideTolerance &&
         p.y() >= -kInsideTolerance && p.y() <= depth + kInsideTolerance;
}

std::string arenaText(const Scene& s) {
  return "the arena [0, " + fmt(s.width) + "] x [0, " + fmt(s.depth) + "]";
}

void parseArena(const json& doc, Scene& s) {
  const auto it = doc.find("arena");
  if (it == doc.end()) fail("arena", "missing (required)");
  expectObject(*it, "arena", {"width", "depth"});
  s.width = positive(requiredNumber(*it, "arena", "width"), "arena.width");
  s.depth = positive(requiredNumber(*it, "arena", "depth"), "arena.depth");
  for (const auto& [side, name] : {std::pair{s.width, "arena.width"}, std::pair{s.depth, "arena.depth"}}) {
    if (side > kMaxArenaSide) {
      fail(name, fmt(side) + " m is more than the " + fmt(kMaxArenaSide) +
                     " m a side an arena may have (a run's memory and time grow with it)");
    }
  }
}

void parseTables(const json& doc, Scene& s) {
  const auto it = doc.find("tables");
  if (it == doc.end()) return;
  expectArray(*it, "tables");
  for (size_t i = 0; i < it->size(); ++i) {
    const json& j = (*it)[i];
    const std::string path = element("tables", i);
    expectObject(j, path, {"x", "y", "theta", "width", "depth", "leg"});
    TableSpec t;
    t.pose.x = requiredNumber(j, path, "x");
    t.pose.y = requiredNumber(j, path, "y");
    t.pose.theta = requiredNumber(j, path, "theta");
    t.width =
        positive(optionalNumber(j, path, "width", kStandardTableWidth), member(path, "width"));
    t.depth =
        positive(optionalNumber(j, path, "depth", kStandardTableDepth), member(path, "depth"));
    t.leg = positive(optionalNumber(j, path, "leg", kStandardLegSide), member(path, "leg"));
    // Four flush legs must fit under the top without overlapping one another.
    if (2.0 * t.leg > std::min(t.width, t.depth)) {
      fail(member(path, "leg"), "leg side " + fmt(t.leg) +
                                    " is more than half the smaller side of the top (" +
                                    fmt(std::min(t.width, t.depth)) + ")");
    }
    for (const Vec2& c : t.top().corners()) {
      if (!insideArena(c, s.width, s.depth)) {
        fail(path, "table top is not fully inside " + arenaText(s) + " (corner at (" + fmt(c.x()) +
                       ", " + fmt(c.y()) + "))");
      }
    }
    s.tables.push_back(t);
  }
}

void parseWalls(const json& doc, Scene& s) {
  const auto it = doc.find("walls");
  if (it == doc.end()) return;
  expectArray(*it, "walls");
  for (size_t i = 0; i < it->size(); ++i) {
    const json& j = (*it)[i];
    const std::string path = element("walls", i);
    expectObject(j, path, {"x0", "y0", "x1", "y1"});
    WallSpec w;
    w.a = {requiredNumber(j, path, "x0"), requiredNumber(j, path, "y0")};
    w.b = {requiredNumber(j, path, "x1"), requiredNumber(j, path, "y1")};
    if (!insideArena(w.a, s.width, s.depth)) {
      fail(member(path, "x0"), "endpoint (x0, y0) is outside " + arenaText(s));
    }
    if (!insideArena(w.b, s.width, s.depth)) {
      fail(member(path, "x1"), "endpoint (x1, y1) is outside " + arenaText(s));
    }
    if ((w.b - w.a).norm() < kMinWallLength) fail(path, "wall has zero length");
    s.walls.push_back(w);
  }
}

void parsePoses(const json& doc, Scene& s) {
  const auto it = doc.find("poses");
  if (it == doc.end()) {
    s.poses = poseGrid(s.width, s.depth, 10, 10, 4);
    return;
  }
  expectObject(*it, "poses", {"grid", "list"});
  const bool has_grid = it->contains("grid"), has_list = it->contains("list");
  if (has_grid == has_list) fail("poses", "expected exactly one of \"grid\" or \"list\"");

  if (has_grid) {
    const json& g = (*it)["grid"];
    expectArray(g, "poses.grid");
    if (g.size() != 3) {
      fail("poses.grid",
           "expected [nx, ny, ntheta], got " + std::to_string(g.size()) + " elements");
    }
    const int nx = positiveInteger(g[0], "poses.grid[0]");
    const int ny = positiveInteger(g[1], "poses.grid[1]");
    const int nt = positiveInteger(g[2], "poses.grid[2]");
    if (static_cast<long long>(nx) * ny * nt > kMaxScenePoses) {
      fail("poses.grid", "more than " + std::to_string(kMaxScenePoses) + " poses in total");
    }
    s.poses = poseGrid(s.width, s.depth, nx, ny, nt);
    return;
  }

  const json& l = (*it)["list"];
  expectArray(l, "poses.list");
  if (l.empty()) fail("poses.list", "expected at least one [x, y, theta]");
  if (l.size() > static_cast<size_t>(kMaxScenePoses)) {
    fail("poses.list", "more than " + std::to_string(kMaxScenePoses) + " poses");
  }
  for (size_t i = 0; i < l.size(); ++i) {
    const std::string path = element("poses.list", i);
    expectArray(l[i], path);
    if (l[i].size() != 3) {
      fail(path, "expected [x, y, theta], got " + std::to_string(l[i].size()) + " elements");
    }
    const Pose2 p{number(l[i][0], element(path, 0)), number(l[i][1], element(path, 1)),
                  number(l[i][2], element(path, 2))};
    // Overlap with tables and walls is the simulator's to judge; outside the arena is a typo.
    if (!insideArena(p.position(), s.width, s.depth)) {
      fail(path, "position is outside " + arenaText(s));
    }
    s.poses.push_back(p);
  }
}

}  // namespace

Result<Scene> parseScene(const std::string& json_text, const std::string& source) {
  if (auto st = checkStrictJson(json_text, source); !st) return st.error();
  json doc;
  try {
    doc = json::parse(json_text);
  } catch (const json::out_of_range&) {  // a number too large for a double
    // nlohmann names no field for a number too large for a double: follow the parse to it.
    JsonPathTracker tracker;
    json::sax_parse(json_text, &tracker);
    const std::string& at = tracker.errorPath();
    return Error{source + ": " + (at.empty() ? "(document)" : at) + ": expected a finite number"};
  } catch (const json::exception& e) {  // syntax errors, with line and column
    return Error{source + ": " + withoutExceptionTag(e.what())};
  }

  Scene s;
  s.source = source;
  try {
    expectObject(doc, "", {"arena", "tables", "walls", "poses"});
    // Arena first: the other sections are checked against its size.
    parseArena(doc, s);
    parseTables(doc, s);
    parseWalls(doc, s);
    parsePoses(doc, s);
  } catch (const FieldError& e) {
    // An empty path is the document itself.
    return Error{describe(source, e)};
  }
  return s;
}

Result<Scene> loadScene(const std::string& path) {
  auto text = readInputFile(path, "scene file");
  if (!text) return text.error();
  return parseScene(text.value(), path);
}

}  // namespace crunch
