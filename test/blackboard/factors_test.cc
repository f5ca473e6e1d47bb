#include "crunch/blackboard/factors.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <vector>

#include "test_builders.h"

using namespace crunch;

namespace {
constexpr double kTight = 1e-12;  // pure arithmetic: only rounding differs
}

TEST_CASE("Factors: Delta_TL (eq. 10) against a hand-computed value", "[blackboard]") {
  const ModelParams p;
  LegHyp leg;
  // Corner 0's leg centre is (0.375, 0.225); move it 1 cm (one sigma) and turn it half a sigma.
  leg.pose = {0.385, 0.225, kPi / 64};
  int corner = -1;
  CHECK(deltaTL({0, 0, 0}, leg, p, &corner) == Approx(1.0 + 0.25).epsilon(kTight));
  CHECK(corner == 0);
  // A quarter turn of the leg is the same square: no angle penalty.
  leg.pose = {-0.375, -0.225, kPi / 2};
  CHECK(deltaTL({0, 0, 0}, leg, p, &corner) == Approx(0.0).margin(kTight));
  CHECK(corner == 2);
}

TEST_CASE("Factors: Delta_LS (eq. 12) uses perimeter distance and the touched side", "[blackboard]") {
  const ModelParams p;
  LegHyp leg;
  leg.pose = {0, 0, 0};
  Shapelet s;
  s.x = 0.030;  // 5 mm outside the +x face: half a sigma
  s.y = 0.0;
  s.phi = kPi / 2;  // the +x face runs along y
  CHECK(deltaLS(leg, s, p) == Approx(0.25).epsilon(kTight));
  s.phi = kPi / 2 + kPi / 32;  // one sigma of angle
  CHECK(deltaLS(leg, s, p) == Approx(1.25).epsilon(kTight));
  s.phi = -kPi / 2;  // a line: the same orientation
  CHECK(deltaLS(leg, s, p) == Approx(0.25).epsilon(kTight));
  s.x = 0.0;  // on the +y face, which runs along x
  s.y = 0.025;
  s.phi = kPi;
  CHECK(deltaLS(leg, s, p) == Approx(0.0).margin(kTight));
}

TEST_CASE("Factors: near a corner Delta_LS compares a shapelet with the face its line fits "
          "(walls and rooms models)", "[blackboard]") {
  ModelParams p;
  LegHyp leg;
  leg.pose = {0, 0, 0};
  leg.side = 0.05;
  Shapelet s;
  // Inside the corner (0.025, -0.025): 1 mm from the -y face, 3 mm from the +x face, and
  // oriented along y, as a contact on the +x face is.
  s.x = 0.022;
  s.y = -0.024;
  s.phi = kPi / 2;
  const double on_x_face = 0.3 * 0.3;  // 3 mm is 0.3 sigma; the angle fits exactly
  // 1 mm, but a quarter turn off: (pi/2) / (pi/32) = 16 sigma
  const double on_y_face = 0.1 * 0.1 + 16.0 * 16.0;
  // The paper model compares the angle with the nearest face's.
  p.objects = ObjectModel::kPaper;
  CHECK(deltaLS(leg, s, p) == Approx(on_y_face).epsilon(1e-9));
  for (ObjectModel m : {ObjectModel::kWalls, ObjectModel::kRooms}) {
    p.objects = m;
    CHECK(deltaLS(leg, s, p) == Approx(on_x_face).epsilon(1e-9));
    // Along x the -y face fits: 1 mm.
    s.phi = 0.0;
    CHECK(deltaLS(leg, s, p) == Approx(0.1 * 0.1).epsilon(1e-9));
    s.phi = kPi / 2;
    // The distance to a face is to its segment: beyond the corner, both legs of the L count.
    Shapelet out = s;
    out.x = 0.028;   // 3 mm past the +x face ...
    out.y = -0.029;  // ... and 4 mm past the corner along it: 5 mm to the face's segment
    CHECK(deltaLS(leg, out, p) == Approx(0.5 * 0.5).epsilon(1e-9));
    // A turned leg: the same shapelet in the leg's frame gives the same Delta.
    LegHyp turned = leg;
    turned.pose = {1.0, 2.0, 0.7};
    Shapelet t = s;
    const Vec2 w = turned.pose.toWorld(Vec2{s.x, s.y});
    t.x = w.x();
    t.y = w.y();
    t.phi = s.phi + 0.7;
    CHECK(deltaLS(turned, t, p) == Approx(on_x_face).epsilon(1e-9));
    // On a face's middle both readings agree; an unoriented shapelet has no face to choose.
    Shapelet mid;
    mid.x = 0.030;
    mid.phi = kPi / 2 + kPi / 32;
    CHECK(deltaLS(leg, mid, p) == Approx(1.25).epsilon(1e-12));
    Shapelet point = s;
    point.oriented = false;
    CHECK(deltaLS(leg, point, p) == Approx(0.1 * 0.1).epsilon(1e-9));
  }
}

TEST_CASE("Factors: leg and shapelet densities mix parent and null prior (eqs. 9, 13, 17)",
          "[blackboard]") {
  const ModelParams p;
  CHECK(logLegDensity(1.25, true, p) == Approx(std::log(0.1 + std::exp(-1.25))).epsilon(kTight));
  CHECK(logLegDensity(1.25, false, p) == Approx(std::log(0.1)).epsilon(kTight));
  const std::vector<double> k = {-0.5, -2.0};
  CHECK(logShapeletDensity(k, p) ==
        Approx(std::log(0.05 + std::exp(-0.5) + std::exp(-2.0))).epsilon(kTight));
  CHECK(logShapeletDensity({}, p) == Approx(std::log(0.05)).epsilon(kTight));
}

TEST_CASE("Factors: eq. 17 is the small-delta limit of discrete noisy-OR (eqs. 18-21)",
          "[blackboard]") {
  const std::vector<double> dens = {0.7, 2.5, 0.05, 1.3};
  double sum = 0;
  for (double d : dens) sum += d;
  for (double delta3 : {1e-2, 1e-4, 1e-6}) {
    double none = 1.0;
    for (double d : dens) none *= 1.0 - delta3 * d;
    const double noisy_or = (1.0 - none) / delta3;
    // The neglected terms are O(delta^6): relative error shrinks linearly in delta^3.
    CHECK(std::abs(noisy_or - sum) / sum < 10.0 * delta3);
  }
}

TEST_CASE("Factors: presence odds use delta^3 (eq. 28)", "[blackboard]") {
  const ModelParams p;
  CHECK(logPresenceOdds(std::log(0.4), p) == Approx(std::log(0.16 / 0.84)).epsilon(kTight));
  // A density too large for delta^3 is capped below probability one, never NaN.
  CHECK(std::isfinite(logPresenceOdds(std::log(1e9), p)));
}

TEST_CASE("Factors: acceptance probabilities of eq. 29", "[blackboard]") {
  CHECK(temperedAcceptance(0.0, 5.0) == Approx(0.5));
  CHECK(temperedAcceptance(std::log(3.0), 1.0) == Approx(0.75));
  CHECK(temperedAcceptance(std::log(3.0), 2.0) == Approx(0.9));
  CHECK(temperedAcceptance(-std::log(3.0), 2.0) == Approx(0.1));
  CHECK(temperedAcceptance(-1e6, 1.0) == 0.0);
  CHECK(temperedAcceptance(1e6, 1.0) == 1.0);
  CHECK(literalAcceptance(std::log(3.0), 1.0) == Approx(0.75));
  CHECK(literalAcceptance(std::log(3.0), 2.0) == Approx(0.5625));
  CHECK(logAddExp(-INFINITY, 1.0) == 1.0);
  CHECK(logAddExp(std::log(2.0), std::log(3.0)) == Approx(std::log(5.0)));
}

TEST_CASE("Factors: a face known to be longer than a leg's diagonal is no leg's (face_span)",
          "[blackboard]") {
  const ModelParams p;
  LegHyp leg;
  leg.pose = {0, 0, 0};
  leg.side = p.leg_side;
  Shapelet s;
  s.x = 0.030;
  s.y = 0.0;
  s.phi = kPi / 2;
  const double kernel = std::log(p.alpha_S) - deltaLS(leg, s, p);
  CHECK(logShapeletKernel(leg, s, p) == Approx(kernel).epsilon(kTight));
  s.face_span = 0.99 * std::sqrt(2.0) * p.leg_side;  // two points of one leg can be this far
  CHECK(legCanCause(p.leg_side, s));
  CHECK(logShapeletKernel(leg, s, p) == Approx(kernel).epsilon(kTight));
  s.face_span = 0.12;  // two whiskers' tips on one face, 12 cm apart: a wall's, not a leg's
  CHECK_FALSE(legCanCause(p.leg_side, s));
  CHECK(logShapeletKernel(leg, s, p) == -std::numeric_limits<double>::infinity());
  // Left to the background term alone.
  const std::vector<double> k = {logShapeletKernel(leg, s, p)};
  CHECK(logShapeletDensity(k, p) == Approx(std::log(p.c_S)).epsilon(kTight));
}

TEST_CASE("Params: the object model by name (--model, recordings)", "[blackboard]") {
  CHECK(objectModelByName("paper").value() == ObjectModel::kPaper);
  CHECK(objectModelByName("walls").value() == ObjectModel::kWalls);
  CHECK(objectModelByName("rooms").value() == ObjectModel::kRooms);
  CHECK(std::string(objectModelName(ObjectModel::kWalls)) == "walls");
  CHECK(ModelParams{.objects = ObjectModel::kWalls}.walled());
  CHECK_FALSE(ModelParams{.objects = ObjectModel::kWalls}.sized());
  CHECK(ModelParams{.objects = ObjectModel::kRooms}.walled());
  CHECK_FALSE(ModelParams{}.walled());
  const auto bad = objectModelByName("Rooms");
  REQUIRE_FALSE(bad);
  CHECK(bad.error().message.find("'Rooms'") != std::string::npos);
  CHECK(bad.error().message.find("paper | walls | rooms") != std::string::npos);
  CHECK(std::string(objectModelName(ObjectModel::kRooms)) == "rooms");
  CHECK(std::string(objectModelName(ObjectModel::kPaper)) == "paper");
  CHECK(ModelParams{}.objects == ObjectModel::kPaper);
}

TEST_CASE("Factors: Delta_TL of a table of its own size, with the leg-width term",
          "[blackboard]") {
  ModelParams p;
  p.objects = ObjectModel::kRooms;
  TableHyp chair;
  chair.pose = {1.0, 2.0, 0.0};
  chair.width = 0.45;
  chair.depth = 0.45;
  chair.leg = 0.03;
  LegHyp leg;
  leg.pose = {1.0 + 0.21, 2.0 + 0.21, 0.0};  // exactly chair corner 0: (0.45 - 0.03) / 2
  leg.side = 0.03;
  int corner = -1;
  CHECK(deltaTLSized(chair, leg, p, &corner) == Approx(0.0).margin(kTight));
  CHECK(corner == 0);
  // A leg 1 cm thicker than the chair's: (0.01 / sigma_w)^2 = 1.
  leg.side = 0.04;
  CHECK(deltaTLSized(chair, leg, p, &corner) == Approx(1.0).epsilon(kTight));
  // The paper's one-size form puts that leg 0.0 + ... far from its corners.
  CHECK(deltaTL(chair.pose, leg, p, nullptr) > 100.0);
}

TEST_CASE("Params: the catalog's term is the mixture's density over the uniform's, validated",
          "[blackboard]") {
  ModelParams p;  // catalog_weight 0.5, catalog_sigma 5 mm about the paper's 0.8 x 0.5 m
  // 1 / U: the (longer, shorter) region's area, 0.7 * 1.7 - 0.7^2 / 2 = 0.945 m^2.
  const double peak = std::log(0.5 + 0.5 * 0.945 / (2 * kPi * 0.005 * 0.005));
  CHECK(p.logCatalogFactor(0.8, 0.5) == Approx(peak));
  CHECK(p.logCatalogFactor(0.5, 0.8) == Approx(peak));  // either side may be the longer
  CHECK(peak > 7.5);  // a table of the catalog's size earns what a fixed size deserves
  // One sd off on each side: the Gaussian's exp(-1).
  CHECK(p.logCatalogFactor(0.805, 0.495) ==
        Approx(std::log(0.5 + 0.5 * 0.945 * std::exp(-1.0) / (2 * kPi * 0.005 * 0.005))));
  // Far from it, the uniform's share alone: a chair or a desk pays log 2.
  CHECK(p.logCatalogFactor(1.4, 0.7) == Approx(std::log(0.5)).margin(1e-12));
  CHECK(p.logCatalogFactor(0.45, 0.45) == Approx(std::log(0.5)).margin(1e-12));
  CHECK(p.logSizePrior(0.8, 0.5, 0.03) == Approx(peak));  // the leg side stays uniform
  p.catalog_weight = 0.0;
  CHECK(p.logCatalogFactor(0.8, 0.5) == 0.0);
  CHECK(p.validate());
  p.catalog_weight = 1.0;  // a model that knows only the catalog is the walls model
  REQUIRE_FALSE(p.validate());
  CHECK(p.validate().error().message.find("catalog_weight") != std::string::npos);
  p.catalog_weight = -0.1;
  CHECK_FALSE(p.validate());
  p.catalog_weight = 0.5;
  p.catalog_sigma = 0.0;
  REQUIRE_FALSE(p.validate());
  CHECK(p.validate().error().message.find("catalog_sigma") != std::string::npos);
}

TEST_CASE("Params: over the sides the evidence fixes, the catalog's term integrates the others "
          "out",
          "[blackboard]") {
  ModelParams p;
  const double s = 0.005, a2 = 2 * 0.945;  // the (width, depth) region is mirrored: area 2 A
  // Both sides fixed: the two-sided term, as before.
  CHECK(p.logCatalogFactor(0.8, 0.5, true, true) == p.logCatalogFactor(0.8, 0.5));
  // Neither: over a likelihood flat in both sides the mixture and the uniform integrate alike.
  CHECK(p.logCatalogFactor(0.8, 0.5, false, false) == 0.0);
  CHECK(p.logCatalogFactor(1.4, 0.7, false, false) == 0.0);
  // One side at 0.8 m: the catalog's 1-D marginal there is half a Gaussian's peak (0.8 is its
  // longer side, not its shorter); the uniform's is the depth range at that width, 1.7 m, over 2 A.
  const double n1 = 0.5 / (std::sqrt(2 * kPi) * s);
  const double one = std::log(0.5 + 0.5 * n1 * a2 / 1.7);
  CHECK(p.logCatalogFactor(0.8, 0.5, true, false) == Approx(one));
  CHECK(p.logCatalogFactor(0.8, 1.9, true, false) == Approx(one));  // the other side is free
  CHECK(p.logCatalogFactor(0.3, 0.8, false, true) == Approx(one));
  CHECK(p.logCatalogFactor(0.5, 0.8, true, false) == Approx(one));  // the shorter side alike
  CHECK(one > 3.0);
  CHECK(one < p.logCatalogFactor(0.8, 0.5) - 4.0);
  // A fixed side far from both of the catalog's: the uniform's share alone, over either range
  // (at 1.5 m, above the largest shorter side, the other side's range is 0.7 m).
  CHECK(p.logCatalogFactor(0.65, 0.5, true, false) == Approx(std::log(0.5)).margin(1e-12));
  CHECK(p.logCatalogFactor(1.5, 0.5, true, false) == Approx(std::log(0.5)).margin(1e-12));
  // logSizePrior passes the sides on.
  CHECK(p.logSizePrior(0.8, 0.5, 0.03, true, false) == Approx(one));
  CHECK(p.logSizePrior(0.8, 0.5, 0.03, false, false) == 0.0);
}

TEST_CASE("Params: the size prior's range is validated, each field by name", "[blackboard]") {
  ModelParams p;
  CHECK(p.validate());
  // Inside the range: one constant, the Occam factor log(2 pi 2 sigma_r^2 / A) +
  // log(sqrt(2 pi) sigma_w / (leg_max - leg_min)), A = 0.7 * 1.7 - 0.7^2 / 2 = 0.945 m^2.
  const double inside = std::log(2 * kPi * 2 * 1e-4 / 0.945) + std::log(std::sqrt(2 * kPi) * 0.01 / 0.06);
  // size_occam off (the default): uniform, but for the catalog's term (the next test).
  CHECK(p.logSizePrior(1.4, 0.7, 0.05) == p.logCatalogFactor(1.4, 0.7));
  p.catalog_weight = 0.0;
  CHECK(p.logSizePrior(1.4, 0.7, 0.05) == 0.0);
  ModelParams occam;
  occam.catalog_weight = 0.0;
  occam.size_occam = true;
  CHECK(occam.logSizePrior(1.4, 0.7, 0.05) == Approx(inside));
  CHECK(occam.logSizePrior(0.45, 0.45, 0.03) == Approx(inside));
  CHECK(occam.logSizePrior(0.7, 1.4, 0.05) == Approx(inside));  // either side may be the longer
  CHECK(p.logSizePrior(0.25, 0.45, 0.03) == -std::numeric_limits<double>::infinity());
  CHECK(p.logSizePrior(2.1, 0.6, 0.05) == -std::numeric_limits<double>::infinity());
  CHECK(p.logSizePrior(1.5, 1.2, 0.05) == -std::numeric_limits<double>::infinity());
  CHECK(p.logSizePrior(0.6, 0.6, 0.09) == -std::numeric_limits<double>::infinity());
  CHECK(p.logSizePrior(0.6, 0.6, 0.01) == -std::numeric_limits<double>::infinity());
  const auto bad = [](auto&& change) {
    ModelParams q;
    change(q);
    const Status s = q.validate();
    return s ? std::string() : s.error().message;
  };
  CHECK(bad([](ModelParams& q) { q.size_min_side = 0.0; }).find("size_min_side") != std::string::npos);
  CHECK(bad([](ModelParams& q) { q.size_max_short = 0.2; }).find("size_max_short") !=
        std::string::npos);
  CHECK(bad([](ModelParams& q) { q.size_max_long = 0.9; }).find("size_max_long") !=
        std::string::npos);
  CHECK(bad([](ModelParams& q) { q.leg_min = -0.01; }).find("leg_min") != std::string::npos);
  CHECK(bad([](ModelParams& q) { q.leg_max = 0.2; }).find("leg_max") != std::string::npos);
  CHECK(bad([](ModelParams& q) { q.leg_max = 0.01; }).find("leg_max") != std::string::npos);
  // A free wall end no likelier than a joined one (0.5: the term is off); 0 would be -inf.
  CHECK(bad([](ModelParams& q) { q.p_wall_end_free = 0.0; }).find("p_wall_end_free") !=
        std::string::npos);
  CHECK(bad([](ModelParams& q) { q.p_wall_end_free = 0.6; }).find("p_wall_end_free") !=
        std::string::npos);
  CHECK(bad([](ModelParams& q) { q.p_wall_end_free = 0.5; }).empty());
}
