// main() of every crunch_add_test executable: what Catch2's default main (CATCH_CONFIG_MAIN)
// does, with Catch2's implementation in crunch_catch (catch_impl.cc) so that it is compiled once.
#include "support/catch_session.h"

int main(int argc, char* argv[]) { return crunch::testing::runCatchSession(argc, argv); }
