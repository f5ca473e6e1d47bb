// Tests of `--explore infogain` (crunch/exploration/infogain_policy.h): Fig. 7's rival tables
// send the robot to a disputed leg; what every draw agrees on is worth nothing; a fully known,
// empty room stops the run; unknown space is worth visiting; the choice is deterministic.
#include "crunch/exploration/infogain_policy.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

using namespace crunch;
using namespace crunch::exploration;

namespace {

// Fig. 7: legs L1 (1.0, 1.5) and L2 (1.75, 1.5) are touched; T1 (north) and T2 (south) explain
// them equally; half the draws hold each. T1's other legs are at y = 1.95, T2's at y = 1.05.
MapTable table(double x, double y) {
  MapTable t;
  t.pose = {x, y, 0.0};
  return t;
}
const MapTable kNorth = table(1.375, 1.725);
const MapTable kSouth = table(1.375, 1.275);

struct World {
  KnownSpace known{{0.0, 0.0}, {3.0, 3.0}, 0.05};
  std::vector<MapSample> samples;
  std::vector<WhiskerMount> mounts = defaultWhiskerArray();
  ModelParams model;
  PlannerOptions planner;
};

struct State {
  Costmap costmap;
  DistanceField travel;
  ExploreState state;
  State(World& w, const Pose2& robot)
      : costmap(w.known, w.planner),
        travel(costmap, robot.position()),
        state{robot, w.known, costmap, travel, w.samples, w.mounts, w.model, {}, 1, 0.0} {}
};

// Everything swept (known free), L1 and L2 touched.
void knownRoomWithTouchedLegs(World& w) {
  w.known.markBody({1.5, 1.5}, 5.0);
  w.known.markContact({1.0, 1.5});
  w.known.markContact({1.75, 1.5});
}

// knownRoomWithTouchedLegs, and 16 draws split 8:8 between the rival tables kNorth and kSouth.
void knownRoomWithRivalDraws(World& w) {
  knownRoomWithTouchedLegs(w);
  for (int i = 0; i < 16; ++i) w.samples.push_back({{i % 2 ? kNorth : kSouth}, {}, {}});
}

bool reachesDisputedLeg(const Pose2& pose) {
  WhiskPredictor p(defaultWhiskerArray());
  std::vector<WhiskerContact> out;
  for (const MapTable& t : {kNorth, kSouth}) {
    MapSample s;
    s.tables.push_back(t);
    WhiskObstacles obs;
    obs.assign(s);
    p.predict(pose, obs, out);
    for (const WhiskerContact& c : out)
      if (c.hit && std::abs(c.point.y() - 1.5) > 0.2) return true;  // not L1 or L2
  }
  return false;
}

}  // namespace

TEST_CASE("Infogain: rival tables send the robot to touch a disputed leg (Fig. 7)",
          "[exploration][infogain]") {
  World w;
  knownRoomWithRivalDraws(w);
  State s(w, {2.6, 2.6, 0.0});
  InfogainPolicy policy(PolicyOptions{});
  Rng rng(1);
  const Decision d = policy.next(s.state, rng);
  REQUIRE(d.goal);
  INFO("goal " << d.goal->x << " " << d.goal->y << " " << d.goal->theta << " score " << d.score);
  CHECK(reachesDisputedLeg(*d.goal));
  // The draws split 8:8 there: one bit, nothing from the (fully swept) space.
  const CandidateValue v = policy.value(s.state, *d.goal);
  CHECK(v.sample_bits == Approx(1.0));
  CHECK(v.unknown_bits == 0.0);
  CHECK(d.score == Approx(1.0 / (v.travel_m + InfogainOptions{}.whisk_cost_m)));

  // Whisking the shared leg L1 from the west tells nothing: both tables predict the same touch.
  const CandidateValue shared = policy.value(s.state, {1.0 - 0.235, 1.5, 0.0});
  CHECK(shared.travel_m < 1e9);
  CHECK(shared.sample_bits == 0.0);
}

TEST_CASE("Infogain: the goal whisked, and a pose within the loop's arrival tolerance of where "
          "it whisked, are that whisk again", "[exploration][infogain]") {
  // The driving loop counts a goal reached within its waypoint tolerance and whisks where it
  // stands. If the draws still disagree there (the whisk settled nothing they dispute), the
  // same goal, or one beside the robot, would win again and again with the robot never moving.
  World w;
  knownRoomWithRivalDraws(w);
  State s(w, {2.6, 2.6, 0.0});
  Rng rng(1);
  for (const double tolerance : {0.0, 0.05}) {
    InfogainPolicy policy(PolicyOptions{});
    s.state.arrival_tolerance = tolerance;
    const Decision d = policy.next(s.state, rng);
    REQUIRE(d.goal);
    CHECK(policy.value(s.state, *d.goal).sample_bits == Approx(1.0));
    // Arrived 4 cm short of the goal, at its heading, and whisked there.
    const Pose2 at{d.goal->x - 0.04, d.goal->y, d.goal->theta};
    State there(w, at);
    there.state.whisks = s.state.whisks + 1;
    there.state.arrival_tolerance = tolerance;
    const Decision again = policy.next(there.state, rng);
    REQUIRE(again.goal);
    INFO("tolerance " << tolerance << ": next goal (" << again.goal->x << ", " << again.goal->y
                      << ", " << again.goal->theta << ")");
    // The goal itself has been whisked, whatever the tolerance.
    CHECK(policy.value(there.state, *d.goal).score == 0.0);
    CHECK_FALSE((again.goal->x == d.goal->x && again.goal->y == d.goal->y &&
                 again.goal->theta == d.goal->theta));
    // 3 cm from where the robot stands (7 cm from the goal), at its heading: the loop would
    // not move for it.
    const Pose2 beside{at.x - 0.03, at.y, at.theta};
    if (tolerance == 0.0) {
      CHECK(policy.value(there.state, beside).sample_bits > 0.0);
    } else {
      CHECK(policy.value(there.state, beside).score == 0.0);
      CHECK((std::hypot(again.goal->x - at.x, again.goal->y - at.y) > tolerance ||
             std::abs(wrapPi(again.goal->theta - at.theta)) > WhiskPredictionOptions{}.amplitude / 2));
    }
  }
}

TEST_CASE("Infogain: where the robot stopped short of a goal, without whisking, was not whisked",
          "[exploration][infogain]") {
  World w;
  knownRoomWithRivalDraws(w);
  State s(w, {2.6, 2.6, 0.0});
  s.state.whisks = 1;  // the robot whisked where it stands
  InfogainPolicy policy(PolicyOptions{});
  Rng rng(1);
  const Decision d = policy.next(s.state, rng);
  REQUIRE(d.goal);
  // It drove towards the goal and stopped 4 cm short (a goal given up), whisking nothing: the
  // disputed leg is as unsettled there as before.
  const Pose2 stopped{d.goal->x - 0.04, d.goal->y, d.goal->theta};
  State there(w, stopped);
  there.state.whisks = 1;
  policy.next(there.state, rng);
  CHECK(policy.value(there.state, stopped).sample_bits == Approx(1.0));
  // Where it whisked before still repeats that whisk.
  CHECK(policy.value(there.state, {2.6, 2.6, 0.0}).score == 0.0);
}

TEST_CASE("Infogain: draws that agree are worth nothing, a known empty room stops the run",
          "[exploration][infogain]") {
  World w;
  knownRoomWithTouchedLegs(w);
  for (int i = 0; i < 16; ++i) w.samples.push_back({{kNorth}, {}, {}});  // no rival
  State s(w, {2.6, 2.6, 0.0});
  InfogainPolicy policy(PolicyOptions{});
  Rng rng(1);
  const Decision d = policy.next(s.state, rng);
  CHECK_FALSE(d.goal);
  CHECK(d.why == "no candidate worth its travel");

  World empty;
  empty.known.markBody({1.5, 1.5}, 5.0);
  State e(empty, {1.5, 1.5, 0.0});
  InfogainPolicy p2(PolicyOptions{});
  CHECK_FALSE(p2.next(e.state, rng).goal);
}

TEST_CASE("Infogain: unswept space is worth the Poisson prior's bits, and the choice is "
          "deterministic", "[exploration][infogain]") {
  World w;  // nothing swept, no draws yet
  w.known.markBody({0.6, 0.6}, 0.3);
  State s(w, {0.6, 0.6, 0.0});
  InfogainPolicy a(PolicyOptions{}), b(PolicyOptions{});
  Rng r1(1), r2(99);
  const Decision da = a.next(s.state, r1);
  const Decision db = b.next(s.state, r2);
  REQUIRE(da.goal);
  REQUIRE(db.goal);
  CHECK(da.goal->x == db.goal->x);
  CHECK(da.goal->y == db.goal->y);
  CHECK(da.goal->theta == db.goal->theta);
  const CandidateValue v = a.value(s.state, *da.goal);
  CHECK(v.sample_bits == 0.0);
  // The whisk alone (path_sweep off): lambda = (1 prior leg + 0) / (1 m^2 + swept area), below
  // 1 leg per m^2. The whiskers' band (0.165..0.305 m over 97.5 degrees, 0.056 m^2) touches at
  // most 45 cells of 5 cm (0.11 m^2, cells counted whole), so p = 1 - exp(-lambda A) < 0.11;
  // the outcome is no touch or a touch at one of A / (15 mm)^2 places: H_b(p) + p log2(A /
  // 0.015^2) bits at most.
  const Decision dc = da;
  const CandidateValue vw = v;
  CHECK(a.legDensity() < 1.0);
  CHECK(vw.unknown_bits > 0.05);
  CHECK(vw.unknown_bits < unknownOutcomeBits(1.0, 0.11, 0.015));
  // With the drive counted (path_sweep), the same pose is worth the band its path sweeps
  // besides: the unswept area grows by at most the body's width (plus a cell each side) along
  // the travel and its disc at the goal, and the bits are the same formula's over the whole
  // area.
  InfogainOptions with_path;
  with_path.path_sweep = true;
  InfogainPolicy c(PolicyOptions{}, with_path);
  Rng r3(1);
  REQUIRE(c.next(s.state, r3).goal);
  const CandidateValue vp = c.value(s.state, *dc.goal);
  const double radius = kRobotRadius, cell = w.known.cell();
  CHECK(vp.unknown_m2 > vw.unknown_m2 + 0.5 * 2 * radius * (vp.travel_m / 1.5 - 0.3 - radius));
  CHECK(vp.unknown_m2 <= vw.unknown_m2 + (2 * radius + 2 * cell) * vp.travel_m + kPi * radius * radius);
  CHECK(vp.unknown_bits == Approx(unknownOutcomeBits(c.legDensity(), vp.unknown_m2, 0.015)));
  CHECK(vp.unknown_bits > vw.unknown_bits);
  CHECK(unknownOutcomeBits(1.0, 0.11, 0.015) ==
        Approx(binaryEntropyBits(1 - std::exp(-0.11)) +
               (1 - std::exp(-0.11)) * std::log2(0.11 / (0.015 * 0.015))));
  // The same pose again (the robot whisked there) is worth nothing.
  ExploreState again = s.state;
  again.robot = *da.goal;
  again.whisks = 2;
  a.next(again, r1);
  CHECK(a.value(again, *da.goal).score == 0.0);
}

TEST_CASE("Infogain: the region's edges are known walls, draws disagreeing only on how far a "
          "wall runs along an edge carry no information", "[exploration][infogain]") {
  World w;
  w.known.markBody({1.5, 1.5}, 5.0);
  // Half the draws extend the wall along the edge y = 0 (placed 2 cm in, as noisy contacts put
  // it) to x = 1.0, half only to x = 0.5.
  for (int i = 0; i < 16; ++i) {
    MapSample s;
    s.walls.push_back({{0.0, 0.02}, {i % 2 ? 1.0 : 0.5, 0.02}, 1.0});
    w.samples.push_back(s);
  }
  State s(w, {1.5, 1.5, 0.0});
  InfogainPolicy policy(PolicyOptions{});
  // Facing the edge at x = 0.75, where the draws' walls differ: the edge is there in all.
  const CandidateValue edge = policy.value(s.state, {0.75, 0.25, -kPi / 2});
  REQUIRE(edge.travel_m < 1e9);  // reachable: a real score, not the unreachable 0
  CHECK(edge.sample_bits == 0.0);
  // The same disagreement about an interior wall (y = 1.0) is worth a bit.
  World v;
  v.known.markBody({1.5, 1.5}, 5.0);
  for (int i = 0; i < 16; ++i) {
    MapSample m;
    m.walls.push_back({{0.3, 1.0}, {i % 2 ? 1.0 : 0.5, 1.0}, 1.0});
    v.samples.push_back(m);
  }
  State t(v, {1.5, 1.5, 0.0});
  InfogainPolicy p2(PolicyOptions{});
  CHECK(p2.value(t.state, {0.75, 1.25, -kPi / 2}).sample_bits == Approx(1.0));
}

TEST_CASE("Infogain: the branch and bound is exact: no candidate, pruned or cut off, is worth "
          "more than its choice",
          "[exploration][infogain]") {
  // Half-swept room with Fig. 7's rival tables: candidates are worth draw bits near the
  // disputed legs and unswept-space bits elsewhere, with and without the path's sweep.
  for (const int variant : {0, 1, 2, 3, 4, 7}) {
    const bool path = variant & 1, table_prior = variant & 2, report = variant & 4;
    INFO("path_sweep " << path << ", table_prior " << table_prior << ", report_level " << report);
    World w;
    w.known.markBody({1.0, 1.0}, 0.9);
    w.known.markContact({1.0, 1.5});
    w.known.markContact({1.75, 1.5});
    for (int i = 0; i < 16; ++i) {
      MapSample s;
      s.tables.push_back(i % 2 ? kNorth : kSouth);
      w.samples.push_back(s);
    }
    State s(w, {0.8, 0.8, 0.0});
    InfogainOptions io;
    io.path_sweep = path;
    io.table_prior = table_prior;
    io.report_level = io.merge_repeats = report;
    InfogainPolicy policy(PolicyOptions{}, io);
    Rng rng(1);
    const Decision d = policy.next(s.state, rng);
    REQUIRE(d.goal);
    // Every candidate next() generated, scored in full by value() (which never prunes).
    InfogainPolicy judge(PolicyOptions{}, io);
    judge.next(s.state, rng);  // the same state prepared, the same candidates
    int scored = 0;
    for (const CandidateValue& c : policy.lastCandidates()) {
      const CandidateValue full = judge.value(s.state, c.pose);
      if (full.score > d.score * (1 + 1e-9) + 1e-12)
        FAIL_CHECK("pruned (" << c.pose.x << ", " << c.pose.y << ", " << c.pose.theta << ") worth "
                              << full.score << " > chosen " << d.score);
      ++scored;
    }
    // And the whole lattice, including what the global bound cut off unseen.
    const PolicyOptions po;
    for (double y = 0.5 * po.candidate_spacing; y < 3.0; y += po.candidate_spacing)
      for (double x = 0.5 * po.candidate_spacing; x < 3.0; x += po.candidate_spacing) {
        if (s.state.costmap.blocked(Vec2(x, y))) continue;
        for (int h = 0; h < po.candidate_headings; ++h) {
          const Pose2 c{x, y, wrapPi(2.0 * kPi * h / po.candidate_headings)};
          const CandidateValue full = judge.value(s.state, c);
          if (full.score > d.score * (1 + 1e-9) + 1e-12)
            FAIL_CHECK("lattice (" << x << ", " << y << ", " << c.theta << ") worth " << full.score
                                   << " > chosen " << d.score);
          ++scored;
        }
      }
    CHECK(scored > 1000);
    CHECK(d.score == Approx(judge.value(s.state, *d.goal).score));
  }
}

TEST_CASE("Infogain: hidden tables: the prior's configurations, each leg's three partners",
          "[exploration][infogain]") {
  const double cell = 0.05;
  ModelParams paper;
  const HiddenTableOffsets p = hiddenTableOffsets(paper, cell);
  REQUIRE(p.weight.size() == 24);  // one size x 12 orientations x 2 mirror images
  REQUIRE(p.dx.size() == 3 * p.weight.size());
  double sum = 0.0;
  for (const double w : p.weight) sum += w;
  CHECK(sum == Approx(1.0));
  // The paper's 0.8 x 0.5 m top on 5 cm legs: partners 0.75 m, 0.45 m and their diagonal away.
  for (size_t c = 0; c < p.weight.size(); ++c) {
    std::vector<double> d;
    for (size_t q = 3 * c; q < 3 * c + 3; ++q) d.push_back(std::hypot(p.dx[q], p.dy[q]) * cell);
    std::sort(d.begin(), d.end());
    CHECK(d[0] == Approx(0.45).margin(cell));
    CHECK(d[1] == Approx(0.75).margin(cell));
    CHECK(d[2] == Approx(std::hypot(0.45, 0.75)).margin(cell));
  }
  ModelParams rooms;
  rooms.objects = ObjectModel::kRooms;
  const HiddenTableOffsets r = hiddenTableOffsets(rooms, cell);
  CHECK(r.weight.size() > p.weight.size());
  sum = 0.0;
  for (const double w : r.weight) sum += w;
  CHECK(sum == Approx(1.0));
}

TEST_CASE("Infogain: hidden tables: an unswept cell is worth the share of tables whose other legs "
          "could stand unswept too", "[exploration][infogain]") {
  for (const ObjectModel m : {ObjectModel::kPaper, ObjectModel::kRooms}) {
    ModelParams model;
    model.objects = m;
    KnownSpace known({0.0, 0.0}, {8.0, 6.0}, 0.05);
    // Swept: everything in x < 3 but a strip 0.3 m wide (narrower than any table's legs are apart).
    for (double y = 0.025; y < 6.0; y += 0.05)
      for (double x = 0.025; x < 3.0; x += 0.05)
        if (!(x > 1.0 && x < 1.3)) known.markBody({x, y}, 0.01);
    std::vector<float> w;
    hiddenLegWeights(known, hiddenTableOffsets(model, known.cell()), w);
    auto at = [&](double x, double y) {
      int ix, iy;
      REQUIRE(known.index({x, y}, ix, iy));
      return w[static_cast<size_t>(iy * known.nx() + ix)];
    };
    CHECK(at(0.5, 3.0) == 0.0f);               // swept
    CHECK(at(1.125, 3.0) == 0.0f);             // in the strip: no table fits its four legs there
    CHECK(at(5.5, 3.0) == Approx(1.0f));       // deep in unswept space: every table fits
    const float edge = at(7.975, 3.0);         // at the room's wall: only tables reaching in
    CHECK(edge > 0.0f);
    CHECK(edge < 0.75f);
    const float frontier = at(3.025, 3.0);     // next to swept space: only tables reaching away
    CHECK(frontier > 0.0f);
    CHECK(frontier < 0.75f);
    // Contacts along the room's wall: their cells are known, but a table may stand flush
    // against the wall with its legs on them, so the cells beside keep their weight.
    const float beside = at(7.925, 3.0);
    for (double y = 2.0; y < 4.0; y += 0.05) known.markContact({7.975, y});
    hiddenLegWeights(known, hiddenTableOffsets(model, known.cell()), w);
    CHECK(at(7.975, 3.0) == 0.0f);  // the contact's own cell is not unswept
    CHECK(at(7.925, 3.0) == Approx(beside));
    // Swept free beside it: tables with a leg there are ruled out.
    for (double y = 2.025; y < 4.0; y += 0.05)
      for (double x = 7.025; x < 7.6; x += 0.05) known.markBody({x, y}, 0.01);
    hiddenLegWeights(known, hiddenTableOffsets(model, known.cell()), w);
    CHECK(at(7.925, 3.0) < beside);
  }
}

TEST_CASE("Infogain: an unswept strip no table fits in is worth nothing, open unswept space is",
          "[exploration][infogain]") {
  World w;  // 3 x 3 m; swept everywhere but a 0.3 m strip at x in [1.0, 1.3] and x > 2.2
  for (double y = 0.025; y < 3.0; y += 0.05)
    for (double x = 0.025; x < 2.2; x += 0.05)
      if (!(x > 1.0 && x < 1.3)) w.known.markBody({x, y}, 0.01);
  State s(w, {0.6, 1.5, 0.0});
  InfogainOptions on;
  on.table_prior = true;
  InfogainPolicy with_prior(PolicyOptions{}, on);
  InfogainPolicy without(PolicyOptions{});  // the default: cells counted whole
  const Pose2 strip{0.85, 1.5, 0.0}, open{2.05, 1.5, 0.0};  // whiskers reach x 1.0 .. 1.16 / 2.2 .. 2.36
  const CandidateValue sp = with_prior.value(s.state, strip), op = with_prior.value(s.state, open);
  const CandidateValue sw = without.value(s.state, strip), ow = without.value(s.state, open);
  CHECK(sw.unknown_bits > 0.1);   // cells counted whole: the strip looks as good as open space
  CHECK(sp.unknown_bits == 0.0);  // no table's four legs fit in 0.3 m
  // Next to swept space only the tables reaching away from it can still hide: the frontier's
  // cells count in part, the strip's not at all.
  CHECK(op.unknown_bits > 0.01);
  CHECK(op.unknown_m2 < ow.unknown_m2);
  CHECK(ow.unknown_bits > op.unknown_bits);
}

TEST_CASE("Infogain: report level: draws that report one map tell it nothing where their "
          "contacts differ, rival maps keep their bits",
          "[exploration][infogain]") {
  // Everything swept, L1 and L2 touched. Half the draws hold kNorth, half kNorth 3 cm east: one
  // map at the map's tolerance (0.10 m), yet a whisker touching a leg touches it twice the
  // sensor's resolution apart in the two halves (or, at a graze, in one half only).
  World w;
  knownRoomWithTouchedLegs(w);
  MapTable east = kNorth;
  east.pose.x += 0.03;
  for (int i = 0; i < 16; ++i) w.samples.push_back({{i % 2 ? kNorth : east}, {}, {}});
  State s(w, {2.6, 2.6, 0.0});
  InfogainOptions draw_level, report_level;
  report_level.report_level = true;
  InfogainPolicy by_draw(PolicyOptions{}, draw_level), by_report(PolicyOptions{}, report_level);
  // Poses facing each of kNorth's legs from whisker reach.
  int differ = 0;
  for (const OrientedRect& leg : legSquares(kNorth)) {
    for (int a = 0; a < 72; ++a) {
      for (const double r : {0.2, 0.25, 0.3}) {
        const double ang = 2.0 * kPi * a / 72;
        const Vec2 p = leg.pose.position() - r * Vec2{std::cos(ang), std::sin(ang)};
        if (s.state.costmap.blocked(p)) continue;
        const Pose2 pose{p.x(), p.y(), ang};
        const double drawn = by_draw.value(s.state, pose).sample_bits;
        CHECK(by_report.value(s.state, pose).sample_bits == 0.0);
        differ += drawn > 0.5;
      }
    }
  }
  INFO("poses where the two halves' contacts differ: " << differ);
  CHECK(differ > 100);  // the draw-level value counts them (a whole bit each)

  // Fig. 7's rivals report different maps: the disputed leg is worth its bit either way.
  World rivals;
  knownRoomWithRivalDraws(rivals);
  State r(rivals, {2.6, 2.6, 0.0});
  InfogainPolicy policy(PolicyOptions{}, report_level);
  Rng rng(1);
  const Decision d = policy.next(r.state, rng);
  REQUIRE(d.goal);
  CHECK(reachesDisputedLeg(*d.goal));
  CHECK(policy.value(r.state, *d.goal).sample_bits == Approx(1.0));
}

TEST_CASE("Infogain: the same reported map: tables and walls within the map's tolerance, one "
          "to one",
          "[exploration][infogain]") {
  const FuseOptions tol;
  MapTable a = kNorth, b = kNorth;
  b.pose.x += 0.09;
  b.pose.theta += 0.1;
  MapTable far = kNorth;
  far.pose.x += 0.11;
  const MapWall w1{{0.0, 1.0}, {2.0, 1.0}, 1.0};
  const MapWall w1_reversed{{2.05, 1.0}, {0.0, 1.05}, 1.0};
  const MapWall w1_longer{{0.0, 1.0}, {2.3, 1.0}, 1.0};
  const std::vector<MapTable> one_a{a}, one_b{b}, one_far{far}, two{a, kSouth}, two_swapped{kSouth, b};
  const std::vector<MapWall> none, wall{w1}, wall_rev{w1_reversed}, wall_long{w1_longer};
  CHECK(sameReportedMap(one_a, none, one_b, none, tol));
  CHECK_FALSE(sameReportedMap(one_a, none, one_far, none, tol));
  CHECK(sameReportedMap(two, none, two_swapped, none, tol));
  CHECK_FALSE(sameReportedMap(one_a, none, two, none, tol));
  CHECK(sameReportedMap(one_a, wall, one_b, wall_rev, tol));
  CHECK_FALSE(sameReportedMap(one_a, wall, one_a, wall_long, tol));
  CHECK_FALSE(sameReportedMap(one_a, wall, one_a, none, tol));
  // Sizes count when the model sizes its tables.
  FuseOptions sized = tol;
  sized.compare_sizes = true;
  MapTable wider = a;
  wider.width += 0.15;
  const std::vector<MapTable> one_wider{wider};
  CHECK(sameReportedMap(one_a, none, one_wider, none, tol));
  CHECK_FALSE(sameReportedMap(one_a, none, one_wider, none, sized));
}
