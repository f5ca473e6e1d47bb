// main() of every crunch_add_test executable: Catch2's own default main (CATCH_CONFIG_MAIN), with
// the implementation in crunch_catch (catch_impl.cc) so that it is compiled once.
#include <catch2/catch.hpp>

int main(int argc, char* argv[]) { return Catch::Session().run(argc, argv); }
