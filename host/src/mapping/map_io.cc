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

Map parseMapDocument(const Json& doc) {
  expectObject(doc, "");
  const auto schema = doc.find("schema");
  if (schema == doc.end()) fail("schema", "missing (required)");
  if (!schema->is_string() || schema->get<std::string>() != kMapSchema) {
    fail("schema", std::string("expected \"") + kMapSchema + "\", got " + schema->dump());
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
