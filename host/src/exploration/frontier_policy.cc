// The classical nearest-frontier explorer (Yamauchi 1997, "A frontier-based approach to
// autonomous exploration"): a frontier cell is unknown with a known-free 4-neighbour; go to the
// cheapest place from which the sensor sees frontier, sense, repeat.
//
// Candidates: positions on a lattice of PolicyOptions::candidate_spacing over the region (where
// the costmap lets the centre stand and the distance field reaches), each with
// candidate_headings headings. A candidate covers the frontier cells its whiskers sweep in a
// body whisk: every whisker, base to tip, at the whisk's headings theta - A .. theta + A
// (A = pi/12, the in-place whisk's amplitude). The candidate with the least path cost wins; ties
// go to the one covering most frontier cells. A frontier cell is counted by one goal only: the
// cells a chosen goal covered are not counted again (an unknown cell behind a touched object
// stays unknown for ever and would otherwise pull the robot back to the same place).
#include <algorithm>
#include <cmath>

#include "crunch/exploration/policy.h"

namespace crunch::exploration {

namespace {

// A goal must cover at least this many frontier cells: one or two cells are the fringe left
// along a whisker's swept line, which any nearby whisk clears on its way.
constexpr int kMinFrontierCells = 3;
constexpr double kWhiskAmplitude = kPi / 12;  // BodyWhisk's default amplitude
constexpr int kSweepSteps = 5;                // headings sampled across the whisk

class FrontierPolicy final : public ExplorePolicy {
 public:
  explicit FrontierPolicy(const PolicyOptions& o) : options_(o) {}
  ExplorePolicyKind kind() const override { return ExplorePolicyKind::kFrontier; }

  Decision next(const ExploreState& s, Rng&) override {
    const KnownSpace& k = s.known;
    const int n = k.nx() * k.ny();
    if (static_cast<int>(attempted_.size()) != n) attempted_.assign(n, 0);
    stamp_.assign(n, 0);
    int stamp = 0;
    // The countable frontier once per decision (the scans below read it many times).
    front_.assign(n, 0);
    for (int iy = 0; iy < k.ny(); ++iy) {
      for (int ix = 0; ix < k.nx(); ++ix) {
        const int i = iy * k.nx() + ix;
        front_[i] = !attempted_[i] && k.frontier(ix, iy);
      }
    }
    double reach = 0.0;
    for (const WhiskerMount& m : s.mounts) reach = std::max(reach, m.base.norm() + m.length);

    // Candidate positions by path cost.
    positions_.clear();
    const double sp = options_.candidate_spacing;
    for (double y = k.lo().y() + 0.5 * sp; y < k.hi().y(); y += sp) {
      for (double x = k.lo().x() + 0.5 * sp; x < k.hi().x(); x += sp) {
        const Vec2 p(x, y);
        const double d = s.travel.to(p);
        if (choosable(s, p)) positions_.push_back({d, p});
      }
    }
    std::sort(positions_.begin(), positions_.end(),
              [](const Cand& a, const Cand& b) { return a.cost < b.cost; });

    std::optional<Pose2> best;
    double best_cost = 0.0;
    int best_cells = 0;
    for (const Cand& c : positions_) {
      if (best && c.cost > best_cost + 1e-9) break;
      if (!frontierWithin(k, c.p, reach)) continue;
      for (int h = 0; h < options_.candidate_headings; ++h) {
        const Pose2 pose{c.p.x(), c.p.y(), wrapPi(2 * kPi * h / options_.candidate_headings)};
        ++stamp;
        const int cells = cover(k, s.mounts, pose, stamp, /*mark=*/false);
        if (cells >= kMinFrontierCells && (!best || cells > best_cells)) {
          best = pose;
          best_cost = c.cost;
          best_cells = cells;
        }
      }
    }
    if (!best) return Decision{std::nullopt, "no frontier left", 0.0};
    cover(k, s.mounts, *best, ++stamp, /*mark=*/true);
    return Decision{best, "", static_cast<double>(best_cells)};
  }

 private:
  struct Cand {
    double cost;
    Vec2 p;
  };

  // Any countable frontier cell within `reach` of p (a cheap test before the headings).
  bool frontierWithin(const KnownSpace& k, const Vec2& p, double reach) const {
    int cx, cy;
    if (!k.index(p, cx, cy)) return false;
    const int r = static_cast<int>(std::ceil(reach / k.cell()));
    for (int iy = std::max(0, cy - r); iy <= std::min(k.ny() - 1, cy + r); ++iy) {
      for (int ix = std::max(0, cx - r); ix <= std::min(k.nx() - 1, cx + r); ++ix) {
        if (front_[iy * k.nx() + ix]) return true;
      }
    }
    return false;
  }

  // The frontier cells the whisk at `pose` sweeps and no earlier goal counted; with `mark`, every
  // swept cell is marked as counted.
  int cover(const KnownSpace& k, const std::vector<WhiskerMount>& mounts, const Pose2& pose,
            int stamp, bool mark) {
    int count = 0;
    const double step = 0.5 * k.cell();
    for (int a = 0; a < kSweepSteps; ++a) {
      const double off = -kWhiskAmplitude + 2 * kWhiskAmplitude * a / (kSweepSteps - 1);
      const Pose2 at{pose.x, pose.y, pose.theta + off};
      for (const WhiskerMount& m : mounts) {
        for (double r = 0.0; r <= m.length + 1e-9; r += step) {
          int ix, iy;
          if (!k.index(m.pointAt(at, r), ix, iy)) continue;
          const int i = iy * k.nx() + ix;
          if (stamp_[i] == stamp) continue;
          stamp_[i] = stamp;
          if (mark) {
            attempted_[i] = 1;
          } else if (front_[i]) {
            ++count;
          }
        }
      }
    }
    return count;
  }

  PolicyOptions options_;
  std::vector<std::uint8_t> attempted_;
  std::vector<std::uint8_t> front_;  // countable frontier cells of this decision
  std::vector<int> stamp_;
  std::vector<Cand> positions_;
};
}  // namespace

std::unique_ptr<ExplorePolicy> makeFrontierPolicy(const PolicyOptions& options) {
  return std::make_unique<FrontierPolicy>(options);
}

}  // namespace crunch::exploration
