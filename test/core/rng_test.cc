#include "crunch/core/rng.h"

#include <catch2/catch.hpp>
#include <set>

using namespace crunch;

TEST_CASE("Rng: jump() gives the published xoshiro256 state", "[core]") {
  // State (0, 0, 0, 1) jumped once, as the reference C code's jump() gives it (the same
  // polynomial serves xoshiro256** and ++; test vectors of github.com/DSCF-1224/xoshiro-fortran,
  // test/README.md).
  Rng r(std::array<uint64_t, 4>{0, 0, 0, 1});
  r.jump();
  const std::array<uint64_t, 4> want = {0x934D05E8B2076310ull, 0xEABDD0BF76A1BE51ull,
                                        0x75DD6A992ACCB1E8ull, 0xC660C602A7330187ull};
  CHECK(r.state() == want);
}

TEST_CASE("Rng: a jump commutes with a draw (it is a power of the generator's step)", "[core]") {
  Rng a(42), b(42);
  a.next();
  a.jump();
  b.jump();
  b.next();
  CHECK(a.state() == b.state());
}

TEST_CASE("Rng: streams split by jump() differ and repeat for the same seed", "[core]") {
  std::set<uint64_t> firsts;
  Rng stream(7);
  for (int i = 0; i < 16; ++i) {
    Rng copy = stream;
    firsts.insert(copy.next());
    stream.jump();
  }
  CHECK(firsts.size() == 16);
  Rng again(7);
  for (int i = 0; i < 16; ++i) again.jump();
  CHECK(again.state() == stream.state());
}

TEST_CASE("drawLogWeighted: draws each index in proportion to exp of its log weight", "[core]") {
  // Log weights far from 0 (the largest is subtracted first) and one impossible index.
  std::array<double, 4> base = {-1000.0 + std::log(1.0), -1000.0 + std::log(2.0),
                                -std::numeric_limits<double>::infinity(),
                                -1000.0 + std::log(5.0)};
  crunch::Rng rng(21);
  std::array<int, 4> count{};
  const int n = 80000;
  for (int i = 0; i < n; ++i) {
    std::array<double, 4> w = base;
    ++count[crunch::drawLogWeighted(w, rng)];
    CHECK(w[3] == 1.0);  // overwritten: exp(log_w - max)
  }
  CHECK(count[2] == 0);
  // Expected n/8, 2n/8, 5n/8; sd at most ~140: 6 sd.
  CHECK(std::abs(count[0] - n / 8) < 840);
  CHECK(std::abs(count[1] - 2 * n / 8) < 840);
  CHECK(std::abs(count[3] - 5 * n / 8) < 840);
  std::array<double, 1> one = {3.0};
  CHECK(crunch::drawLogWeighted(one, rng) == 0);
}
