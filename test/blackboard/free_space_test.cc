#include "crunch/blackboard/free_space.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include "crunch/core/rng.h"
#include "free_space_scan.h"

using namespace crunch;

TEST_CASE("FreeSpace: a ray through a leg's core counts, one grazing its outline does not",
          "[mapping]") {
  FreeSpaceGrid g({0, 0}, {1, 1}, 0.01);
  const Pose2 leg{0.5, 0.5, 0.3};
  g.addRay({{0.2, 0.5}, {0.8, 0.5}});  // straight through the centre
  CHECK(g.maxInSquare(leg, 0.05, 0.015) == 1);
  FreeSpaceGrid graze({0, 0}, {1, 1}, 0.01);
  // 1.5 cm above the centre: inside the 5 cm outline, outside the 2 cm core however turned.
  graze.addRay({{0.2, 0.515}, {0.8, 0.515}});
  CHECK(graze.maxInSquare(leg, 0.05, 0.015) == 0);
  CHECK(graze.maxInSquare(leg, 0.05, 0.0) >= 1);  // the unshrunk square does see it
}

TEST_CASE("FreeSpace: each ray counts once per cell, outside the grid is zero", "[mapping]") {
  FreeSpaceGrid g({0, 0}, {1, 1}, 0.01);
  for (int i = 0; i < 3; ++i) g.addRay({{0.1, 0.1}, {0.9, 0.9}});
  CHECK(g.count({0.5, 0.5}) == 3);
  CHECK(g.count({0.5, 0.2}) == 0);
  CHECK(g.count({-1.0, 0.5}) == 0);
  CHECK(g.count({0.5, 7.0}) == 0);
  CHECK(g.rays() == 3);
  g.addRay({{-5, -5}, {-4, -4}});  // wholly outside: harmless
  CHECK(g.rays() == 4);
}

TEST_CASE("FreeSpace: sweptNear sees a pass within its box only, and outside the room is known",
          "[mapping]") {
  FreeSpaceGrid g({0, 0}, {2, 2}, 0.01);
  CHECK_FALSE(g.sweptNear({1.0, 1.0}, 0.1));  // nothing swept yet
  g.addRay({{0.5, 1.0}, {0.9, 1.0}});         // a pass along y = 1 from x = 0.5 to 0.9
  CHECK(g.sweptNear({0.7, 1.0}, 0.0));
  CHECK(g.sweptNear({1.0, 1.0}, 0.12));        // 0.1 m past the ray's end
  CHECK_FALSE(g.sweptNear({1.0, 1.0}, 0.05));
  CHECK(g.sweptNear({0.7, 1.08}, 0.1));
  CHECK_FALSE(g.sweptNear({0.7, 1.2}, 0.1));
  CHECK_FALSE(g.sweptNear({0.7, 1.0}, -0.1));  // no box
  CHECK_FALSE(g.sweptNear({std::nan(""), 1.0}, 0.1));
  CHECK_FALSE(g.sweptNear({5.0, 5.0}, 0.1));  // off the grid, no room set: nothing known
  g.setRoom({0.2, 0.2}, {1.8, 1.8});
  CHECK(g.sweptNear({1.9, 1.0}, 0.01));  // outside the room: the room's bounds are evidence
  CHECK_FALSE(g.sweptNear({1.5, 1.5}, 0.01));
}

namespace {

// Adds `n` zero-length rays at the centre of cell (ix, iy): n passes through that cell alone.
void passCell(FreeSpaceGrid& g, int ix, int iy, int n) {
  const Vec2 c = g.origin() + Vec2{(ix + 0.5) * g.cell(), (iy + 0.5) * g.cell()};
  for (int i = 0; i < n; ++i) g.addRay({c, c});
}

// A random query: anywhere over the grid and a little beyond, any angle (the exact quarter
// turns among them), cores from a point up to 40 cells across.
struct Query {
  Pose2 pose;
  double side, margin;
};
Query randomQuery(Rng& rng, const FreeSpaceGrid& g) {
  const double w = g.cellsX() * g.cell(), h = g.cellsY() * g.cell();
  static constexpr double kTurns[] = {0.0, kPi / 2, kPi, -kPi / 2, kPi / 4, -3 * kPi / 4};
  Query q;
  q.pose.x = g.origin().x() + rng.uniform(-0.1 * w, 1.1 * w);
  q.pose.y = g.origin().y() + rng.uniform(-0.1 * h, 1.1 * h);
  q.pose.theta = rng.below(4) == 0 ? kTurns[rng.below(6)] : rng.uniform(-4 * kPi, 4 * kPi);
  q.side = rng.uniform(0.0, 40.0 * g.cell());
  q.margin = rng.below(5) == 0 ? 0.0 : rng.uniform(0.0, 0.5 * q.side);
  return q;
}

}  // namespace

TEST_CASE("FreeSpace: rays count the cells the reference walk counts, on cell edges too",
          "[mapping]") {
  // addRay reads each sample's cell without a division and falls back to the exact arithmetic
  // near a cell edge: random rays, rays along exact cell edges and corners (cell 0.25 and 0.5:
  // exact in binary), rays leaving and entering the grid and lying wholly outside must all give
  // the old walk's counts (test::walkRay), cell for cell.
  struct Layout {
    Vec2 lo, hi;
    double cell;
  };
  const Layout layouts[] = {{{0, 0}, {1, 1}, 0.01},
                            {{-0.37, 0.21}, {0.9, 1.05}, 0.013},
                            {{0, 0}, {4, 3}, 0.25},
                            {{-2.0, -1.0}, {2.0, 1.0}, 0.5},
                            {{150.0, 40.0}, {152.0, 41.0}, 0.01}};
  Rng rng(27);
  for (const Layout& l : layouts) {
    FreeSpaceGrid g(l.lo, l.hi, l.cell);
    std::vector<int> want(static_cast<size_t>(g.cellsX()) * static_cast<size_t>(g.cellsY()), 0);
    const Vec2 span = l.hi - l.lo;
    std::vector<FreeRay> rays;
    for (int r = 0; r < 400; ++r) {  // random, some starting or ending outside
      const Vec2 a =
          l.lo + Vec2{rng.uniform(-0.2, 1.2) * span.x(), rng.uniform(-0.2, 1.2) * span.y()};
      const double len = rng.uniform(0.0, 0.5 * span.x()), dir = rng.uniform(-kPi, kPi);
      rays.push_back({a, a + len * Vec2{std::cos(dir), std::sin(dir)}});
    }
    for (int k = -1; k <= g.cellsX() + 1; ++k) {  // along cell edges, through cell corners
      const double x = l.lo.x() + k * l.cell;
      rays.push_back({{x, l.lo.y() - l.cell}, {x, l.hi.y() + l.cell}});
      rays.push_back({{x, l.lo.y()}, {x + 3 * l.cell, l.lo.y() + 3 * l.cell}});
      rays.push_back({{l.lo.x(), l.lo.y() + k * l.cell}, {l.hi.x(), l.lo.y() + k * l.cell}});
    }
    rays.push_back({{l.lo.x() - 1.0, l.lo.y() - 1.0}, {l.lo.x() - 0.5, l.lo.y() - 0.2}});
    for (const FreeRay& r : rays) {
      g.addRay(r);
      test::walkRay(g, r, want);
    }
    int mismatches = 0, swept = 0;
    for (int iy = 0; iy < g.cellsY(); ++iy) {
      for (int ix = 0; ix < g.cellsX(); ++ix) {
        const int w = want[static_cast<size_t>(iy * g.cellsX() + ix)];
        mismatches += g.countAt(ix, iy) != w;
        swept += w > 0;
      }
    }
    CHECK(mismatches == 0);
    CHECK(swept > g.cellsX());  // the rays covered more than a row
  }
}

TEST_CASE("FreeSpace: the look-up equals the brute-force scan over random rays and cores",
          "[mapping]") {
  // Whisker-like rays (a few cm to a metre) pile up into counts of 0..~40; the cores land on
  // empty space, inside swept space and across its edges, which is where the look-up's bounds
  // disagree and it visits rows.
  struct Layout {
    Vec2 lo, hi;
    double cell;
  };
  const Layout layouts[] = {{{0, 0}, {1, 1}, 0.01}, {{-0.37, 0.21}, {0.9, 1.05}, 0.013},
                            {{2.0, -3.0}, {6.0, 1.0}, 0.05}};
  Rng rng(15);
  for (const Layout& l : layouts) {
    FreeSpaceGrid g(l.lo, l.hi, l.cell);
    const Vec2 span = l.hi - l.lo;
    int nonzero = 0, checked = 0;
    for (int batch = 0; batch < 12; ++batch) {
      for (int r = 0; r < 25; ++r) {
        const Vec2 a = l.lo + Vec2{rng.uniform() * span.x(), rng.uniform() * span.y()};
        const double len = rng.uniform(0.02, 0.6 * span.x()), dir = rng.uniform(-kPi, kPi);
        g.addRay({a, a + len * Vec2{std::cos(dir), std::sin(dir)}});
      }
      for (int k = 0; k < 1500; ++k) {
        const Query q = randomQuery(rng, g);
        const int want = test::scanMaxInSquare(g, q.pose, q.side, q.margin);
        const int got = g.maxInSquare(q.pose, q.side, q.margin);
        if (got != want) {
          FAIL_CHECK("pose " << q.pose.x << "," << q.pose.y << "," << q.pose.theta << " side "
                             << q.side << " margin " << q.margin << ": " << got << " vs scan "
                             << want);
        }
        nonzero += want > 0;
        ++checked;
      }
    }
    CHECK(checked == 12 * 1500);
    CHECK(nonzero > checked / 4);  // the test saw swept space, not only empty cores
  }
}

TEST_CASE("FreeSpace: cores whose outline runs through cell centres match the scan",
          "[mapping]") {
  // Every cell 0..4 passes at random, so neighbouring cells differ and the bounds rarely agree;
  // cores centred on cell centres and corners, square to the grid or at 45 degrees, with
  // half-sides of whole and half cells: their outlines pass exactly through rows of centres,
  // where only the scan's own arithmetic decides.
  FreeSpaceGrid g({0, 0}, {0.4, 0.4}, 0.01);
  Rng rng(7);
  for (int iy = 0; iy < g.cellsY(); ++iy)
    for (int ix = 0; ix < g.cellsX(); ++ix) passCell(g, ix, iy, static_cast<int>(rng.below(5)));
  int checked = 0;
  for (int k = 0; k < 4000; ++k) {
    const double cx = 0.005 * rng.below(80), cy = 0.005 * rng.below(80);
    const double theta = (kPi / 4) * (static_cast<int>(rng.below(9)) - 4);
    const double h = 0.005 * (1 + rng.below(10));
    const Pose2 pose{cx, cy, theta};
    const int want = test::scanMaxInSquare(g, pose, 2 * h, 0.0);
    const int got = g.maxInSquare(pose, 2 * h, 0.0);
    if (got != want) {
      FAIL_CHECK("pose " << cx << "," << cy << "," << theta << " half-side " << h << ": " << got
                         << " vs scan " << want);
    }
    ++checked;
  }
  CHECK(checked == 4000);
}

TEST_CASE("FreeSpace: counts saturate at 65535 and the look-up follows them", "[mapping]") {
  FreeSpaceGrid g({0, 0}, {0.1, 0.1}, 0.01);
  passCell(g, 3, 4, 65540);
  CHECK(g.countAt(3, 4) == 65535);
  CHECK(g.maxInSquare({0.035, 0.045, 0.2}, 0.05, 0.0) == 65535);
  CHECK(g.maxInSquare({0.085, 0.045, 0.2}, 0.05, 0.0) == 0);  // 5 cells away: outside
  CHECK(g.countAt(-1, 0) == 0);
  CHECK(g.countAt(0, 10) == 0);
}

TEST_CASE("FreeSpace: memory follows the rays, not the arena (issue 16)", "[mapping]") {
  // The largest arena a scene may have (200 m a side, 4e8 cells): no tile until a ray arrives.
  FreeSpaceGrid g({-100, -100}, {100, 100}, 0.01);
  CHECK(g.tileBytes() == 0);
  CHECK(g.maxInSquare({50, 50, 0.3}, 0.05, 0.0) == 0);
  // A 1 m ray crosses 100 cells: 2 or 3 tiles of 64 x 64 cells, with their -x/-y neighbours
  // where a window starting there reaches the ray.
  g.addRay({{10.0, 10.0}, {11.0, 10.3}});
  const size_t tile_bytes = 3 * 64 * 64 * sizeof(uint16_t);
  CHECK(g.tileBytes() >= 2 * tile_bytes);
  CHECK(g.tileBytes() <= 8 * tile_bytes);
  CHECK(g.maxInSquare({10.5, 10.15, 0.3}, 0.05, 0.0) == 1);
  CHECK(g.maxInSquare({-10.5, 10.15, 0.3}, 0.05, 0.0) == 0);
  // A ray across a tile corner: the windows in the neighbouring tiles see it too (cell
  // (6399, 6399) is the last of its tile; the window of side 4 at (6397, 6397) holds (6400, 6400)).
  FreeSpaceGrid h({0, 0}, {100, 100}, 0.01);
  passCell(h, 6400, 6400, 2);
  CHECK(h.maxInSquare({63.995, 63.995, 0.0}, 0.04, 0.0) == 2);
  CHECK(h.maxInSquare({63.995, 63.995, 0.0}, 0.04, 0.0) ==
        test::scanMaxInSquare(h, {63.995, 63.995, 0.0}, 0.04, 0.0));
  CHECK(h.maxInSquare({63.975, 63.975, 0.0}, 0.02, 0.0) == 0);
}

TEST_CASE("FreeSpace: the body's sweep adds its passes to every cell within the radius of the "
          "segment, nothing beyond, and the look-up follows it",
          "[mapping]") {
  FreeSpaceGrid g({0, 0}, {2, 1}, 0.01);
  const Vec2 a{0.5, 0.5}, b{1.3, 0.7};
  const double r = 0.165;
  g.addSweep(a, b, r, 2);
  CHECK(g.rays() == 1);
  const Vec2 d = b - a;
  int inside = 0, outside = 0;
  for (int iy = 0; iy < g.cellsY(); ++iy) {
    for (int ix = 0; ix < g.cellsX(); ++ix) {
      const Vec2 c = g.origin() + Vec2((ix + 0.5) * g.cell(), (iy + 0.5) * g.cell());
      const double t = std::clamp((c - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
      const double dist = (c - (a + t * d)).norm();
      if (dist <= r - 1e-9) {
        ++inside;
        if (g.countAt(ix, iy) != 2) FAIL_CHECK("cell " << ix << "," << iy << " inside: " << g.countAt(ix, iy));
      } else if (dist > r + 1e-9) {
        ++outside;
        if (g.countAt(ix, iy) != 0) FAIL_CHECK("cell " << ix << "," << iy << " outside: " << g.countAt(ix, iy));
      }
    }
  }
  // The capsule's area over a cell's: 2 r |ab| + pi r^2.
  const double cells = (2 * r * d.norm() + kPi * r * r) / (g.cell() * g.cell());
  CHECK(std::abs(inside - cells) < 0.02 * cells);
  CHECK(outside > 0);
  // A second, standing sweep (a == b) adds its passes to the disc only; the look-up agrees with
  // the scan on cores inside, across the edge and outside.
  g.addSweep(b, b, r, 1);
  CHECK(g.count(b) == 3);
  CHECK(g.count(a) == 2);
  CHECK(g.count({1.9, 0.1}) == 0);
  Rng rng(7);
  for (int k = 0; k < 3000; ++k) {
    const Pose2 pose{rng.uniform(0.2, 1.8), rng.uniform(0.1, 0.9), rng.uniform(-kPi, kPi)};
    const double side = rng.uniform(0.02, 0.08), margin = rng.uniform(0.0, 0.015);
    const int want = test::scanMaxInSquare(g, pose, side, margin);
    if (g.maxInSquare(pose, side, margin) != want) FAIL_CHECK("pose " << pose.x << "," << pose.y);
  }
  // Bad input sweeps nothing.
  g.addSweep({std::nan(""), 0.5}, b, r, 5);
  g.addSweep(a, b, -1.0, 5);
  g.addSweep(a, b, r, 0);
  CHECK(g.count(a) == 2);
  CHECK(g.rays() == 2);
}

TEST_CASE("FreeSpace: beyond the room's walls every core is swept, count() is not",
          "[mapping]") {
  FreeSpaceGrid g({-0.3, -0.3}, {2.3, 1.3}, 0.01);
  g.addRay({{0.2, 0.5}, {0.8, 0.5}});
  const long long rays = g.rays();
  const int inside = g.maxInSquare({0.5, 0.5, 0.2}, 0.06, 0.015);
  CHECK(inside == 1);
  CHECK(g.maxInSquare({2.15, 0.5, 0.0}, 0.04, 0.015) == 0);  // beyond x = 2 but no room yet
  g.setRoom({0, 0}, {2, 1});
  CHECK(g.rays() == rays + 1);
  CHECK(g.maxInSquare({0.5, 0.5, 0.2}, 0.06, 0.015) == inside);
  CHECK(g.maxInSquare({1.95, 0.95, 0.0}, 0.04, 0.015) == 0);  // inside, unswept
  CHECK(g.maxInSquare({2.15, 0.5, 0.0}, 0.04, 0.015) == 65535);  // beyond, inside the grid
  CHECK(g.maxInSquare({-0.01, 0.5, 0.0}, 0.04, 0.015) == 65535);
  CHECK(g.maxInSquare({5.0, 5.0, 0.0}, 0.04, 0.015) == 65535);  // beyond the grid too
  CHECK(g.count({2.15, 0.5}) == 0);
}

TEST_CASE("FreeSpace: with the windows capped, the look-up equals the scan up to the cap",
          "[mapping]") {
  // The blackboard reads min(maxInSquare(), free_pass_cap): the capped grid must give the same
  // for every square, through rays and body sweeps, while count() stays exact.
  Rng rng(23);
  for (const int cap : {0, 1, 2, 5}) {
    INFO("cap " << cap);
    FreeSpaceGrid g({0, 0}, {1, 1}, 0.01);
    g.setWindowCap(cap);
    int above = 0, checked = 0;
    for (int batch = 0; batch < 8; ++batch) {
      for (int r = 0; r < 25 * (1 + cap); ++r) {  // counts past the cap: more rays for more
        const Vec2 a{rng.uniform(), rng.uniform()};
        const double len = rng.uniform(0.02, 0.6), dir = rng.uniform(-kPi, kPi);
        g.addRay({a, a + len * Vec2{std::cos(dir), std::sin(dir)}});
      }
      const Vec2 c{rng.uniform(), rng.uniform()};
      g.addSweep(c, c + Vec2{rng.uniform(-0.2, 0.2), rng.uniform(-0.2, 0.2)}, 0.05, 3);
      for (int k = 0; k < 1000; ++k) {
        const Query q = randomQuery(rng, g);
        const int want = test::scanMaxInSquare(g, q.pose, q.side, q.margin);
        const int got = g.maxInSquare(q.pose, q.side, q.margin);
        if (std::min(got, cap) != std::min(want, cap)) {
          FAIL_CHECK("pose " << q.pose.x << "," << q.pose.y << "," << q.pose.theta << " side "
                             << q.side << ": " << got << " vs scan " << want);
        }
        above += want > cap;
        ++checked;
      }
    }
    CHECK(above > checked / 10);  // counts well past the cap were read
  }
}
