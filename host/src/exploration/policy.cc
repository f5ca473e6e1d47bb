#include "crunch/exploration/policy.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace crunch::exploration {

bool choosable(const ExploreState& s, const Vec2& p) {
  if (s.costmap.blocked(p) || !std::isfinite(s.travel.to(p))) return false;
  return std::none_of(s.given_up.begin(), s.given_up.end(), [&](const Vec2& g) {
    return (g - p).norm() < s.given_up_radius;
  });
}

Result<ExplorePolicyKind> explorePolicyByName(const std::string& name) {
  if (name == "grid") return ExplorePolicyKind::kGrid;
  if (name == "random") return ExplorePolicyKind::kRandom;
  if (name == "frontier") return ExplorePolicyKind::kFrontier;
  if (name == "entropy") return ExplorePolicyKind::kEntropy;
  if (name == "infogain") return ExplorePolicyKind::kInfogain;
  return Error{"--explore: unknown policy '" + name +
               "' (expected grid, random, frontier, entropy or infogain)"};
}

const char* explorePolicyName(ExplorePolicyKind kind) {
  switch (kind) {
    case ExplorePolicyKind::kRandom: return "random";
    case ExplorePolicyKind::kFrontier: return "frontier";
    case ExplorePolicyKind::kEntropy: return "entropy";
    case ExplorePolicyKind::kInfogain: return "infogain";
    case ExplorePolicyKind::kGrid: break;
  }
  return "grid";
}

Status PolicyOptions::validate() const {
  std::ostringstream s;
  if (samples < 1 || samples > 256) {
    s << "policy samples " << samples << ": must be 1 to 256";
  } else if (!std::isfinite(candidate_spacing) || candidate_spacing <= 0) {
    s << "policy candidate_spacing " << candidate_spacing << ": must be above 0 metres";
  } else if (candidate_headings < 1 || candidate_headings > 64) {
    s << "policy candidate_headings " << candidate_headings << ": must be 1 to 64";
  } else if (!std::isfinite(min_bits_per_metre) || min_bits_per_metre < 0) {
    s << "policy min_bits_per_metre " << min_bits_per_metre << ": must be 0 or more";
  } else {
    return okStatus();
  }
  return Error{s.str()};
}

std::unique_ptr<ExplorePolicy> makePolicy(ExplorePolicyKind kind, const PolicyOptions& options) {
  switch (kind) {
    case ExplorePolicyKind::kRandom: return makeRandomPolicy(options);
    case ExplorePolicyKind::kFrontier: return makeFrontierPolicy(options);
    case ExplorePolicyKind::kEntropy: return makeEntropyPolicy(options);
    case ExplorePolicyKind::kInfogain: return makeInfogainPolicy(options);
    case ExplorePolicyKind::kGrid: break;
  }
  return makeGridPolicy(options);
}

}  // namespace crunch::exploration
