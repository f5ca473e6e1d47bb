// serve/live_state.h: the live view's snapshot and its document (schema crunch.live/1).
#include "crunch/serve/live_state.h"

#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

namespace {

using namespace crunch;
using serve::LiveState;
using json = nlohmann::json;

Shapelet shapeletAt(double x, double y, int pose) {
  Shapelet s;
  s.x = x;
  s.y = y;
  s.phi = 0.5;
  s.whisker = 2;
  s.pose_index = pose;
  s.ox = x - 0.1;
  s.oy = y;
  return s;
}

}  // namespace

TEST_CASE("Live state: the document holds the pose, path, map, contacts and counters",
          "[serve]") {
  LiveState s;
  s.mode = "robot";
  s.stage = "roaming";
  s.t = 12.5;
  s.area_hi = {6.0, 4.0};
  s.moveTo({1.0, 1.0, 0.0});
  s.moveTo({1.5, 1.0, 0.25});
  Map map;
  MapTable t;
  t.pose = {2.0, 2.0, 0.3};
  t.score = 0.9;
  map.tables.push_back(t);
  map.walls.push_back({{0.0, 3.0}, {1.5, 3.0}, 0.8});
  for (int i = 0; i < 3; ++i) map.shapelets.push_back(shapeletAt(1.0 + i, 2.0, i));
  s.setMap(map);
  s.setCounter("ring_dropped", 0);
  s.setCounter("map_write_max_s", 0.125);
  s.setCounter("ring_dropped", 2);  // updated in place

  const std::string text = serve::liveStateJson(s, 7);
  const json d = json::parse(text);
  CHECK(d["schema"] == "crunch.live/1");
  CHECK(d["seq"] == 7);
  CHECK(d["mode"] == "robot");
  CHECK(d["stage"] == "roaming");
  CHECK(d["t"] == 12.5);
  CHECK(d["done"] == false);
  CHECK(d["area"] == json{{"x0", 0.0}, {"y0", 0.0}, {"x1", 6.0}, {"y1", 4.0}});
  CHECK(d["pose"] == json::array({1.5, 1.0, 0.25}));
  CHECK(d["path"] == json::array({json::array({1.0, 1.0}), json::array({1.5, 1.0})}));
  REQUIRE(d["tables"].size() == 1);
  CHECK(d["tables"][0]["x"] == 2.0);
  CHECK(d["tables"][0]["score"] == 0.9);
  CHECK(d["tables"][0]["width"] == kStandardTableWidth);
  // Four legs, each four corners, within the table's half-diagonal of its centre.
  REQUIRE(d["legs"].size() == 4);
  const double half_diagonal = 0.5 * std::hypot(kStandardTableWidth, kStandardTableDepth);
  for (const json& leg : d["legs"]) {
    REQUIRE(leg.size() == 4);
    for (const json& c : leg) {
      CHECK(std::hypot(c[0].get<double>() - 2.0, c[1].get<double>() - 2.0) <=
            half_diagonal + 1e-9);
    }
  }
  CHECK(d["walls"] == json::array({{{"x0", 0.0}, {"y0", 3.0}, {"x1", 1.5}, {"y1", 3.0},
                                    {"score", 0.8}}}));
  REQUIRE(d["contacts"].size() == 3);
  CHECK(d["contacts"][2]["x"] == 3.0);
  CHECK(d["contacts"][2]["whisk"] == 2);
  CHECK(d["contacts"][2]["whisker"] == 2);
  CHECK(d["contacts"][2]["from"] == json::array({2.9, 2.0}));
  CHECK(d["shapelets"] == 3);
  // Counters in the order first set; integers as integers.
  CHECK(text.find(R"("counters":{"ring_dropped":2,"map_write_max_s":0.125})") != std::string::npos);
}

TEST_CASE("Live state: no pose yet is null, non-finite counters are null", "[serve]") {
  LiveState s;
  s.setCounter("nan", std::nan(""));
  const json d = json::parse(serve::liveStateJson(s, 0));
  CHECK(d["pose"].is_null());
  CHECK(d["path"].empty());
  CHECK(d["counters"]["nan"].is_null());
}

TEST_CASE("Live state: the contacts are the newest kMaxContacts, newest last", "[serve]") {
  Map map;
  for (int i = 0; i < 100; ++i) map.shapelets.push_back(shapeletAt(0.01 * i, 0.0, i / 4));
  LiveState s;
  s.setMap(map);
  REQUIRE(s.contacts.size() == LiveState::kMaxContacts);
  CHECK(s.contacts.back().whisk == 24);
  CHECK(s.contacts.front().x == Approx(0.01 * (100 - LiveState::kMaxContacts)));
  CHECK(s.shapelets == 100);
}

TEST_CASE("Live state: the path keeps a point per kPathStep and halves past kPathMaxPoints",
          "[serve]") {
  LiveState s;
  s.moveTo({0.0, 0.0, 0.0});
  s.moveTo({0.5 * LiveState::kPathStep, 0.0, 0.0});  // too near: the pose moves, the path not
  CHECK(s.path.size() == 1);
  CHECK(s.pose->x == 0.5 * LiveState::kPathStep);
  std::size_t most = 0;
  for (std::size_t i = 1; i <= 2 * LiveState::kPathMaxPoints; ++i) {
    s.moveTo({static_cast<double>(i) * 2.0 * LiveState::kPathStep, 0.0, 0.0});
    most = std::max(most, s.path.size());
  }
  CHECK(most == LiveState::kPathMaxPoints);
  CHECK(s.path.size() > LiveState::kPathMaxPoints / 2);
  // The newest point is always kept; the points stay in order.
  CHECK(s.path.back().x() == Approx(2.0 * LiveState::kPathMaxPoints * 2.0 * LiveState::kPathStep));
  bool ordered = true;
  for (std::size_t i = 1; i < s.path.size(); ++i) ordered = ordered && s.path[i].x() > s.path[i - 1].x();
  CHECK(ordered);
}
