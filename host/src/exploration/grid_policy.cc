// The paper's pre-determined pose list, in order (its §2.8 experiment). Driving, a pose whose
// centre the costmap blocks or the distance field cannot reach is skipped; teleporting, every
// pose is taken (the list is already the poses where the body fits in the world).
#include <cmath>

#include "crunch/exploration/policy.h"

namespace crunch::exploration {

namespace {
class GridPolicy final : public ExplorePolicy {
 public:
  ExplorePolicyKind kind() const override { return ExplorePolicyKind::kGrid; }
  Decision next(const ExploreState& s, Rng&) override {
    while (next_ < s.grid_poses.size()) {
      const Pose2 p = s.grid_poses[next_++];
      if (s.teleport) return Decision{p, "", 0.0};
      if (!choosable(s, p.position())) continue;
      return Decision{p, "", 0.0};
    }
    return Decision{std::nullopt, "the pose list is done", 0.0};
  }

 private:
  std::size_t next_ = 0;
};
}  // namespace

std::unique_ptr<ExplorePolicy> makeGridPolicy(const PolicyOptions&) {
  return std::make_unique<GridPolicy>();
}

}  // namespace crunch::exploration
