#include "crunch/mapping/map_io.h"
#include "crunch/core/json_input.h"

#include "core/json_fields.h"

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <string_view>
#include <system_error>

namespace crunch {

namespace {

// ordered_json keeps the keys in the contract's order, which makes the file easier to read.
using OrderedJson = nlohmann::ordered_json;

// A table's orientation is meaningful modulo pi; written in [0, pi) so equal tables read alike.
double normaliseTableTheta(double theta) {
  double t = std::fmod(theta, kPi);
  if (t < 0.0) t += kPi;
  if (t >= kPi) t = 0.0;  // -tiny + pi rounds to pi
  return t;
}

// free_space.rows[iy]: the swept cells of row iy as runs "start+length", separated by spaces.
std::string sweptRuns(const FreeSpaceLayer& f, int iy) {
  std::string row;
  for (int ix = 0; ix < f.nx;) {
    if (!f.at(ix, iy)) {
      ++ix;
      continue;
    }
    const int start = ix;
    while (ix < f.nx && f.at(ix, iy)) ++ix;
    if (!row.empty()) row += ' ';
    row += std::to_string(start);
    row += '+';
    row += std::to_string(ix - start);
  }
  return row;
}

}  // namespace

std::string mapToJson(const Map& map) {
  OrderedJson tables = OrderedJson::array();
  for (const MapTable& t : map.tables) {
    tables.push_back({{"x", t.pose.x},
                      {"y", t.pose.y},
                      {"theta", normaliseTableTheta(t.pose.theta)},
                      {"width", t.width},
                      {"depth", t.depth},
                      {"leg", t.leg},
                      {"score", t.score},
                      {"support", t.support}});
  }
  OrderedJson walls = OrderedJson::array();
  for (const MapWall& w : map.walls) {
    walls.push_back(
        {{"x0", w.a.x()}, {"y0", w.a.y()}, {"x1", w.b.x()}, {"y1", w.b.y()}, {"score", w.score}});
  }
  OrderedJson per_pose = OrderedJson::array();
  for (const PoseMap& pm : map.per_pose) {
    OrderedJson pose_tables = OrderedJson::array();
    for (const MapTable& t : pm.tables) {
      OrderedJson pt = {
          {"x", t.pose.x}, {"y", t.pose.y}, {"theta", normaliseTableTheta(t.pose.theta)}};
      // A size only where it is not the standard one (the rooms model's objects; the paper's
      // per-pose tables are written as before).
      if (t.width != kStandardTableWidth || t.depth != kStandardTableDepth ||
          t.leg != kStandardLegSide) {
        pt["width"] = t.width;
        pt["depth"] = t.depth;
        pt["leg"] = t.leg;
      }
      pose_tables.push_back(std::move(pt));
    }
    per_pose.push_back({{"pose", {pm.pose.x, pm.pose.y, pm.pose.theta}},
                        {"shapelets", pm.shapelets},
                        {"tables", std::move(pose_tables)}});
  }
  const MapStats& s = map.stats;
  OrderedJson doc = {{"schema", kMapSchema},
              {"tables", std::move(tables)},
              {"walls", std::move(walls)},
              {"per_pose", std::move(per_pose)},
              {"stats",
               {{"poses", s.poses},
                {"skipped_poses", s.skipped_poses},
                {"shapelets", s.shapelets},
                {"rejected_reports", s.rejected_reports},
                {"proposals", s.proposals},
                {"wall_s", s.wall_s},
                {"peak_live_tables", s.peak_live_tables},
                {"peak_live_legs", s.peak_live_legs}}}};
  const FreeSpaceLayer& f = map.free_space;
  if (!f.empty()) {
    OrderedJson rows = OrderedJson::array();
    for (int iy = 0; iy < f.ny; ++iy) rows.push_back(sweptRuns(f, iy));
    doc["free_space"] = {{"cell", f.cell},
                         {"origin", {f.origin.x(), f.origin.y()}},
                         {"size", {f.nx, f.ny}},
                         {"rows", std::move(rows)}};
  }
  return doc.dump(2) + "\n";
}

// ---------------------------------------------------------------------------------------------
// Reading map.json back.

namespace {

using Json = json_fields::Json;  // reading: key order does not matter
using namespace json_fields;

// A non-negative count that fits in T.
template <typename T>
T count(const Json& j, const std::string& path) {
  const bool ok = j.is_number_unsigned() &&
                  j.get<uint64_t>() <= static_cast<uint64_t>(std::numeric_limits<T>::max());
  if (!ok) fail(path, "expected a non-negative integer, got " + j.dump());
  return static_cast<T>(j.get<uint64_t>());
}

template <typename T>
T optionalCount(const Json& obj, const std::string& path, std::string_view key) {
  const auto it = obj.find(key);
  return it == obj.end() ? T{0} : count<T>(*it, member(path, key));
}

// The array at doc[key], or an empty one if absent.
const Json& optionalArray(const Json& doc, std::string_view key) {
  static const Json kEmpty = Json::array();
  const auto it = doc.find(key);
  if (it == doc.end()) return kEmpty;
  expectArray(*it, std::string(key));
  return *it;
}

MapTable parseTable(const Json& j, const std::string& path) {
  expectObject(j, path);
  MapTable t;
  t.pose.x = requiredNumber(j, path, "x");
  t.pose.y = requiredNumber(j, path, "y");
  t.pose.theta = requiredNumber(j, path, "theta");
  t.width = optionalNumber(j, path, "width", kStandardTableWidth);
  t.depth = optionalNumber(j, path, "depth", kStandardTableDepth);
  t.leg = optionalNumber(j, path, "leg", kStandardLegSide);
  t.score = optionalNumber(j, path, "score", 0.0);
  t.support = optionalCount<int>(j, path, "support");
  return t;
}

// One row of free_space.rows: runs "start+length" separated by single spaces, each inside the
// row and after the one before it.
void parseSweptRow(const Json& j, const std::string& path, int iy, FreeSpaceLayer& f) {
  if (!j.is_string()) fail(path, std::string("expected a string of runs, got ") + j.type_name());
  const std::string& row = j.get_ref<const std::string&>();
  const auto bad = [&path](const std::string& why) {
    fail(path, why + " (expected runs \"start+length\" separated by spaces)");
  };
  std::size_t i = 0;
  long long next_free = 0;  // the first cell a run may start at
  while (i < row.size()) {
    const auto digits = [&row, &i, &bad]() {
      const std::size_t from = i;
      long long v = 0;
      while (i < row.size() && row[i] >= '0' && row[i] <= '9' && v <= (1LL << 40)) {
        v = v * 10 + (row[i] - '0');
        ++i;
      }
      if (i == from) bad(std::string("a run without a number at character ").append(std::to_string(from)));
      return v;
    };
    const long long start = digits();
    if (i >= row.size() || row[i] != '+') {
      bad(std::string("a run without '+' at character ").append(std::to_string(i)));
    }
    ++i;
    const long long length = digits();
    if (length < 1 || start < next_free || start + length > f.nx) {
      std::string why = "run ";
      why.append(std::to_string(start)).append("+").append(std::to_string(length));
      why.append(" is empty, overlaps or touches the run before it, or leaves the row of ");
      why.append(std::to_string(f.nx)).append(" cells");
      bad(why);
    }
    for (long long ix = start; ix < start + length; ++ix) {
      f.swept[static_cast<std::size_t>(iy) * static_cast<std::size_t>(f.nx) +
              static_cast<std::size_t>(ix)] = 1;
    }
    next_free = start + length + 1;
    if (i < row.size()) {
      if (row[i] != ' ' || i + 1 == row.size()) {
        bad(std::string("a stray character at ").append(std::to_string(i)));
      }
      ++i;
    }
  }
}

FreeSpaceLayer parseFreeSpace(const Json& j) {
  const std::string path = "free_space";
  expectObject(j, path, {"cell", "origin", "size", "rows"});
  FreeSpaceLayer f;
  f.cell = requiredNumber(j, path, "cell");
  if (!(f.cell > 0.0)) fail(member(path, "cell"), "expected a cell side > 0 m");
  const Json& origin = array(required(j, path, "origin"), member(path, "origin"), 2);
  f.origin = {number(origin[0], member(path, "origin[0]")),
              number(origin[1], member(path, "origin[1]"))};
  const Json& size = array(required(j, path, "size"), member(path, "size"), 2);
  // At most 10^8 cells (a 100 x 100 m floor at 1 cm): a bound on the memory a map file can ask.
  constexpr int kMaxSide = 100000;
  f.nx = json_fields::count(size[0], member(path, "size[0]"), kMaxSide);
  f.ny = json_fields::count(size[1], member(path, "size[1]"), kMaxSide);
  if (static_cast<long long>(f.nx) * f.ny > 100'000'000LL) {
    fail(member(path, "size"), "more than 10^8 cells");
  }
  const Json& rows = required(j, path, "rows");
  array(rows, member(path, "rows"), static_cast<size_t>(f.ny));
  f.swept.assign(static_cast<std::size_t>(f.nx) * static_cast<std::size_t>(f.ny), 0);
  for (int iy = 0; iy < f.ny; ++iy) {
    const auto i = static_cast<size_t>(iy);
    parseSweptRow(rows[i], element(member(path, "rows"), i), iy, f);
  }
  if (f.nx == 0 || f.ny == 0) f = FreeSpaceLayer{};
  return f;
}

Map parseMapDocument(const Json& doc) {
  expectObject(doc, "");
  const auto schema = doc.find("schema");
  if (schema == doc.end()) fail("schema", "missing (required)");
  if (!schema->is_string() ||
      (schema->get<std::string>() != kMapSchema && schema->get<std::string>() != kMapSchemaV1)) {
    fail("schema", std::string("expected \"") + kMapSchema + "\" or \"" + kMapSchemaV1 +
                       "\", got " + schema->dump());
  }

  Map map;
  const Json& tables = optionalArray(doc, "tables");
  for (size_t i = 0; i < tables.size(); ++i) {
    map.tables.push_back(parseTable(tables[i], element("tables", i)));
  }

  const Json& walls = optionalArray(doc, "walls");
  for (size_t i = 0; i < walls.size(); ++i) {
    const std::string path = element("walls", i);
    expectObject(walls[i], path);
    MapWall w;
    w.a = {requiredNumber(walls[i], path, "x0"), requiredNumber(walls[i], path, "y0")};
    w.b = {requiredNumber(walls[i], path, "x1"), requiredNumber(walls[i], path, "y1")};
    w.score = optionalNumber(walls[i], path, "score", 0.0);
    map.walls.push_back(w);
  }

  const Json& per_pose = optionalArray(doc, "per_pose");
  for (size_t i = 0; i < per_pose.size(); ++i) {
    const std::string path = element("per_pose", i);
    const Json& j = per_pose[i];
    expectObject(j, path);
    PoseMap pm;
    const auto pose = j.find("pose");
    if (pose == j.end()) fail(member(path, "pose"), "missing (required)");
    expectArray(*pose, member(path, "pose"));
    if (pose->size() != 3) fail(member(path, "pose"), "expected [x, y, theta]");
    pm.pose = {number((*pose)[0], element(member(path, "pose"), 0)),
               number((*pose)[1], element(member(path, "pose"), 1)),
               number((*pose)[2], element(member(path, "pose"), 2))};
    pm.shapelets = optionalCount<int>(j, path, "shapelets");
    const auto pt = j.find("tables");
    if (pt != j.end()) {
      expectArray(*pt, member(path, "tables"));
      for (size_t k = 0; k < pt->size(); ++k) {
        pm.tables.push_back(parseTable((*pt)[k], element(member(path, "tables"), k)));
      }
    }
    map.per_pose.push_back(std::move(pm));
  }

  const auto stats = doc.find("stats");
  if (stats != doc.end()) {
    expectObject(*stats, "stats");
    MapStats& s = map.stats;
    s.poses = optionalCount<int>(*stats, "stats", "poses");
    s.skipped_poses = optionalCount<int>(*stats, "stats", "skipped_poses");
    s.shapelets = optionalCount<int>(*stats, "stats", "shapelets");
    s.rejected_reports = optionalCount<int>(*stats, "stats", "rejected_reports");
    s.proposals = optionalCount<long long>(*stats, "stats", "proposals");
    s.wall_s = optionalNumber(*stats, "stats", "wall_s", 0.0);
    // Added for issue 6; absent from older files (read as 0).
    s.peak_live_tables = optionalCount<int>(*stats, "stats", "peak_live_tables");
    s.peak_live_legs = optionalCount<int>(*stats, "stats", "peak_live_legs");
  }
  const auto free_space = doc.find("free_space");
  if (free_space != doc.end()) map.free_space = parseFreeSpace(*free_space);
  return map;
}

}  // namespace

Result<Map> parseMapJson(const std::string& text, const std::string& source) {
  if (auto st = checkStrictJson(text, source); !st) return st.error();
  Json doc;
  try {
    doc = Json::parse(text);
  } catch (const Json::exception& e) {  // syntax errors and numbers too large for a double
    return Error{source + ": " + withoutExceptionTag(e.what())};
  }
  try {
    return parseMapDocument(doc);
  } catch (const FieldError& e) {
    // An empty path is the document itself.
    return Error{describe(source, e)};
  }
}

// ---------------------------------------------------------------------------------------------
// Files. (writeFileAtomic is in core/atomic_file.cc.)

}  // namespace crunch
