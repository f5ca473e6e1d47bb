// ExploreOptions::validate and explorePolicyByName: errors name the flag.
#include "crunch/exploration/exploration.h"

#include <catch2/catch.hpp>
#include <cmath>

using namespace crunch;
using namespace crunch::exploration;

TEST_CASE("ExploreOptions: budgets are checked and the flag named", "[exploration]") {
  ExploreOptions o;
  CHECK(o.validate());
  o.travel_budget_m = -1;
  REQUIRE_FALSE(o.validate());
  CHECK(o.validate().error().message.rfind("--travel-budget -1", 0) == 0);
  o.travel_budget_m = std::nan("");
  CHECK_FALSE(o.validate());
  o.travel_budget_m = 40;
  CHECK(o.validate());
  o.whisk_budget = -3;
  REQUIRE_FALSE(o.validate());
  CHECK(o.validate().error().message.rfind("--whisk-budget -3", 0) == 0);
  o.whisk_budget = 0;
  o.start = Pose2{std::nan(""), 0, 0};
  REQUIRE_FALSE(o.validate());
  CHECK(o.validate().error().message.rfind("--start", 0) == 0);
}

TEST_CASE("explorePolicyByName: the five names round-trip, others name --explore",
          "[exploration]") {
  for (const char* name : {"grid", "random", "frontier", "entropy", "infogain"}) {
    const auto kind = explorePolicyByName(name);
    REQUIRE(kind);
    CHECK(std::string(explorePolicyName(kind.value())) == name);
    CHECK(makePolicy(kind.value(), PolicyOptions{})->kind() == kind.value());
  }
  const auto bad = explorePolicyByName("spiral");
  REQUIRE_FALSE(bad);
  CHECK(bad.error().message.find("--explore") != std::string::npos);
  CHECK(bad.error().message.find("spiral") != std::string::npos);
}

TEST_CASE("exploreOptionsFromFlags: no policy is no exploration, budgets need one and are checked",
          "[exploration]") {
  using crunch::exploration::exploreOptionsFromFlags;
  const auto none = exploreOptionsFromFlags(std::nullopt, std::nullopt, std::nullopt);
  REQUIRE(none);
  CHECK_FALSE(none.value().has_value());
  const auto orphan = exploreOptionsFromFlags(std::nullopt, 10.0, std::nullopt);
  REQUIRE_FALSE(orphan);
  CHECK(orphan.error().message.find("--travel-budget") != std::string::npos);
  const auto unknown = exploreOptionsFromFlags(std::string("wander"), std::nullopt, std::nullopt);
  REQUIRE_FALSE(unknown);
  CHECK(unknown.error().message.find("--explore") != std::string::npos);
  const auto negative = exploreOptionsFromFlags(std::string("frontier"), std::nullopt, -2);
  REQUIRE_FALSE(negative);
  CHECK(negative.error().message.find("--whisk-budget") != std::string::npos);
  const auto ok = exploreOptionsFromFlags(std::string("infogain"), 12.5, 40);
  REQUIRE(ok);
  REQUIRE(ok.value().has_value());
  CHECK(ok.value()->policy == crunch::exploration::ExplorePolicyKind::kInfogain);
  CHECK(ok.value()->travel_budget_m == 12.5);
  CHECK(ok.value()->whisk_budget == 40);
}
