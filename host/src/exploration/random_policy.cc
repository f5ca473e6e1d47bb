// The paper's baseline (§3.4): a whisk pose drawn uniformly over the reachable space: a cell
// uniform among the region's cells the robot's centre may stand on and can reach, its centre
// the position, a heading uniform in [-pi, pi).
#include <cmath>

#include "crunch/exploration/policy.h"

namespace crunch::exploration {

namespace {
class RandomPolicy final : public ExplorePolicy {
 public:
  ExplorePolicyKind kind() const override { return ExplorePolicyKind::kRandom; }
  Decision next(const ExploreState& s, Rng& rng) override {
    cells_.clear();
    const KnownSpace& k = s.known;
    for (int iy = 0; iy < k.ny(); ++iy) {
      for (int ix = 0; ix < k.nx(); ++ix) {
        if (choosable(s, k.centre(ix, iy))) {
          cells_.push_back(iy * k.nx() + ix);
        }
      }
    }
    if (cells_.empty()) return Decision{std::nullopt, "boxed in: no reachable whisk pose", 0.0};
    const std::size_t pick =
        std::min(cells_.size() - 1, static_cast<std::size_t>(rng.uniform() * cells_.size()));
    const Vec2 c = k.centre(cells_[pick] % k.nx(), cells_[pick] / k.nx());
    return Decision{Pose2{c.x(), c.y(), rng.uniform(-kPi, kPi)}, "", 0.0};
  }

 private:
  std::vector<int> cells_;
};
}  // namespace

std::unique_ptr<ExplorePolicy> makeRandomPolicy(const PolicyOptions&) {
  return std::make_unique<RandomPolicy>();
}

}  // namespace crunch::exploration
