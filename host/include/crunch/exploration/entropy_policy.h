// `--explore entropy`: the paper's §2.9 as written (eqs. 31-36, Fig. 8), to reproduce its §3.4
// finding (docs/EXPLORATION.md, "Information gain and the paper's entropy").
//
// A foveal grid (Fig. 8) of square cells centred on the robot. From the posterior draws
// (ExploreState::samples, drawn by the explore loop from the blackboard's chain) each draw's
// tables are rasterised: T_s(x, y) = 1 if the cell's centre is under draw s's table top, and
// L_s(x, y) = 1 if it is under one of its legs (a leg square, or the cell holding a leg's
// centre). The occupancy probabilities are the draws' frequencies with the flat (Laplace)
// prior the paper starts from, and eq. 34's conditionals are the frequencies among the draws
// with and without a leg in the action cell a:
//   P(T(x,y) | L(a) = b) = (#{s : T_s(x,y) = 1, L_s(a) = b} + 1) / (#{s : L_s(a) = b} + 2)
// and eq. 36's
//   dH(a) = sum_{x,y} H(T(x,y) | L(a)) - H(T(x,y) | not L(a)).
// The action with the largest dH is taken (ties broken by the rng): the robot goes to a whisk
// pose facing cell a at whisker reach (the reachable one of 8 approach directions nearest by
// travel). Exactly as §3.4 found, a cell whose leg state few draws share has a conditional
// built from few draws, so its background cells sit near 1/2 and dominate dH; this policy
// keeps that behaviour on purpose (it is the paper's method), and reports it.
//
// Randomness: only the rng (ties). Allocation: in next(). Draws used: at most 64 (bit masks).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "crunch/exploration/policy.h"

namespace crunch::exploration {

struct EntropyOptions {
  double fovea_side = 1.6;  // metres, the foveal grid's side (Fig. 8: a local region)
  double cell = 0.05;       // metres: one leg side, so a cell holds at most one leg
  double aim_distance = 0.235;  // robot centre to the action cell: mid-whisker
};

// The foveal grid's occupancy bits: one bit per draw (bit s = draw s), row-major nx * nx.
struct FovealGrid {
  int n = 0;                       // cells per side
  double cell = 0.05;
  Vec2 lo = Vec2::Zero();          // corner
  int draws = 0;
  std::vector<std::uint64_t> table;  // T_s
  std::vector<std::uint64_t> leg;    // L_s
  Vec2 centre(int ix, int iy) const { return lo + Vec2((ix + 0.5) * cell, (iy + 0.5) * cell); }
};

// Rasterises up to 64 draws into a fovea of side `side` centred on `centre`.
FovealGrid rasteriseFovea(std::span<const MapSample> samples, const Vec2& centre,
                          const EntropyOptions& options);
// Eq. 36's dH for action cell (ax, ay), from the Laplace-smoothed frequencies of eq. 34.
double entropyDelta(const FovealGrid& grid, int ax, int ay);

class EntropyPolicy final : public ExplorePolicy {
 public:
  EntropyPolicy(const PolicyOptions& options, const EntropyOptions& entropy = {});
  ExplorePolicyKind kind() const override { return ExplorePolicyKind::kEntropy; }
  int samplesWanted() const override { return std::min(options_.samples, 64); }
  Decision next(const ExploreState& state, Rng& rng) override;

  // The last decision's grid and dH per cell (NaN where no pose reaches the cell): Fig. 14.
  const FovealGrid& lastGrid() const { return grid_; }
  const std::vector<double>& lastDelta() const { return delta_; }

 private:
  PolicyOptions options_;
  EntropyOptions eo_;
  FovealGrid grid_;
  std::vector<double> delta_;
};

}  // namespace crunch::exploration
