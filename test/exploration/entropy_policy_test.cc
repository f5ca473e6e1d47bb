// Tests of `--explore entropy`, the paper's §2.9 (crunch/exploration/entropy_policy.h): the
// foveal rasterisation, eq. 34's Laplace-smoothed conditionals and eq. 36's dH on a hand-made
// grid, and the §3.4 failure this reproduces: a cell no draw puts a leg in outscores the leg
// that would settle rival tables, because its conditional rests on no draws.
#include "crunch/exploration/entropy_policy.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

using namespace crunch;
using namespace crunch::exploration;

namespace {
double h2(double p) { return -(p * std::log2(p) + (1 - p) * std::log2(1 - p)); }
}  // namespace

TEST_CASE("Entropy: eq. 34-36 on a hand-made grid", "[exploration][entropy]") {
  FovealGrid g;
  g.n = 2;
  g.draws = 4;
  // Table bits per cell (bit s = draw s), leg bits: a leg in cell 0 in draw 0 only.
  g.table = {0b0011, 0b1100, 0b0000, 0b1111};
  g.leg = {0b0001, 0b0000, 0b0000, 0b0000};
  // Action cell 0: with the leg, draws {0} (n = 1); without, {1, 2, 3} (n = 3).
  // P(T | L) = (count + 1) / (1 + 2), P(T | not L) = (count + 1) / (3 + 2):
  //   cell 0: 2/3 vs 2/5; cell 1: 1/3 vs 3/5; cell 2: 1/3 vs 1/5; cell 3: 2/3 vs 4/5.
  const double expected = (h2(2.0 / 3) - h2(0.4)) + (h2(1.0 / 3) - h2(0.6)) +
                          (h2(1.0 / 3) - h2(0.2)) + (h2(2.0 / 3) - h2(0.8));
  CHECK(entropyDelta(g, 0, 0) == Approx(expected));
  // Action cell 1: no draw has a leg there: P(T | L) = 1/2 everywhere (the flat prior alone),
  // P(T | not L) from all four draws: (2+1)/6, (2+1)/6, 1/6, 5/6.
  CHECK(entropyDelta(g, 1, 0) ==
        Approx(4.0 - (h2(0.5) + h2(0.5) + h2(1.0 / 6) + h2(5.0 / 6))));
}

TEST_CASE("Entropy: rasterised draws, and the paper's §3.4 failure reproduced",
          "[exploration][entropy]") {
  // Fig. 7's rival tables, half the draws each (as the infogain test).
  MapTable north, south;
  north.pose = {1.375, 1.725, 0.0};
  south.pose = {1.375, 1.275, 0.0};
  std::vector<MapSample> draws;
  for (int i = 0; i < 16; ++i) draws.push_back({{i % 2 ? north : south}, {}, {}});
  const FovealGrid g = rasteriseFovea(draws, {1.4, 1.5}, EntropyOptions{});
  REQUIRE(g.n == 32);
  REQUIRE(g.draws == 16);
  auto cellOf = [&](const Vec2& p, int& ix, int& iy) {
    ix = static_cast<int>(std::floor((p.x() - g.lo.x()) / g.cell));
    iy = static_cast<int>(std::floor((p.y() - g.lo.y()) / g.cell));
  };
  int ix, iy;
  cellOf({1.0, 1.5}, ix, iy);  // L1: shared, every draw
  CHECK(g.leg[static_cast<size_t>(iy * g.n + ix)] == 0xFFFF);
  cellOf({1.0, 1.95}, ix, iy);  // T1's own leg: the odd draws
  CHECK(g.leg[static_cast<size_t>(iy * g.n + ix)] == 0xAAAA);
  const double disputed = entropyDelta(g, ix, iy);
  cellOf({1.4, 1.5}, ix, iy);  // under both tops
  CHECK(g.table[static_cast<size_t>(iy * g.n + ix)] == 0xFFFF);
  // An empty cell far from both tables: no draw has a leg there, so its "with a leg"
  // conditional is the flat prior, H = 1 bit in every cell, and dH is the whole background's.
  cellOf({0.7, 0.8}, ix, iy);
  const double empty = entropyDelta(g, ix, iy);
  // Eq. 36 is a difference of the two conditionals, not an expected reduction: with the draws
  // split 8:8 the two conditionals mirror each other (9/10 vs 1/10) and dH is exactly 0, for
  // the very leg that would settle the rivals.
  CHECK(disputed == Approx(0.0).margin(1e-9));
  CHECK(empty > 100.0);
  CHECK(empty > disputed);
}
