#include "crunch/exploration/infogain_policy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

namespace crunch::exploration {

double binaryEntropyBits(double p) {
  if (!(p > 0.0) || !(p < 1.0)) return 0.0;
  return -(p * std::log2(p) + (1.0 - p) * std::log2(1.0 - p));
}

InfogainPolicy::InfogainPolicy(const PolicyOptions& options, const InfogainOptions& infogain)
    : options_(options), io_(infogain), predictor_(defaultWhiskerArray(), infogain.prediction) {}

bool InfogainPolicy::whiskedBefore(const Pose2& pose) const {
  // The same whisk again repeats its outcome at the sensor's resolution: nothing new.
  const double tol = 2.0 * io_.prediction.resolution;
  for (const Pose2& w : whisked_) {
    if (std::hypot(w.x - pose.x, w.y - pose.y) <= tol &&
        std::abs(wrapPi(w.theta - pose.theta)) <= io_.prediction.amplitude / 2)
      return true;
  }
  return false;
}

void InfogainPolicy::prepare(const ExploreState& state) {
  if (predictor_.mounts().size() != state.mounts.size() ||
      !std::equal(state.mounts.begin(), state.mounts.end(), predictor_.mounts().begin(),
                  [](const WhiskerMount& a, const WhiskerMount& b) {
                    return a.base == b.base && a.bearing == b.bearing && a.length == b.length;
                  })) {
    predictor_ = WhiskPredictor(state.mounts, io_.prediction);
  }
  obstacles_.resize(state.samples.size());
  outcomes_.resize(state.samples.size());
  double legs = 0.0;
  for (size_t i = 0; i < state.samples.size(); ++i) {
    obstacles_[i].assign(state.samples[i]);
    legs += static_cast<double>(obstacles_[i].legs.size());
  }
  if (!state.samples.empty()) legs /= static_cast<double>(state.samples.size());
  const KnownSpace& k = state.known;
  int known_cells = 0;
  for (int iy = 0; iy < k.ny(); ++iy)
    for (int ix = 0; ix < k.nx(); ++ix) known_cells += k.at(ix, iy) != KnownSpace::Cell::kUnknown;
  const double known_m2 = known_cells * k.cell() * k.cell();
  lambda_ = (io_.prior_legs + legs) / (io_.prior_area_m2 + known_m2);
  stamp_.assign(static_cast<size_t>(k.nx() * k.ny()), 0);
  stamp_now_ = 0;
}

double InfogainPolicy::sampleBits(const Pose2& pose) {
  const size_t n = obstacles_.size();
  if (n < 2) return 0.0;
  bool any = false;
  for (const WhiskObstacles& o : obstacles_) any = any || predictor_.anyInReach(pose.position(), o);
  if (!any) return 0.0;  // every draw predicts no touch: one outcome
  for (size_t i = 0; i < n; ++i) predictor_.predict(pose, obstacles_[i], outcomes_[i]);
  // Partition the draws by outcome (greedy: a draw joins the first class whose representative
  // it matches). H(Y) of the partition; H(Y | M) = 0 for a deterministic quantised prediction.
  cls_count_.assign(n, 0);
  std::vector<size_t>& rep = rep_scratch_;
  rep.clear();
  for (size_t i = 0; i < n; ++i) {
    size_t c = 0;
    for (; c < rep.size(); ++c)
      if (sameOutcome(outcomes_[rep[c]], outcomes_[i], io_.prediction.resolution)) break;
    if (c == rep.size()) rep.push_back(i);
    ++cls_count_[c];
  }
  double h = 0.0;
  for (size_t c = 0; c < rep.size(); ++c) {
    const double p = static_cast<double>(cls_count_[c]) / static_cast<double>(n);
    h -= p * std::log2(p);
  }
  return h;
}

double InfogainPolicy::unknownBits(const ExploreState& state, const Pose2& pose) {
  const KnownSpace& k = state.known;
  const double cell = k.cell();
  ++stamp_now_;
  int unknown = 0;
  const double amp = io_.prediction.amplitude;
  for (const WhiskerMount& m : predictor_.mounts()) {
    const double tip = (m.base + m.length * m.direction()).norm();
    // Angular step: half a cell at the tip; radial step half a cell.
    const int na = std::max(1, static_cast<int>(std::ceil(2.0 * amp * tip / (0.5 * cell))));
    const int nr = std::max(1, static_cast<int>(std::ceil(m.length / (0.5 * cell))));
    for (int a = 0; a <= na; ++a) {
      const double off = -amp + 2.0 * amp * a / na;
      const Pose2 at{pose.x, pose.y, pose.theta + off};
      const Vec2 base = at.toWorld(m.base);
      const double h = at.theta + m.bearing;
      const Vec2 dir{std::cos(h), std::sin(h)};
      for (int r = 0; r <= nr; ++r) {
        int ix, iy;
        if (!k.index(base + (m.length * r / nr) * dir, ix, iy)) break;
        const KnownSpace::Cell c = k.at(ix, iy);
        if (c == KnownSpace::Cell::kOccupied) break;  // the whisker stops at a known obstacle
        if (c != KnownSpace::Cell::kUnknown) continue;
        int& s = stamp_[static_cast<size_t>(iy * k.nx() + ix)];
        if (s == stamp_now_) continue;
        s = stamp_now_;
        ++unknown;
      }
    }
  }
  const double area = unknown * cell * cell;
  return binaryEntropyBits(1.0 - std::exp(-lambda_ * area));
}

CandidateValue InfogainPolicy::value(const ExploreState& state, const Pose2& pose) {
  if (obstacles_.size() != state.samples.size() || stamp_.empty()) prepare(state);
  CandidateValue v;
  v.pose = pose;
  v.travel_m = state.travel.to(pose.position());
  if (!std::isfinite(v.travel_m) || whiskedBefore(pose)) return v;
  v.sample_bits = sampleBits(pose);
  v.unknown_bits = unknownBits(state, pose);
  v.score = (v.sample_bits + v.unknown_bits) / (v.travel_m + io_.whisk_cost_m);
  return v;
}

Decision InfogainPolicy::next(const ExploreState& state, Rng& /*rng*/) {
  // The pose just whisked (the robot stands where its last whisk began).
  if (state.whisks > 0) whisked_.push_back(state.robot);
  prepare(state);
  values_.clear();
  std::vector<Pose2> candidates;
  const KnownSpace& k = state.known;
  const double step = options_.candidate_spacing;
  const int nh = options_.candidate_headings;
  const Vec2 lo = k.lo(), hi = k.hi();
  for (double y = lo.y() + 0.5 * step; y < hi.y(); y += step)
    for (double x = lo.x() + 0.5 * step; x < hi.x(); x += step) {
      const Vec2 p{x, y};
      if (state.costmap.blocked(p) || !std::isfinite(state.travel.to(p))) continue;
      for (int h = 0; h < nh; ++h) candidates.push_back({x, y, wrapPi(2.0 * kPi * h / nh)});
    }
  // Fig. 7: the poses that would settle each leg of each draw.
  const size_t lattice = candidates.size();
  for (const WhiskObstacles& o : obstacles_)
    for (const OrientedRect& leg : o.legs)
      for (int d = 0; d < 8; ++d) {
        const double a = 2.0 * kPi * d / 8;
        const Vec2 p = leg.pose.position() - io_.aim_distance * Vec2{std::cos(a), std::sin(a)};
        if (state.costmap.blocked(p) || !std::isfinite(state.travel.to(p))) continue;
        candidates.push_back({p.x(), p.y(), wrapPi(a)});
      }
  // Duplicates (draws agreeing on a leg) are scored once.
  auto key = [](const Pose2& q) {
    return std::make_tuple(std::lround(q.x / 0.01), std::lround(q.y / 0.01),
                           std::lround(wrapPi(q.theta) / 0.05));
  };
  std::sort(candidates.begin() + static_cast<std::ptrdiff_t>(lattice), candidates.end(),
            [&](const Pose2& a, const Pose2& b) { return key(a) < key(b); });
  candidates.erase(std::unique(candidates.begin() + static_cast<std::ptrdiff_t>(lattice),
                               candidates.end(),
                               [&](const Pose2& a, const Pose2& b) { return key(a) == key(b); }),
                   candidates.end());

  Decision d;
  int best = -1;
  for (const Pose2& c : candidates) {
    values_.push_back(value(state, c));
    if (best < 0 || values_.back().score > values_[static_cast<size_t>(best)].score)
      best = static_cast<int>(values_.size()) - 1;
  }
  if (best < 0) {
    d.why = "no reachable whisk pose";
    return d;
  }
  const CandidateValue& b = values_[static_cast<size_t>(best)];
  if (!(b.score > options_.min_bits_per_metre) || b.score <= 1e-9) {
    d.why = "no candidate worth its travel";
    d.score = b.score;
    return d;
  }
  d.goal = b.pose;
  d.score = b.score;
  return d;
}

std::unique_ptr<ExplorePolicy> makeInfogainPolicy(const PolicyOptions& options) {
  return std::make_unique<InfogainPolicy>(options);
}

}  // namespace crunch::exploration
