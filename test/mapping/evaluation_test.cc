#include "crunch/mapping/evaluation.h"

#include <catch2/catch.hpp>
#include <cmath>

using crunch::Evaluation;
using crunch::kPi;
using crunch::Map;
using crunch::MapTable;
using crunch::MatchTolerance;
using crunch::Scene;
using crunch::TableSpec;
using crunch::Vec2;

namespace {

MapTable makeMapTable(double x, double y, double theta) {
  MapTable t;
  t.pose = {x, y, theta};
  return t;
}

TableSpec makeTable(double x, double y, double theta) {
  TableSpec t;
  t.pose = {x, y, theta};
  return t;
}

// A 4 x 4 arena with no tables and no poses.
Scene emptyScene() {
  Scene s;
  s.poses.clear();
  return s;
}

// A map whose fused tables are exactly the scene's.
Map perfectMap(const Scene& s) {
  Map m;
  for (const TableSpec& t : s.tables)
    m.tables.push_back(makeMapTable(t.pose.x, t.pose.y, t.pose.theta));
  return m;
}

}  // namespace

TEST_CASE("Evaluation: a perfect map has precision and recall 1 and no error", "[mapping]") {
  const Scene s = crunch::defaultArena();
  const Evaluation e = crunch::evaluate(perfectMap(s), s);
  CHECK(e.true_tables == 6);
  CHECK(e.fused_tables == 6);
  CHECK(e.matched == 6);
  CHECK(e.precision == 1.0);
  CHECK(e.recall == 1.0);
  CHECK(e.f1 == 1.0);
  CHECK(e.mean_position_error == 0.0);
  CHECK(e.mean_angle_error == Approx(0.0).margin(1e-12));
  CHECK(e.phantoms_near_walls == 0);
  CHECK(e.phantoms_elsewhere == 0);
}

TEST_CASE("Evaluation: a table turned by pi is the same table", "[mapping]") {
  const MatchTolerance tol;
  const TableSpec truth = makeTable(2.0, 2.0, 0.4);
  CHECK(crunch::tableMatches(makeMapTable(2.0, 2.0, 0.4 + kPi), truth, tol));
  CHECK(crunch::tableMatches(makeMapTable(2.0, 2.0, 0.4 - kPi + 0.1), truth, tol));
  CHECK_FALSE(crunch::tableMatches(makeMapTable(2.0, 2.0, 0.4 + 0.5 * kPi), truth, tol));

  Scene s = emptyScene();
  s.tables.push_back(truth);
  Map m;
  m.tables.push_back(makeMapTable(2.0, 2.0, 0.4 + kPi + 0.05));
  const Evaluation e = crunch::evaluate(m, s);
  CHECK(e.matched == 1);
  CHECK(e.mean_angle_error == Approx(0.05));
}

TEST_CASE("Evaluation: a table 0.2 m off does not match, 0.1 m off does", "[mapping]") {
  const MatchTolerance tol;  // 0.15 m
  const TableSpec truth = makeTable(2.0, 2.0, 0.0);
  CHECK_FALSE(crunch::tableMatches(makeMapTable(2.2, 2.0, 0.0), truth, tol));
  CHECK(crunch::tableMatches(makeMapTable(2.0, 2.1, 0.0), truth, tol));

  Scene s = emptyScene();
  s.tables.push_back(truth);
  Map m;
  m.tables.push_back(makeMapTable(2.2, 2.0, 0.0));
  const Evaluation e = crunch::evaluate(m, s);
  CHECK(e.matched == 0);
  CHECK(e.precision == 0.0);
  CHECK(e.recall == 0.0);
  CHECK(e.f1 == 0.0);
  CHECK(e.phantoms_elsewhere == 1);
}

TEST_CASE("Evaluation: two fused tables on one real table match only once, the closer one",
          "[mapping]") {
  Scene s = emptyScene();
  s.tables.push_back(makeTable(2.0, 2.0, 0.0));
  Map m;
  m.tables.push_back(makeMapTable(2.1, 2.0, 0.0));   // further, listed first
  m.tables.push_back(makeMapTable(2.0, 2.05, 0.0));  // closer
  const Evaluation e = crunch::evaluate(m, s);
  CHECK(e.matched == 1);
  CHECK(e.precision == 0.5);
  CHECK(e.recall == 1.0);
  CHECK(e.f1 == Approx(2.0 / 3.0));
  CHECK(e.mean_position_error == Approx(0.05));
  CHECK(e.phantoms_elsewhere == 1);  // the duplicate is an unmatched fused table
}

TEST_CASE("Evaluation: greedy matching pairs each fused table with its nearest free table",
          "[mapping]") {
  Scene s = emptyScene();
  s.tables.push_back(makeTable(1.0, 2.0, 0.0));
  s.tables.push_back(makeTable(3.0, 2.0, 0.0));
  Map m;
  m.tables.push_back(makeMapTable(3.1, 2.0, 0.0));
  m.tables.push_back(makeMapTable(1.0, 1.9, 0.0));
  const Evaluation e = crunch::evaluate(m, s);
  CHECK(e.matched == 2);
  CHECK(e.mean_position_error == Approx(0.1));
}

TEST_CASE("Evaluation: an unmatched table near a wall is a wall phantom", "[mapping]") {
  Scene s = emptyScene();
  s.walls.push_back({Vec2{2.0, 0.0}, Vec2{2.0, 1.0}});  // interior wall
  Map m;
  m.tables.push_back(makeMapTable(0.5, 2.0, 0.5 * kPi));  // top 0.25 m from the west wall
  m.tables.push_back(makeMapTable(2.0, 1.4, 0.0));        // top 0.15 m from the interior wall
  m.tables.push_back(makeMapTable(2.0, 2.5, 0.0));        // in the open
  m.tables.push_back(makeMapTable(0.8, 2.0, 0.5 * kPi));  // top 0.55 m from the west wall
  const Evaluation e = crunch::evaluate(m, s);
  CHECK(e.matched == 0);
  CHECK(e.phantoms_near_walls == 2);
  CHECK(e.phantoms_elsewhere == 2);
}

TEST_CASE("Evaluation: per-pose tables count as matched if they match any real table",
          "[mapping]") {
  Scene s = emptyScene();
  s.tables.push_back(makeTable(1.0, 1.0, 0.0));
  s.tables.push_back(makeTable(3.0, 3.0, 0.0));
  Map m;
  m.per_pose.resize(3);
  m.per_pose[0].tables = {makeMapTable(1.0, 1.0, 0.0), makeMapTable(3.0, 3.0, kPi)};
  m.per_pose[1].tables = {makeMapTable(1.0, 1.0, 0.0)};  // both poses saw table 0: both count
  m.per_pose[2].tables = {makeMapTable(2.0, 2.0, 0.0)};  // matches nothing
  const Evaluation e = crunch::evaluate(m, s);
  CHECK(e.per_pose_tables == 4);
  CHECK(e.per_pose_match_fraction == Approx(0.75));
}

TEST_CASE("Evaluation: an empty map of an empty scene is perfect", "[mapping]") {
  const Evaluation e = crunch::evaluate(Map{}, emptyScene());
  CHECK(e.true_tables == 0);
  CHECK(e.fused_tables == 0);
  CHECK(e.matched == 0);
  CHECK(e.precision == 1.0);
  CHECK(e.recall == 1.0);
  CHECK(e.f1 == 1.0);
  CHECK(e.mean_position_error == 0.0);
  CHECK(e.per_pose_tables == 0);
  CHECK(e.per_pose_match_fraction == 0.0);
  CHECK(e.phantoms_near_walls + e.phantoms_elsewhere == 0);
}

TEST_CASE("Evaluation: an empty map of a furnished scene has recall 0", "[mapping]") {
  const Evaluation e = crunch::evaluate(Map{}, crunch::defaultArena());
  CHECK(e.precision == 1.0);  // nothing claimed, nothing claimed wrongly
  CHECK(e.recall == 0.0);
  CHECK(e.f1 == 0.0);
}

namespace {
MapTable sizedMapTable(double x, double y, double theta, double w, double d, double leg) {
  MapTable t = makeMapTable(x, y, theta);
  t.width = w;
  t.depth = d;
  t.leg = leg;
  return t;
}
TableSpec sizedTable(double x, double y, double theta, double w, double d, double leg) {
  TableSpec t = makeTable(x, y, theta);
  t.width = w;
  t.depth = d;
  t.leg = leg;
  return t;
}
MatchTolerance roomsTolerance() {
  crunch::ModelParams p;
  p.objects = crunch::ObjectModel::kRooms;
  return crunch::matchToleranceFor(p);
}
}  // namespace

TEST_CASE("Evaluation: with sizes judged, a table of the wrong size does not match", "[mapping]") {
  Scene s = emptyScene();
  s.tables.push_back(sizedTable(1.0, 1.0, 0.0, 0.45, 0.45, 0.03));
  Map m;
  m.tables.push_back(makeMapTable(1.0, 1.0, 0.0));  // the paper's 0.8 x 0.5 at the chair
  CHECK(crunch::evaluate(m, s).matched == 1);        // sizes not judged: as before
  CHECK(crunch::evaluate(m, s, roomsTolerance()).matched == 0);
  m.tables[0] = sizedMapTable(1.0, 1.0, 0.0, 0.48, 0.44, 0.035);
  const Evaluation e = crunch::evaluate(m, s, roomsTolerance());
  CHECK(e.matched == 1);
  CHECK(e.max_width_error == Approx(0.03));
  CHECK(e.max_depth_error == Approx(0.01));
  CHECK(e.mean_leg_error == Approx(0.005));
  m.tables[0].width = 0.51;  // 6 cm over
  CHECK(crunch::evaluate(m, s, roomsTolerance()).matched == 0);
  CHECK(roomsTolerance().size == Approx(0.05));
  CHECK_FALSE(std::isfinite(crunch::matchToleranceFor(crunch::ModelParams{}).size));
}

TEST_CASE("Evaluation: a w x d table at theta is the d x w one at theta + pi/2, a square's angle "
          "means modulo pi/2",
          "[mapping]") {
  Scene s = emptyScene();
  s.tables.push_back(sizedTable(1.0, 1.0, 0.1, 0.6, 1.0, 0.06));
  s.tables.push_back(sizedTable(3.0, 1.0, 0.0, 0.45, 0.45, 0.03));
  Map m;
  m.tables.push_back(sizedMapTable(1.0, 1.0, 0.1 + kPi / 2, 1.0, 0.6, 0.06));
  m.tables.push_back(sizedMapTable(3.0, 1.0, kPi / 2 + 0.05, 0.45, 0.45, 0.03));
  const Evaluation e = crunch::evaluate(m, s, roomsTolerance());
  CHECK(e.matched == 2);
  CHECK(e.mean_angle_error == Approx(0.025));
  CHECK(e.max_width_error == Approx(0.0).margin(1e-12));
}

TEST_CASE("Evaluation: one object reported as two, and two as one, are counted", "[mapping]") {
  Scene s = emptyScene();
  s.tables.push_back(sizedTable(1.5, 1.5, 0.0, 1.4, 0.7, 0.05));  // a desk
  s.tables.push_back(sizedTable(1.0, 3.0, 0.0, 0.45, 0.45, 0.03));
  s.tables.push_back(sizedTable(1.55, 3.0, 0.0, 0.45, 0.45, 0.03));  // two chairs side by side
  Map m;
  m.tables.push_back(sizedMapTable(1.1, 1.5, 0.0, 0.6, 0.6, 0.05));  // the desk as two chairs
  m.tables.push_back(sizedMapTable(1.9, 1.5, 0.0, 0.6, 0.6, 0.05));
  m.tables.push_back(sizedMapTable(1.275, 3.0, 0.0, 1.0, 0.45, 0.03));  // two chairs as a bench
  const Evaluation e = crunch::evaluate(m, s, roomsTolerance());
  CHECK(e.split_objects == 1);
  CHECK(e.merged_objects == 1);
  CHECK(e.matched == 0);
  CHECK(crunch::evaluate(perfectMap(s), s).split_objects == 0);
}
