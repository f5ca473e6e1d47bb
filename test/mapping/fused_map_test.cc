#include "crunch/mapping/fused_map.h"

#include <catch2/catch.hpp>
#include <vector>

using crunch::FuseOptions;
using crunch::kPi;
using crunch::MapTable;
using crunch::PoseMap;

namespace {
MapTable sized(double x, double y, double theta, double w, double d, double leg) {
  MapTable t;
  t.pose = {x, y, theta};
  t.width = w;
  t.depth = d;
  t.leg = leg;
  return t;
}

// `n` poses, each of whose MAPs holds `tables`, seen from a pose at the tables' place.
std::vector<PoseMap> posesSeeing(const std::vector<MapTable>& tables, int n) {
  std::vector<PoseMap> out;
  for (int i = 0; i < n; ++i) {
    PoseMap pm;
    pm.pose = {1.0, 1.0, 0.0};
    pm.tables = tables;
    out.push_back(pm);
  }
  return out;
}
}  // namespace

TEST_CASE("Fused map: with sizes compared, a chair and a table at one spot are two objects",
          "[mapping]") {
  FuseOptions opt;
  opt.min_support = 3;
  // Three poses see a 0.45 m chair, three a 0.8 x 0.5 table, at (nearly) the same place.
  std::vector<PoseMap> poses = posesSeeing({sized(1.0, 1.0, 0.0, 0.45, 0.45, 0.03)}, 3);
  for (const PoseMap& pm : posesSeeing({sized(1.02, 1.0, 0.0, 0.8, 0.5, 0.05)}, 3))
    poses.push_back(pm);
  const auto blind = crunch::fuseTables(poses, opt);
  REQUIRE(blind.size() == 1);  // sizes ignored: one cluster of six
  CHECK(blind[0].support == 6);
  opt.compare_sizes = true;
  const auto fused = crunch::fuseTables(poses, opt);
  // Two clusters of three; they overlap, so the fusion keeps one (eq. 25), with its own size.
  REQUIRE(fused.size() == 1);
  CHECK(fused[0].support == 3);
  const bool chair = fused[0].width == Approx(0.45) && fused[0].depth == Approx(0.45);
  const bool table = fused[0].width == Approx(0.8) && fused[0].depth == Approx(0.5);
  CHECK((chair || table));
}

TEST_CASE("Fused map: a cluster's size is its members' mean, a square's angle is modulo pi/2",
          "[mapping]") {
  FuseOptions opt;
  opt.compare_sizes = true;
  opt.min_support = 3;
  // A stool seen turned by a quarter in one pose: the same stool.
  std::vector<PoseMap> poses = posesSeeing({sized(2.0, 2.0, 0.02, 0.60, 0.58, 0.04)}, 2);
  for (const PoseMap& pm : posesSeeing({sized(2.01, 2.0, kPi / 2 + 0.01, 0.62, 0.60, 0.04)}, 1))
    poses.push_back(pm);
  const auto fused = crunch::fuseTables(poses, opt);
  REQUIRE(fused.size() == 1);
  CHECK(fused[0].support == 3);
  CHECK(fused[0].width == Approx((0.60 + 0.60 + 0.62) / 3));
  CHECK(fused[0].depth == Approx((0.58 + 0.58 + 0.60) / 3));
  CHECK(std::abs(crunch::wrapPeriod(fused[0].pose.theta - 0.0167, kPi / 2)) < 0.01);
  // Sizes 0.15 m apart (a 0.45 m chair against a 0.6 m stool) do not agree.
  CHECK_FALSE(crunch::tablesAgree(sized(1, 1, 0, 0.45, 0.45, 0.03), sized(1, 1, 0, 0.6, 0.6, 0.04),
                                  opt));
  CHECK(crunch::tablesAgree(sized(1, 1, 0, 0.45, 0.45, 0.03), sized(1, 1, 0, 0.5, 0.47, 0.04),
                            opt));
}

TEST_CASE("Fused map: tables pushed together both stay, overlapping ones do not", "[mapping]") {
  FuseOptions opt;
  opt.compare_sizes = true;
  opt.min_support = 3;
  // adjacent_tables' pair: 0.8 m wide, centres 0.8 m apart, the left one fitted 1 cm too wide
  // (its side reaches 5 mm into the right one's).
  std::vector<PoseMap> poses = posesSeeing({sized(2.4, 2.9, 0.0, 0.81, 0.5, 0.05)}, 4);
  for (const PoseMap& pm : posesSeeing({sized(3.2, 2.9, 0.0, 0.8, 0.5, 0.05)}, 3))
    poses.push_back(pm);
  CHECK(crunch::fuseTables(poses, opt).size() == 2);
  CHECK(crunch::tablesClash(sized(2.4, 2.9, 0.0, 0.81, 0.5, 0.05),
                            sized(3.2, 2.9, 0.0, 0.8, 0.5, 0.05), opt) == false);
  // 3 cm into each other: one of them is wrong, the better supported stays.
  for (PoseMap& pm : poses)
    for (MapTable& t : pm.tables)
      if (t.pose.x > 3.0) t.pose.x = 3.17;
  const auto fused = crunch::fuseTables(poses, opt);
  REQUIRE(fused.size() == 1);
  CHECK(fused[0].support == 4);
  // clash_depth 0 is the strict rule: the 5 mm are a clash.
  opt.clash_depth = 0.0;
  CHECK(crunch::tablesClash(sized(2.4, 2.9, 0.0, 0.81, 0.5, 0.05),
                            sized(3.2, 2.9, 0.0, 0.8, 0.5, 0.05), opt));
  opt.clash_depth = 0.6;
  REQUIRE_FALSE(opt.validate());
  CHECK(opt.validate().error().message.find("clash_depth") != std::string::npos);
}
