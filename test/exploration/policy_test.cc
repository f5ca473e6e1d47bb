// PolicyOptions::validate names the bad field.
#include "crunch/exploration/policy.h"

#include <catch2/catch.hpp>

using namespace crunch;
using namespace crunch::exploration;

TEST_CASE("PolicyOptions: out-of-range fields are named", "[exploration]") {
  PolicyOptions o;
  CHECK(o.validate());
  o.candidate_spacing = 0;
  REQUIRE_FALSE(o.validate());
  CHECK(o.validate().error().message.find("candidate_spacing") != std::string::npos);
  o = PolicyOptions{};
  o.candidate_headings = 65;
  CHECK_FALSE(o.validate());
  o = PolicyOptions{};
  o.samples = 0;
  CHECK_FALSE(o.validate());
}
