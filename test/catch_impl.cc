// Catch2's implementation (the session, reporters, matchers), compiled once for every test
// executable: crunch_test_main links it, and so does usb_bridge_hil_test, which has its own
// main(). Compiling it is about 33 s of CPU at -O3 (docs/BENCHMARKS.md, "CI time").
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include "support/catch_session.h"

int crunch::testing::runCatchSession(int argc, char* argv[]) {
  return Catch::Session().run(argc, argv);
}
