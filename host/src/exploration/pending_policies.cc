// Stand-ins for the entropy and infogain policies until their own files land (issue 14's
// INFOGAIN part deletes this file): a policy that never proposes a goal, so a run that asks for
// one ends at once and says why.
#include "crunch/exploration/policy.h"

namespace crunch::exploration {

namespace {
class PendingPolicy final : public ExplorePolicy {
 public:
  explicit PendingPolicy(ExplorePolicyKind kind) : kind_(kind) {}
  ExplorePolicyKind kind() const override { return kind_; }
  Decision next(const ExploreState&, Rng&) override {
    return Decision{std::nullopt, std::string(explorePolicyName(kind_)) + ": not built yet", 0.0};
  }

 private:
  ExplorePolicyKind kind_;
};
}  // namespace

std::unique_ptr<ExplorePolicy> makeEntropyPolicy(const PolicyOptions&) {
  return std::make_unique<PendingPolicy>(ExplorePolicyKind::kEntropy);
}
std::unique_ptr<ExplorePolicy> makeInfogainPolicy(const PolicyOptions&) {
  return std::make_unique<PendingPolicy>(ExplorePolicyKind::kInfogain);
}

}  // namespace crunch::exploration
