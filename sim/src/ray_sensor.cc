#include "crunch_sim/ray_sensor.h"

#include <cassert>
#include <cmath>
#include <utility>

namespace crunch::sim {
namespace {

[[maybe_unused]] bool validSigma(double s) { return std::isfinite(s) && s >= 0.0; }

}  // namespace

Status RaySensorModel::Options::validate() const {
  if (!std::isfinite(z)) return Error{"RaySensorModel::Options::z must be finite"};
  if (!std::isfinite(whisk_amplitude) || whisk_amplitude < 0.0 || whisk_amplitude >= kPi) {
    return Error{"RaySensorModel::Options::whisk_amplitude must be in [0, pi) radians"};
  }
  if (!std::isfinite(sweep_step) || sweep_step <= 0.0) {
    return Error{"RaySensorModel::Options::sweep_step must be a positive angle in radians"};
  }
  return okStatus();
}

RaySensorModel::RaySensorModel(const World& world, std::vector<WhiskerMount> mounts,
                               NoiseRegime noise, Options options)
    : world_(world),
      mounts_(std::move(mounts)),
      noise_(std::move(noise)),
      options_(options),
      peaks_(mounts_.size()) {
  assert(options_.validate().ok());
  assert(validSigma(noise_.sigma_r) && validSigma(noise_.sigma_phi));
  const double amp = options_.whisk_amplitude;
  const int n = amp > 0.0 ? static_cast<int>(std::ceil(amp / options_.sweep_step)) : 0;
  offsets_.reserve(static_cast<size_t>(2 * n + 1));
  offsets_.push_back(0.0);
  for (int k = 1; k <= n; ++k) offsets_.push_back(amp * k / n);
  for (int k = 1; k <= n; ++k) offsets_.push_back(-amp * k / n);
  free_.reserve(offsets_.size() * mounts_.size());
}

void RaySensorModel::sense(const Pose2& pose, Rng& rng, std::vector<ContactReport>& out) {
  for (Peak& p : peaks_) p = Peak{};
  free_.clear();

  for (const double offset : offsets_) {
    const Pose2 at{pose.x, pose.y, pose.theta + offset};
    for (size_t w = 0; w < mounts_.size(); ++w) {
      const WhiskerMount& m = mounts_[w];
      const auto hit =
          world_.castRay(at.toWorld(m.base), at.theta + m.bearing, m.length, options_.z);
      // Strictly smaller: on a tie the earlier sample of the whisk wins.
      if (hit && (!peaks_[w].hit || hit->distance < peaks_[w].distance)) {
        peaks_[w] = {true, hit->distance, hit->normal, at};
      }
      if (!hit) {
        const Vec2 dir{std::cos(at.theta + m.bearing), std::sin(at.theta + m.bearing)};
        const Vec2 base = at.toWorld(m.base);
        free_.push_back({base, base + m.length * dir});
      }
    }
  }

  for (size_t w = 0; w < mounts_.size(); ++w) {
    const Peak& p = peaks_[w];
    if (!p.hit) continue;
    const double tangent = std::atan2(p.normal.y(), p.normal.x()) + 0.5 * kPi;
    ContactReport rep;
    rep.whisker = static_cast<int>(w);
    rep.r = p.distance + rng.normal(0.0, noise_.sigma_r);                                 // eq. 4
    rep.phi = wrapHalfTurn(tangent - p.robot.theta + rng.normal(0.0, noise_.sigma_phi));  // eq. 5
    rep.robot = p.robot;
    out.push_back(rep);
  }
}

}  // namespace crunch::sim
