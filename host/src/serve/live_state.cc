#include "crunch/serve/live_state.h"

#include <cmath>
#include <nlohmann/json.hpp>

#include "crunch/exploration/whisk_prediction.h"

namespace crunch::serve {

using json = nlohmann::ordered_json;

void LiveState::moveTo(const Pose2& p) {
  pose = p;
  const Vec2 at = p.position();
  if (!path.empty() && (at - path.back()).norm() < kPathStep) return;
  path.push_back(at);
  if (path.size() > kPathMaxPoints) {
    // Every other point, the newest kept: the path's shape at half the resolution.
    std::size_t keep = 0;
    for (std::size_t i = path.size() % 2 == 0 ? 1 : 0; i < path.size(); i += 2) path[keep++] = path[i];
    path.resize(keep);
  }
}

void LiveState::setMap(const Map& map, std::size_t max_contacts) {
  tables = map.tables;
  walls = map.walls;
  shapelets = static_cast<int>(map.shapelets.size());
  contacts.clear();
  const std::size_t n = std::min(max_contacts, map.shapelets.size());
  for (std::size_t i = map.shapelets.size() - n; i < map.shapelets.size(); ++i) {
    const Shapelet& s = map.shapelets[i];
    contacts.push_back({s.x, s.y, s.phi, s.oriented, s.whisker, s.pose_index, {s.ox, s.oy}});
  }
}

void LiveState::setCounter(const std::string& name, double value) {
  for (LiveCounter& c : counters) {
    if (c.name == name) {
      c.value = value;
      return;
    }
  }
  counters.push_back({name, value});
}

namespace {

// Integers as integers (counters), else the double; non-finite as null (JSON has no NaN).
json number(double v) {
  if (!std::isfinite(v)) return nullptr;
  if (v == std::floor(v) && std::abs(v) < 9.0e15) return static_cast<long long>(v);
  return v;
}

json xy(const Vec2& p) { return json::array({p.x(), p.y()}); }

}  // namespace

std::string liveStateJson(const LiveState& s, std::uint64_t seq) {
  json doc;
  doc["schema"] = "crunch.live/1";
  doc["seq"] = seq;
  doc["mode"] = s.mode;
  doc["stage"] = s.stage;
  doc["t"] = s.t;
  doc["done"] = s.done;
  doc["area"] = {{"x0", s.area_lo.x()}, {"y0", s.area_lo.y()}, {"x1", s.area_hi.x()},
                 {"y1", s.area_hi.y()}};
  doc["pose"] = s.pose ? json::array({s.pose->x, s.pose->y, s.pose->theta}) : json(nullptr);
  json path = json::array();
  for (const Vec2& p : s.path) path.push_back(xy(p));
  doc["path"] = std::move(path);
  json tables = json::array(), legs = json::array();
  for (const MapTable& t : s.tables) {
    tables.push_back({{"x", t.pose.x},
                      {"y", t.pose.y},
                      {"theta", t.pose.theta},
                      {"width", t.width},
                      {"depth", t.depth},
                      {"leg", t.leg},
                      {"score", t.score}});
    for (const OrientedRect& leg : exploration::legSquares(t)) {
      json corners = json::array();
      for (const Vec2& c : leg.corners()) corners.push_back(xy(c));
      legs.push_back(std::move(corners));
    }
  }
  doc["tables"] = std::move(tables);
  doc["legs"] = std::move(legs);
  json walls = json::array();
  for (const MapWall& w : s.walls) {
    walls.push_back({{"x0", w.a.x()}, {"y0", w.a.y()}, {"x1", w.b.x()}, {"y1", w.b.y()},
                     {"score", w.score}});
  }
  doc["walls"] = std::move(walls);
  json contacts = json::array();
  for (const LiveContact& c : s.contacts) {
    contacts.push_back({{"x", c.x},
                        {"y", c.y},
                        {"phi", c.phi},
                        {"oriented", c.oriented},
                        {"whisker", c.whisker},
                        {"whisk", c.whisk},
                        {"from", xy(c.from)}});
  }
  doc["contacts"] = std::move(contacts);
  doc["shapelets"] = s.shapelets;
  json counters = json::object();
  for (const LiveCounter& c : s.counters) counters[c.name] = number(c.value);
  doc["counters"] = std::move(counters);
  return doc.dump();
}

}  // namespace crunch::serve
