// Detailed balance of the reversible-jump sampler (Acceptance::kReversibleJump) on small models:
// the chain at beta = 1 must sample the target exp(J) / rj_cell^n (sampler.cc, "Reversible-jump
// moves"), so the frequencies of discrete statistics it visits must match the target's
// probabilities, computed here independently of the chain by importance sampling of the
// target's integrals (the normalising constant of each number of hypotheses). The tolerance is
// the Monte Carlo error of both: the chain's by batch means, the reference's by its sample
// variance, at 4.5 standard errors.
//
// How we know the test can fail: with the birth/death proposal ratio dropped (decideRj called
// with 0 instead of log(|B_s| / (n rj_cell)) in rjLegBirthDeath) the leg-count test fails
// (the chain piles up four and more legs: P(1 leg) chain 0.000 vs reference 0.628); with the
// table birth's -log q(T | L) dropped the table test fails (P(table) chain 0.9995 vs 0.903). Each was checked by editing sampler.cc and running this
// test (docs/BLACKBOARD.md, "Reversible-jump acceptance"). Not covered here: the parent change's
// ratio log(w_old / W_rev) - log(w_new / W_fwd) (it is 0 unless a leg has two candidate tables,
// which a model this small does not reach) and the table jitter (symmetric).
//
// (Rechecked 2026-11-25 on the full chains: the leg birth's ratio alone set to 0 fails the
// leg-count test at 124 standard errors, P(1 leg) chain 0.957 vs 0.628; log q(T | L) dropped
// from both the parent-table birth's and death's ratios fails the table test at 15, P(table)
// 0.9995 vs 0.889. Dropped from the birth's ratio alone it is NOT caught: 0.928 vs 0.889, 3.5
// standard errors.)
//
// The rooms model's test (tables of any size) was checked the same way: a drift of 3 mm in
// resizeTable's width step fails both its statistics (P(table) 0.998 vs 0.986, P(width above the
// prior's middle) 0.94 vs 0.32); log q(T | L) dropped from the parent table's death fails
// P(table) at 25 standard errors (0.9948 vs 0.9861); the table's leg side's density about the
// leg's (logSideNearDensity) taken against Lebesgue instead of the prior's uniform probability
// (0.807 vs 0.986). Not caught there: the same term dropped from
// the birth alone (every birth of that small model is accepted either way), and a size drawn
// from another density than the prior's (the shorter side uniform: P(wide) 0.315 vs 0.322).
//
// Under AddressSanitizer (support/sanitizers.h) the leg-count test draws a quarter of the samples
// (chain, burn-in and reference): 158 s of CPU under ASan at -O0, 109 s with the blackboard at
// -O1 (the asan preset), 25 s with the quarter as well. It walks the same moves (~21,000 accepted
// births and deaths, ~43,000 jitters) and asserts the same agreement at 4.5 standard errors,
// which are about twice as wide: the leg birth's ratio set to 0 still fails it (60 standard
// errors, checked on a Release build with the quarter), a 10 % error in that ratio does not (4.0
// standard errors; the full chain: 6.3). The Release build in the same CI run keeps the full
// samples and so that power; the sanitizers' run is for memory errors and undefined behaviour
// along these moves. The table test runs in full everywhere (11 s under ASan at -O1).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <vector>

#include "crunch/blackboard/blackboard.h"
#include "crunch/blackboard/sampler.h"
#include "support/sanitizers.h"
#include "test_builders.h"

using namespace crunch;
using crunch::testing::asanScaled;
using crunch::testing::LegOf;
using crunch::testing::MakeShapelet;

namespace {

// The birth box of an oriented shapelet, restated from SamplerOptions' documentation: along
// the face within half a leg side plus the margin, half a leg side behind it give or take the
// margin, turned within rj_box_theta of the face.
struct Box {
  Vec2 origin, along, in;
  double u, v0, v1, phi, theta, volume;
  bool contains(const Pose2& p) const {
    const Vec2 d = p.position() - origin;
    const double a = d.dot(along), v = d.dot(in);
    return std::abs(a) <= u && v >= v0 && v <= v1 &&
           std::abs(wrapPeriod(p.theta - phi, kPi / 2)) <= theta;
  }
  Pose2 sample(Rng& rng) const {
    const Vec2 c = origin + rng.uniform(-u, u) * along + rng.uniform(v0, v1) * in;
    return {c.x(), c.y(), wrapPeriod(phi + rng.uniform(-theta, theta), kPi / 2)};
  }
};

Box boxOf(const Shapelet& s, const ModelParams& p, const SamplerOptions& o) {
  Box b;
  const double half = 0.5 * p.leg_side, m = o.rj_box_margin;
  b.origin = {s.x, s.y};
  b.along = {std::cos(s.phi), std::sin(s.phi)};
  Vec2 n{-std::sin(s.phi), std::cos(s.phi)};
  if (n.dot(Vec2{s.ox - s.x, s.oy - s.y}) > 0) n = -n;
  b.in = n;
  b.u = half + m;
  b.v0 = half - m;
  b.v1 = half + m;
  b.phi = s.phi;
  b.theta = o.rj_box_theta;
  b.volume = 2 * b.u * (b.v1 - b.v0) * 2 * b.theta;
  return b;
}

// Frequencies of a statistic along a chain with their batch-means standard error.
struct Freq {
  std::vector<double> x;
  double mean() const {
    double s = 0;
    for (double v : x) s += v;
    return s / static_cast<double>(x.size());
  }
  double stderror(int batches = 50) const {
    const size_t per = x.size() / static_cast<size_t>(batches);
    const double m = mean();
    double ss = 0;
    for (int b = 0; b < batches; ++b) {
      double s = 0;
      for (size_t i = 0; i < per; ++i) s += x[static_cast<size_t>(b) * per + i];
      ss += std::pow(s / static_cast<double>(per) - m, 2);
    }
    return std::sqrt(ss / (batches - 1) / batches);
  }
};

// A reference probability from importance-sampled integrals: Z_k estimated by the mean of
// weights; p_k = Z_k / sum Z; its standard error by the delta method over independent Z's.
struct Reference {
  std::vector<double> z, var;  // estimate and variance of the estimate per class
  double p(size_t k) const {
    double t = 0;
    for (double v : z) t += v;
    return z[k] / t;
  }
  double se(size_t k) const {
    double t = 0;
    for (double v : z) t += v;
    // dp_k/dz_j = (delta_kj t - z_k) / t^2
    double s = 0;
    for (size_t j = 0; j < z.size(); ++j) {
      const double d = ((j == k ? t : 0.0) - z[k]) / (t * t);
      s += d * d * var[j];
    }
    return std::sqrt(s);
  }
};

// A reference whose first class is the empty state: Z_0 = 1 exactly.
Reference fromEmpty() {
  Reference r;
  r.z.push_back(1.0);
  r.var.push_back(0.0);
  return r;
}

void addEstimate(Reference& r, const std::vector<double>& w) {
  double s = 0, ss = 0;
  for (double v : w) {
    s += v;
    ss += v * v;
  }
  const double n = static_cast<double>(w.size()), m = s / n;
  r.z.push_back(m);
  r.var.push_back(std::max(0.0, ss / n - m * m) / n);
}

// The chain's frequency agrees with the reference within 4.5 combined standard errors.
#define CHECK_AGREES(chain, chain_se, ref, ref_se)                                          \
  do {                                                                                      \
    INFO("chain " << (chain) << " +- " << (chain_se) << ", reference " << (ref) << " +- " \
                  << (ref_se));                                                             \
    CHECK(std::abs((chain) - (ref)) <= 4.5 * std::hypot((chain_se), (ref_se)));            \
  } while (0)

SamplerOptions rjOptions(ReversibleMoves moves) {
  SamplerOptions o;
  o.acceptance = Acceptance::kReversibleJump;
  o.rj_moves = moves;
  return o;
}
}  // namespace

TEST_CASE("Reversible jump: leg births, deaths and moves sample the number of legs exactly",
          "[blackboard]") {
  // Two shapelets on perpendicular faces of one leg: their boxes overlap around the leg, so the
  // death's choice among the orphans of a box and the union of boxes are both exercised.
  ModelParams p;
  const Pose2 leg{0.3, 0.2, 0.1};
  const Shapelet a = MakeShapelet(leg, p.leg_side, 0), b = MakeShapelet(leg, p.leg_side, 1);
  const SamplerOptions opt = rjOptions({1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0});
  const Box boxes[2] = {boxOf(a, p, opt), boxOf(b, p, opt)};

  // Reference: Z_n = (1/n!) integral over the union of boxes^n of exp(J - J_0) / cell^n, by
  // importance sampling with legs drawn from the even mixture of the two boxes.
  Blackboard ref(p, 2, 64);
  ref.pushShapelet(a);
  ref.pushShapelet(b);
  const double j0 = ref.totalEnergy();
  Rng rng(5);
  Reference r = fromEmpty();
  const int kSamples = asanScaled(40000, 4);
  for (int n = 1; n <= 5; ++n) {
    std::vector<double> w;
    w.reserve(kSamples);
    double fact = 1;
    for (int i = 2; i <= n; ++i) fact *= i;
    for (int s = 0; s < kSamples; ++s) {
      double log_w = 0;
      int32_t ids[5];
      for (int i = 0; i < n; ++i) {
        const Pose2 l = boxes[rng.below(2)].sample(rng);
        double q = 0;
        for (const Box& bx : boxes) q += bx.contains(l) ? 0.5 / bx.volume : 0.0;
        log_w -= std::log(q) + std::log(opt.rj_cell);
        ids[i] = ref.addLeg(l, kNone);
      }
      w.push_back(std::exp(ref.totalEnergy() - j0 + log_w) / fact);
      for (int i = 0; i < n; ++i) {
        ref.killLeg(ids[i]);
        ref.releaseLeg(ids[i]);
      }
    }
    addEstimate(r, w);
  }
  // Six or more legs must be negligible for the truncation to be exact enough.
  REQUIRE(r.p(5) < 0.002);

  Blackboard bb(p, 2, 64);
  bb.pushShapelet(a);
  bb.pushShapelet(b);
  Rng chain_rng(17);
  Sampler sampler(bb, opt, chain_rng);
  for (int i = 0; i < asanScaled(2000, 4); ++i) sampler.sweep(1.0);  // burn-in
  Freq n[4];
  for (int i = 0; i < asanScaled(100000, 4); ++i) {
    sampler.sweep(1.0);
    for (int k = 0; k < 4; ++k) n[k].x.push_back(bb.liveLegs() == k);
  }
  for (size_t k = 0; k < 4; ++k) {
    INFO(k << " legs");
    CHECK_AGREES(n[k].mean(), n[k].stderror(), r.p(k), r.se(k));
  }
}

TEST_CASE("Reversible jump: table births and deaths sample P(table) exactly", "[blackboard]") {
  // Either table move alone: through the leg (its sole parent), or the smart birth with adoption
  // and the death of any table (with one leg its weights are even and it adopts that leg).
  const bool smart = GENERATE(false, true);
  INFO((smart ? "smart table birth/death" : "a leg's parent-table birth/death"));
  ModelParams p;
  const Pose2 leg{0.3, 0.2, 0.1};
  const Shapelet a = MakeShapelet(leg, p.leg_side, 0);
  const SamplerOptions opt = smart ? rjOptions({0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0})
                                   : rjOptions({0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0});

  // Reference: Z_1 = integral of exp(J(L, T) - J(L)) / cell over the table's pose, by importance
  // sampling from 8 placements with Gaussian steps (a restatement of the birth's Q, whose
  // density is computed here from scratch).
  Blackboard ref(p, 1, 64);
  ref.pushShapelet(a);
  const int32_t l = ref.addLeg(leg, kNone);
  const double j0 = ref.totalEnergy();
  Rng rng(9);
  const double sr = opt.jitter_sigma_r, st = opt.jitter_sigma_theta;
  std::vector<Pose2> centres;
  for (int k = 0; k < 8; ++k) {
    const double th = wrapPeriod(leg.theta + (k / 4) * (kPi / 2), kPi);
    const Vec2 off = Pose2{0, 0, th}.toWorld(p.cornerOffset(k % 4));
    centres.push_back({leg.x - off.x(), leg.y - off.y(), th});
  }
  std::vector<double> w;
  for (int s = 0; s < 40000; ++s) {
    const Pose2& c = centres[rng.below(8)];
    const Pose2 t{c.x + rng.normal(0, sr), c.y + rng.normal(0, sr),
                  wrapPeriod(c.theta + rng.normal(0, st), kPi)};
    double q = 0;
    for (const Pose2& m : centres) {
      const double dth = std::remainder(t.theta - m.theta, kPi);  // nearest winding (st << pi)
      q += (1.0 / 8) * std::exp(-0.5 * (std::pow(t.x - m.x, 2) + std::pow(t.y - m.y, 2)) / (sr * sr)) /
           (2 * kPi * sr * sr) * std::exp(-0.5 * dth * dth / (st * st)) / (std::sqrt(2 * kPi) * st);
    }
    // Both moves make (and unmake) only tables with the leg within the link radius of a corner:
    // the target they sample is restricted to those. (Beyond, a table's weight does not vanish:
    // its child falls back on c_L, eq. 17, so the unrestricted integral would not converge.)
    bool near = false;
    for (int corner = 0; corner < 4; ++corner)
      near |= (t.toWorld(p.cornerOffset(corner)) - leg.position()).norm() <= p.cornerLinkRadius();
    if (!near) {
      w.push_back(0.0);
      continue;
    }
    const int32_t id = ref.addTable(t);
    ref.setParent(l, id);
    w.push_back(std::exp(ref.totalEnergy() - j0) / (q * opt.rj_cell));
    ref.setParent(l, kNone);
    ref.killTable(id);
    ref.releaseTable(id);
  }
  Reference r = fromEmpty();
  addEstimate(r, w);

  Blackboard bb(p, 1, 64);
  bb.pushShapelet(a);
  bb.addLeg(leg, kNone);
  Rng chain_rng(smart ? 29 : 23);
  Sampler sampler(bb, opt, chain_rng);
  Freq has;
  for (int i = 0; i < 200000; ++i) {
    sampler.sweep(1.0);
    has.x.push_back(bb.liveTables() == 1);
  }
  CHECK(bb.liveLegs() == 1);
  CHECK_AGREES(has.mean(), has.stderror(), r.p(1), r.se(1));
}

namespace {
// Shapelets every `step` metres along the face from a to b, sensed from its left (0.1 m off).
std::vector<Shapelet> faceShapelets(const Vec2& a, const Vec2& b, double step) {
  std::vector<Shapelet> out;
  const double len = (b - a).norm();
  const Vec2 d = (b - a) / len, n{-d.y(), d.x()};
  for (double t = 0; t <= len + 1e-9; t += step) {
    const Vec2 q = a + t * d;
    Shapelet s;
    s.x = q.x();
    s.y = q.y();
    s.phi = wrapPeriod(std::atan2(d.y(), d.x()), kPi);
    s.ox = q.x() + 0.1 * n.x();
    s.oy = q.y() + 0.1 * n.y();
    out.push_back(s);
  }
  return out;
}
}  // namespace

TEST_CASE("Reversible jump: wall births, deaths and steps sample P(wall) exactly", "[blackboard]") {
  // Seven contacts along one face (x 0.3..0.9 at y = 0.4, sensed from +y), the walls model,
  // only the wall kernels: birth around the contacts' fitted segment or death, and the
  // symmetric steps (jitterWall, extendWall). c_W is made small so that no wall and one wall
  // are both likely at beta = 1 (8e-12: the lone wall's two free ends cost
  // 2 log(p_wall_end_free / (1 - p_wall_end_free)) = -2.77 nats, which c_W makes up).
  ModelParams p;
  p.objects = ObjectModel::kWalls;
  p.c_W = 8e-12;
  const Vec2 a0{0.3, 0.4}, b0{0.9, 0.4};
  const std::vector<Shapelet> contacts = faceShapelets(a0, b0, 0.1);
  const SamplerOptions opt = rjOptions({0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0});

  // Reference: Z_1 = integral of exp(J(W) - J_0) / rj_wall_cell over walls with both ends in
  // rectangles about a0 and b0, 4 m either way along the face and 0.3 m across (the region the
  // chain keeps to: checked below; at beta = 1 an end wanders beyond the last contact with the
  // wall's cost per metre, exp(-2 m^-1 x), so 4 m leaves e^-8), free side +y (the contacts'
  // side: a wall facing away explains none and the chain never turns one over), no shorter
  // than wall_min_length. Importance sampling from a mixture: 0.95 ends about a0 and b0 (along
  // from an even mixture of normals of 0.1 m and 0.6 m, across 2 cm), 0.05 ends uniform in the
  // rectangles.
  Blackboard ref(p, 16, 64);
  for (const Shapelet& s : contacts) ref.pushShapelet(s);
  const double j0 = ref.totalEnergy();
  const double along = 4.0, across = 0.3, s_n = 0.1, s_w = 0.6, s_ac = 0.02;
  const auto inRegion = [&](const Vec2& a, const Vec2& b) {
    return std::abs(a.x() - a0.x()) < along && std::abs(a.y() - a0.y()) < across &&
           std::abs(b.x() - b0.x()) < along && std::abs(b.y() - b0.y()) < across;
  };
  const auto normal = [](double x, double s) {
    return std::exp(-0.5 * x * x / (s * s)) / (std::sqrt(2 * kPi) * s);
  };
  const auto endDensity = [&](const Vec2& at, const Vec2& mean) {
    const Vec2 d = at - mean;  // along x, across y
    return 0.5 * (normal(d.x(), s_n) + normal(d.x(), s_w)) * normal(d.y(), s_ac);
  };
  const auto drawEnd = [&](Rng& g, const Vec2& mean) {
    const double s = g.uniform() < 0.5 ? s_n : s_w;
    return Vec2(mean + Vec2{g.normal(0, s), g.normal(0, s_ac)});
  };
  Rng rng(31);
  std::vector<double> w;
  const int kSamples = asanScaled(400000, 4);
  w.reserve(kSamples);
  for (int i = 0; i < kSamples; ++i) {
    const bool near = rng.uniform() < 0.95;
    const auto uniformEnd = [&](const Vec2& mean) {
      return Vec2(mean + Vec2{rng.uniform(-along, along), rng.uniform(-across, across)});
    };
    const Vec2 a = near ? drawEnd(rng, a0) : uniformEnd(a0);
    const Vec2 b = near ? drawEnd(rng, b0) : uniformEnd(b0);
    if (!inRegion(a, b) || (b - a).x() <= 0.0 || (b - a).norm() < p.wall_min_length) {
      w.push_back(0.0);
      continue;
    }
    const double q = 0.95 * endDensity(a, a0) * endDensity(b, b0) +
                     0.05 / std::pow(4 * along * across, 2);
    const int32_t id = ref.addWall(a, b);
    w.push_back(std::exp(ref.totalEnergy() - j0) / (q * opt.rj_wall_cell));
    ref.killWall(id);
    ref.releaseWall(id);
  }
  Reference r = fromEmpty();
  addEstimate(r, w);
  INFO("reference P(1 wall) " << r.p(1) << " +- " << r.se(1));
  REQUIRE(r.p(1) > 0.1);  // both states likely: the test has power
  REQUIRE(r.p(1) < 0.9);

  Blackboard bb(p, 16, 64);
  for (const Shapelet& s : contacts) bb.pushShapelet(s);
  Rng chain_rng(37);
  Sampler sampler(bb, opt, chain_rng);
  for (int i = 0; i < 2000; ++i) sampler.sweep(1.0);  // burn-in
  Freq one, two, outside;
  for (int i = 0; i < asanScaled(100000, 4); ++i) {
    sampler.sweep(1.0);
    one.x.push_back(bb.liveWalls() == 1);
    two.x.push_back(bb.liveWalls() >= 2);
    bool out = false;
    for (int32_t id = 0; id < bb.wallExtent(); ++id)
      if (bb.wall(id).alive && !inRegion(bb.wall(id).a, bb.wall(id).b)) out = true;
    outside.x.push_back(out);
  }
  // Two walls (pieces of the face that do not share space, each paying c_W) are negligible,
  // and the chain keeps to the reference's region.
  CHECK(two.mean() < 0.002);
  CHECK(outside.mean() < 0.002);
  CHECK(sampler.stats().proposals > 100000);
  CHECK_AGREES(one.mean(), one.stderror(), r.p(1), r.se(1));
}

TEST_CASE("Reversible jump: whole-table births and deaths sample the table's legs exactly",
          "[blackboard]") {
  // One shapelet off the outward face of each of two adjacent legs of a table; only the
  // whole-table kernel (rjTableGroup): a table is born with a leg in a shapelet's box and a leg
  // or none at each other corner, or dies with all its legs. The states: nothing, a table with
  // one leg, a table with two (one in each box: every leg stands in a box).
  ModelParams p;
  // A rarer table than the default (c_T 0.4): each table born brings its own reference-measure
  // volume, so at beta = 1 the default prior makes a second and third table likely, states the
  // reference below does not count; with this c_T two tables are negligible (checked).
  p.c_T = 0.001;
  // A leg far from its table's corner falls back on c_L (eq. 17): with the default that floor
  // gives a table turned about its leg weight at any angle, which neither the move (nor the
  // reference) explores in a test's time; the known limit (docs/BLACKBOARD.md).
  p.c_L = 1e-6;
  const Pose2 table{0.6, 0.5, 0.2};
  const Shapelet sa = MakeShapelet(LegOf(table, p, 0), p.leg_side, 0);
  const Shapelet sb = MakeShapelet(LegOf(table, p, 1), p.leg_side, 2);
  // The move's Gaussian steps as wide as the target's spread of a table about its leg (sigma_r_leg,
  // sigma_theta_leg), so that births reach every part of it and the chain mixes in a test's time.
  SamplerOptions opt = rjOptions({0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0});
  opt.rj_steps_per_shapelet = 20;
  opt.jitter_sigma_r = 0.02;
  opt.jitter_sigma_theta = 0.1;
  const Box boxes[2] = {boxOf(sa, p, opt), boxOf(sb, p, opt)};
  // The reference's own steps, wider than the move's (jitter_sigma_r, jitter_sigma_theta) so
  // that its weights have no heavy tail where the target is wider than the move's proposal.
  const double sr = 0.02, st = 0.15;

  // Reference, by importance sampling: a leg from the even mixture of the two boxes, a table
  // at one of its 8 placements with a Gaussian step (as the table test above, wider) and, for two legs, a second leg at one of the three other corners (uniformly) with a
  // Gaussian step. The weight divides by the density of the unordered configuration (summed
  // over which leg came first), so Z_2 carries the 1/2! of two exchangeable legs. Both
  // integrals are restricted as the move is: a first leg within cornerLinkRadius of a corner,
  // and every leg in a box.
  const auto qBox = [&](const Pose2& l) {
    double q = 0;
    for (const Box& bx : boxes) q += bx.contains(l) ? 0.5 / bx.volume : 0.0;
    return q;
  };
  // A table for a leg: one of the 8 corner placements (k), its axis from the placement's
  // (0.7: a normal of st about it) or uniform (0.3: the target keeps some weight for any turn
  // about the corner, where a turned table's leg falls back on c_L), its centre such that the
  // placement's corner, turned with it, meets the leg, give or take a normal step of sr.
  constexpr double kNarrow = 0.7;
  const auto placementAxis = [&](const Pose2& leg, int k) {
    return wrapPeriod(leg.theta + (k / 4) * (kPi / 2), kPi);
  };
  const auto centreFor = [&](const Pose2& leg, int k, double theta) {
    const Vec2 off = Pose2{0, 0, theta}.toWorld(p.cornerOffset(k % 4));
    return Vec2(leg.position() - off);
  };
  const auto drawTable = [&](Rng& g, const Pose2& leg) {
    const int k = static_cast<int>(g.below(8));
    const double th = g.uniform() < kNarrow ? wrapPeriod(placementAxis(leg, k) + g.normal(0, st), kPi)
                                            : g.uniform(-kPi / 2, kPi / 2);
    const Vec2 c = centreFor(leg, k, th);
    return Pose2{c.x() + g.normal(0, sr), c.y() + g.normal(0, sr), th};
  };
  const auto qPlace = [&](const Pose2& t, const Pose2& leg) {
    double q = 0;
    for (int k = 0; k < 8; ++k) {
      const double dth = std::remainder(t.theta - placementAxis(leg, k), kPi);
      const double q_th = kNarrow * std::exp(-0.5 * dth * dth / (st * st)) / (std::sqrt(2 * kPi) * st) +
                          (1 - kNarrow) / kPi;
      const Vec2 d = t.position() - centreFor(leg, k, t.theta);
      q += (1.0 / 8) * q_th * std::exp(-0.5 * d.squaredNorm() / (sr * sr)) / (2 * kPi * sr * sr);
    }
    return q;
  };
  const auto nearest = [&](const Pose2& t, const Vec2& at) {
    int best = 0;
    for (int c = 1; c < 4; ++c)
      if ((t.toWorld(p.cornerOffset(c)) - at).norm() < (t.toWorld(p.cornerOffset(best)) - at).norm())
        best = c;
    return best;
  };
  const auto atCorner = [&](const Pose2& t, const Vec2& at) {
    return (t.toWorld(p.cornerOffset(nearest(t, at))) - at).norm() <= p.cornerLinkRadius();
  };
  const auto qCorner = [&](const Pose2& t, int c, const Pose2& leg) {
    const Vec2 d = leg.position() - t.toWorld(p.cornerOffset(c));
    const double dth = std::remainder(leg.theta - t.theta, kPi / 2);
    return std::exp(-0.5 * d.squaredNorm() / (sr * sr)) / (2 * kPi * sr * sr) *
           std::exp(-0.5 * dth * dth / (st * st)) / (std::sqrt(2 * kPi) * st);
  };
  const auto qOther = [&](const Pose2& t, const Pose2& first, const Pose2& other) {
    double q = 0;
    for (int c = 0; c < 4; ++c)
      if (c != nearest(t, first.position())) q += qCorner(t, c, other) / 3;
    return q;
  };

  Blackboard ref(p, 2, 64);
  ref.pushShapelet(sa);
  ref.pushShapelet(sb);
  const double j0 = ref.totalEnergy();
  Rng rng(41);
  std::vector<double> w1, w2;
  // Under AddressSanitizer an eighth of the samples and sweeps (43 s there in full).
  const int kSamples = asanScaled(400000, 8);
  for (int s = 0; s < kSamples; ++s) {
    const Pose2 l1 = boxes[rng.below(2)].sample(rng);
    const Pose2 t = drawTable(rng, l1);
    int others[3], n = 0;
    for (int k = 0; k < 4; ++k)
      if (k != nearest(t, l1.position())) others[n++] = k;
    const Vec2 at = t.toWorld(p.cornerOffset(others[rng.below(3)]));
    const Pose2 l2{at.x() + rng.normal(0, sr), at.y() + rng.normal(0, sr),
                   wrapPeriod(t.theta + rng.normal(0, st), kPi / 2)};
    // One leg.
    double v1 = 0.0;
    if (atCorner(t, l1.position())) {
      const int32_t id = ref.addTable(t);
      const int32_t a = ref.addLeg(l1, id);
      v1 = std::exp(ref.totalEnergy() - j0) / (qBox(l1) * qPlace(t, l1) * std::pow(opt.rj_cell, 2));
      ref.killLeg(a);
      ref.releaseLeg(a);
      ref.killTable(id);
      ref.releaseTable(id);
    }
    w1.push_back(v1);
    // Two legs.
    double v2 = 0.0;
    const bool in_boxes = qBox(l2) > 0;
    const bool support = (atCorner(t, l1.position())) || (atCorner(t, l2.position()));
    if (in_boxes && support) {
      const double q = qBox(l1) * qPlace(t, l1) * qOther(t, l1, l2) +
                       qBox(l2) * qPlace(t, l2) * qOther(t, l2, l1);
      const int32_t id = ref.addTable(t);
      const int32_t a = ref.addLeg(l1, id), b = ref.addLeg(l2, id);
      v2 = std::exp(ref.totalEnergy() - j0) / (q * std::pow(opt.rj_cell, 3));
      ref.killLeg(b);
      ref.releaseLeg(b);
      ref.killLeg(a);
      ref.releaseLeg(a);
      ref.killTable(id);
      ref.releaseTable(id);
    }
    w2.push_back(v2);
  }
  Reference r = fromEmpty();
  addEstimate(r, w1);
  addEstimate(r, w2);

  Blackboard bb(p, 2, 64);
  bb.pushShapelet(sa);
  bb.pushShapelet(sb);
  Rng chain_rng(43);
  Sampler sampler(bb, opt, chain_rng);
  Freq n[3], more;
  for (int i = 0; i < asanScaled(100000, 8); ++i) {
    sampler.sweep(1.0);
    const int k = bb.liveTables() == 0 ? 0 : bb.liveLegs();
    for (int j = 0; j < 3; ++j) n[j].x.push_back(bb.liveTables() <= 1 && k == j);
    more.x.push_back(bb.liveTables() > 1);
  }
  INFO("P(two or more tables) " << more.mean());
  CHECK(more.mean() < 0.01);
  for (size_t k = 0; k < 3; ++k) {
    INFO(k << " legs under a table (0: no table)");
    CHECK_AGREES(n[k].mean(), n[k].stderror(), r.p(k), r.se(k));
  }
}

TEST_CASE("Reversible jump: the rooms model's tables of any size sample P(table) exactly",
          "[blackboard]") {
  // A leg (fixed pose) of its own side in a shapelet's box; the kernels: its parent table's birth
  // (size from the prior, one of 8 placements of that size) and death, and (size_steps) the
  // size steps: the table's width and depth with a corner fixed, its leg side, the leg's side.
  // Target: exp(J) / rj_cell per table, against the prior (a uniform probability) on every size
  // parameter (sampler.cc, "Reversible-jump moves").
  ModelParams p;
  p.objects = ObjectModel::kRooms;
  const Pose2 leg{0.3, 0.2, 0.1};
  const Shapelet a = MakeShapelet(leg, p.leg_side, 0);
  ReversibleMoves moves{0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0};
  moves.wall_birth_death = moves.wall_jitter = 0.0;
  moves.sizes = 1.0;
  SamplerOptions opt = rjOptions(moves);
  // Births wider than the target in every direction (eq. 10's sigma_r_leg, sigma_theta_leg): with
  // the defaults' narrower angle step the chain reaches the target's tails only through rare
  // births and leaves them through rarer deaths, and this many sweeps do not converge.
  opt.jitter_sigma_r = 2.0 * p.sigma_r_leg;
  opt.jitter_sigma_theta = 2.0 * p.sigma_theta_leg;

  // Reference: Z_k = integral over the leg's side s (uniform on [leg_min, leg_max]) and, for
  // k = 1, the table's size
  // (uniform over the prior's region, both orders of width and depth), leg side and pose of
  // exp(J - j_ref) / rj_cell, by importance sampling from a density of our own that follows the
  // target's shape: s, width and depth from their priors (width and depth by rejection from a
  // square), the table's leg side from a normal about s, the angle from a normal about the leg's
  // (or a quarter turn), the leg at one of the 4 corners with a normal error. The table turns
  // about that corner, not about its centre as the chain's births do: for a 2 m table a small
  // turn about the centre moves the corner off the leg, so the births' density would leave the
  // weights heavy-tailed exactly where the size steps take the chain.
  Blackboard ref(p, 1, 64);
  ref.pushShapelet(a);
  const int32_t l = ref.addLeg(leg, p.leg_side, kNone);
  const double j_ref = ref.totalEnergy();
  Rng rng(31);
  const double sr = 2.0 * p.sigma_r_leg, st = 2.0 * p.sigma_theta_leg, ts = 3.0 * p.sigma_w;
  const auto normal = [](double x, double sd) {
    return std::exp(-0.5 * x * x / (sd * sd)) / (std::sqrt(2 * kPi) * sd);
  };
  // Z_1 split by the table's width: at most the prior's middle, or more (the size's marginal).
  const double mid = 0.5 * (p.size_min_side + p.size_max_long);
  std::vector<double> w0, w1, w_narrow, w_wide;
  for (int i = 0; i < 400000; ++i) {
    const double s = rng.uniform(p.leg_min, p.leg_max);
    ref.setLegSide(l, s);
    w0.push_back(std::exp(ref.totalEnergy() - j_ref));
    double wd = 0, dp = 0;
    do {
      wd = rng.uniform(p.size_min_side, p.size_max_long);
      dp = rng.uniform(p.size_min_side, p.size_max_long);
    } while (std::min(wd, dp) > p.size_max_short);
    const double tl = s + rng.normal(0, ts);
    const double th0 = wrapPeriod(leg.theta + rng.below(2) * (kPi / 2), kPi);
    const double th = wrapPeriod(th0 + rng.normal(0, st), kPi);
    const int c = static_cast<int>(rng.below(4));
    const Vec2 corner = leg.position() + Vec2(rng.normal(0, sr), rng.normal(0, sr));
    const Vec2 centre = corner - Pose2{0, 0, th}.toWorld(ModelParams::cornerOffset(c, wd, dp, tl));
    const Pose2 t{centre.x(), centre.y(), th};
    if (!p.legSideAllowed(tl)) {
      w1.push_back(0.0);
      w_narrow.push_back(0.0);
      w_wide.push_back(0.0);
      continue;
    }
    // The density of (pose, leg side) given the size: a mixture over the two angles and the
    // four corners; the leg side's against the prior's uniform probability.
    double q = 0;
    for (int turn = 0; turn < 2; ++turn) {
      const double dth = std::remainder(th - (leg.theta + turn * (kPi / 2)), kPi);
      for (int k = 0; k < 4; ++k) {
        const Vec2 e = t.toWorld(ModelParams::cornerOffset(k, wd, dp, tl)) - leg.position();
        q += (1.0 / 8) * normal(dth, st) * normal(e.x(), sr) * normal(e.y(), sr);
      }
    }
    q *= normal(tl - s, ts) * (p.leg_max - p.leg_min);
    bool near = false;
    for (int k = 0; k < 4; ++k)
      near |= (t.toWorld(ModelParams::cornerOffset(k, wd, dp, tl)) - leg.position()).norm() <=
              p.cornerLinkRadius();
    if (!near) {
      w1.push_back(0.0);
      w_narrow.push_back(0.0);
      w_wide.push_back(0.0);
      continue;
    }
    const int32_t id = ref.addTable(t, wd, dp, tl);
    ref.setParent(l, id);
    w1.push_back(std::exp(ref.totalEnergy() - j_ref) / (q * opt.rj_cell));
    w_narrow.push_back(wd <= mid ? w1.back() : 0.0);
    w_wide.push_back(wd > mid ? w1.back() : 0.0);
    ref.setParent(l, kNone);
    ref.killTable(id);
    ref.releaseTable(id);
  }
  Reference r, by_width;
  addEstimate(r, w0);
  addEstimate(r, w1);
  addEstimate(by_width, w_narrow);
  addEstimate(by_width, w_wide);

  Blackboard bb(p, 1, 64);
  bb.pushShapelet(a);
  bb.addLeg(leg, p.leg_side, kNone);
  Rng chain_rng(37);
  Sampler sampler(bb, opt, chain_rng);
  sampler.setAudit(true);
  Freq has, wide;  // a table; its width above the middle (over the sweeps with a table)
  for (int i = 0; i < 400000; ++i) {
    sampler.sweep(1.0);
    has.x.push_back(bb.liveTables() == 1);
    for (int32_t id = 0; id < bb.tableExtent(); ++id)
      if (bb.table(id).alive) wide.x.push_back(bb.table(id).width > mid);
  }
  CHECK(bb.liveLegs() == 1);
  CHECK(sampler.stats().audit_max_error < 1e-9);
  CHECK_AGREES(has.mean(), has.stderror(), r.p(1), r.se(1));
  CHECK_AGREES(wide.mean(), wide.stderror(), by_width.p(1), by_width.se(1));
}
