// Tests of the whisk predictor (crunch/exploration/whisk_prediction.h): the ray tests, which
// whiskers a leg in front of the robot meets and where, nothing out of reach, and the outcome
// equality at the sensor's resolution. Its agreement with the simulator's RaySensorModel is
// test/sim/whisk_prediction_sim_test.cc.
#include "crunch/exploration/whisk_prediction.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

using namespace crunch;
using namespace crunch::exploration;

TEST_CASE("rayRect and raySegment: first hit along the ray", "[exploration][whisk]") {
  const Vec2 o{0.0, 0.0}, d{1.0, 0.0};
  CHECK(rayRect(o, d, 1.0, {{0.5, 0.0, 0.0}, 0.1, 0.1}) == Approx(0.45));
  // A square turned 45 degrees meets the ray with its corner.
  CHECK(rayRect(o, d, 1.0, {{0.5, 0.0, kPi / 4}, 0.1, 0.1}) == Approx(0.5 - 0.05 * std::sqrt(2.0)));
  CHECK(rayRect(o, d, 0.4, {{0.5, 0.0, 0.0}, 0.1, 0.1}) < 0.0);   // beyond the length
  CHECK(rayRect(o, d, 1.0, {{0.5, 0.2, 0.0}, 0.1, 0.1}) < 0.0);   // beside the ray
  CHECK(rayRect(o, d, 1.0, {{-0.5, 0.0, 0.0}, 0.1, 0.1}) < 0.0);  // behind the origin
  CHECK(raySegment(o, d, 1.0, {0.3, -1.0}, {0.3, 1.0}) == Approx(0.3));
  CHECK(raySegment(o, d, 0.2, {0.3, -1.0}, {0.3, 1.0}) < 0.0);
  CHECK(raySegment(o, d, 1.0, {0.3, 0.1}, {0.3, 1.0}) < 0.0);
}

TEST_CASE("WhiskPredictor: a leg straight ahead is met by the two inner whiskers only",
          "[exploration][whisk]") {
  // Default array: bearings -33.75, -11.25, +11.25, +33.75 degrees, bases on the 0.165 m rim.
  WhiskPredictor p(defaultWhiskerArray());
  MapSample sample;
  WhiskObstacles obs;
  obs.legs.push_back({{0.25, 0.0, 0.0}, 0.05, 0.05});  // near face at x = 0.225
  std::vector<WhiskerContact> out;
  p.predict({0.0, 0.0, 0.0}, obs, out);
  REQUIRE(out.size() == 4);
  CHECK_FALSE(out[0].hit);
  CHECK_FALSE(out[3].hit);
  REQUIRE(out[1].hit);
  REQUIRE(out[2].hit);
  // The deepest contact: the whisker turned by -/+11.25 degrees to point straight at the face
  // from its base at (0.165, 0): 0.06 m, on the face.
  for (int w : {1, 2}) {
    CHECK(out[static_cast<size_t>(w)].distance == Approx(0.06).margin(0.002));
    CHECK(out[static_cast<size_t>(w)].point.x() == Approx(0.225).margin(0.001));
    CHECK(out[static_cast<size_t>(w)].object == 0);
  }
  CHECK(p.anyInReach({0.0, 0.0}, obs));
  // Moved out of reach (tip at 0.305 m): nothing.
  p.predict({-0.2, 0.0, 0.0}, obs, out);
  for (const WhiskerContact& c : out) CHECK_FALSE(c.hit);
  CHECK_FALSE(p.anyInReach({-0.2, 0.0}, obs));
}

TEST_CASE("WhiskPredictor: walls as segments, and a table's legs flush in its corners",
          "[exploration][whisk]") {
  WhiskPredictor p(defaultWhiskerArray());
  MapSample sample;
  sample.walls.push_back({{0.25, -1.0}, {0.25, 1.0}, 1.0});
  MapTable t;
  t.pose = {2.0, 2.0, 0.0};
  sample.tables.push_back(t);
  WhiskObstacles obs;
  obs.assign(sample);
  REQUIRE(obs.legs.size() == 4);
  REQUIRE(obs.walls.size() == 1);
  // Corner order (+x+y, -x+y, -x-y, +x-y), centres half a leg in from the top's corners.
  CHECK(obs.legs[0].pose.x == Approx(2.375));
  CHECK(obs.legs[0].pose.y == Approx(2.225));
  CHECK(obs.legs[2].pose.x == Approx(1.625));
  std::vector<WhiskerContact> out;
  p.predict({0.0, 0.0, 0.0}, obs, out);
  for (const WhiskerContact& c : out) {
    REQUIRE(c.hit);  // a wall across the front: every whisker reaches it
    CHECK(c.point.x() == Approx(0.25));
    CHECK(c.object == 4);  // after the four legs
  }
}

TEST_CASE("sameOutcome: the same whiskers touch within the resolution", "[exploration][whisk]") {
  std::vector<WhiskerContact> a(2), b(2);
  CHECK(sameOutcome(a, b, 0.015));
  a[0].hit = true;
  a[0].point = {1.0, 1.0};
  CHECK_FALSE(sameOutcome(a, b, 0.015));
  b[0] = a[0];
  b[0].point = {1.01, 1.0};
  CHECK(sameOutcome(a, b, 0.015));
  b[0].point = {1.02, 1.0};
  CHECK_FALSE(sameOutcome(a, b, 0.015));
  CHECK(WhiskPredictionOptions::forSigma(0.005).resolution == Approx(0.015));
}
