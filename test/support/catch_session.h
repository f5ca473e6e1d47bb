// Runs Catch2's session (what Catch2's own default main() does) from a main() outside the one TU
// that compiles Catch2's implementation (test/catch_impl.cc): Catch::Session is declared only
// where the implementation is compiled, and that TU is compiled once for every test executable.
#pragma once

namespace crunch::testing {

// Catch::Session().run(argc, argv): runs the selected test cases, returns the exit code.
int runCatchSession(int argc, char* argv[]);

}  // namespace crunch::testing
