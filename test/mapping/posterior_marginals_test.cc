// Tests of posterior marginals from samples (crunch/mapping/posterior_marginals.h): a cluster's
// score is the fraction of samples holding it, shapes tell objects apart at one spot, and a
// near-square table's angle means the same a quarter turn on when square_half_period is set.
#include "crunch/mapping/posterior_marginals.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

using namespace crunch;

namespace {

ObjectSample table(int sample, double x, double y, double theta, double w, double d) {
  return {sample, {x, y, theta}, {w, d, 0.05}};
}

}  // namespace

TEST_CASE("posteriorMarginals: score is the fraction of samples holding the object, pose their mean",
          "[mapping]") {
  // Four samples: a table in all four (one sample holds two copies: counted once), another in one.
  const std::vector<ObjectSample> items = {
      table(0, 1.00, 1.00, 0.10, 0.8, 0.5), table(1, 1.02, 1.00, 0.12, 0.8, 0.5),
      table(2, 0.98, 1.02, 0.08, 0.8, 0.5), table(3, 1.00, 0.98, 0.10, 0.8, 0.5),
      table(3, 1.01, 0.99, 0.10, 0.8, 0.5), table(2, 3.00, 3.00, 1.00, 0.8, 0.5)};
  const std::vector<MarginalObject> out = posteriorMarginals(items, 4, MarginalOptions{});
  REQUIRE(out.size() == 2);
  CHECK(out[0].samples == 4);
  CHECK(out[0].score == Approx(1.0));
  CHECK(out[0].pose.x == Approx(1.0).margin(0.01));
  CHECK(out[0].pose.theta == Approx(0.10).margin(0.01));
  CHECK(out[1].score == Approx(0.25));
  CHECK(out[1].pose.x == Approx(3.0));
}

TEST_CASE("posteriorMarginals: a chair and a table at one spot are two objects", "[mapping]") {
  const std::vector<ObjectSample> items = {table(0, 1, 1, 0.0, 0.45, 0.45),
                                           table(1, 1, 1, 0.0, 0.45, 0.45),
                                           table(2, 1, 1, 0.0, 0.80, 0.50)};
  MarginalOptions opt;
  opt.shape_tolerance = 0.10;
  const std::vector<MarginalObject> out = posteriorMarginals(items, 3, opt);
  REQUIRE(out.size() == 2);
  CHECK(out[0].score == Approx(2.0 / 3.0));
  CHECK(out[0].shape[0] == Approx(0.45));
  CHECK(out[1].shape[0] == Approx(0.80));
}

TEST_CASE("posteriorMarginals: a square table turned a quarter is the same table with "
          "square_half_period",
          "[mapping]") {
  // One square chair seen at theta = 0.02, 1.58 (a quarter turn on) and 3.13 (a half turn less a
  // bit): across the period's seam, so a plain mean of angles would be wrong.
  const std::vector<ObjectSample> chair = {table(0, 1, 1, 0.02, 0.45, 0.44),
                                           table(1, 1, 1, 1.58, 0.45, 0.45),
                                           table(2, 1, 1, 3.13, 0.44, 0.45)};
  MarginalOptions opt;
  SECTION("off: the quarter-turned one is another object") {
    const std::vector<MarginalObject> out = posteriorMarginals(chair, 3, opt);
    CHECK(out.size() == 2);
  }
  SECTION("on: one object, its angle the mean modulo pi/2") {
    opt.square_half_period = true;
    const std::vector<MarginalObject> out = posteriorMarginals(chair, 3, opt);
    REQUIRE(out.size() == 1);
    CHECK(out[0].score == Approx(1.0));
    CHECK(std::abs(wrapPeriod(out[0].pose.theta - 0.01, kPi / 2)) < 0.02);
  }
  SECTION("on, but an oblong table a quarter turned is another table") {
    opt.square_half_period = true;
    const std::vector<ObjectSample> desk = {table(0, 1, 1, 0.02, 0.8, 0.5),
                                            table(1, 1, 1, 1.58, 0.8, 0.5)};
    CHECK(posteriorMarginals(desk, 2, opt).size() == 2);
  }
}

TEST_CASE("MarginalOptions::validate names the bad field", "[mapping]") {
  MarginalOptions opt;
  CHECK(opt.validate());
  opt.radius = 0.0;
  REQUIRE_FALSE(opt.validate());
  CHECK(opt.validate().error().message.find("radius") != std::string::npos);
}
