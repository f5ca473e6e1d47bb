#include "crunch/session/whisk_evidence.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace crunch {

double halfTurn(double a) {
  double w = wrapPeriod(a, kPi);
  if (w < 0.0) w += kPi;
  if (w >= kPi) w -= kPi;
  return w;
}

WhiskEvidence::WhiskEvidence(std::vector<WhiskerMount> mounts)
    : mounts_(std::move(mounts)), entries_(mounts_.size()) {}

void WhiskEvidence::begin() {
  for (Entry& e : entries_) e = Entry{};
  samples_.clear();
  ++counts_.whisks;
}

void WhiskEvidence::fill(Entry& e, std::size_t w, const signal::ContactEpisode& ep,
                         const signal::WhiskerContact& c, const Pose2& onset,
                         const Pose2& peak) const {
  e = Entry{};
  e.have = true;
  e.f1 = c.f1;
  e.report.whisker = static_cast<int>(w);
  e.report.robot = peak;
  e.has_r = c.has_r;
  e.report.r = std::clamp(c.r, 0.0, mounts_[w].length);
  e.has_phi = ep.has_orientation;
  // The template's angle is relative to the heading at the first contact (the window's
  // alignment, §2.5); the report is relative to the heading at this whisker's peak.
  e.report.phi = halfTurn(ep.orientation.angle + onset.theta - peak.theta);
}

void WhiskEvidence::discardReports() {
  for (Entry& e : entries_) e = Entry{};
}

void WhiskEvidence::sample(const Pose2& pose, std::uint32_t contact_mask) {
  samples_.push_back({pose, contact_mask});
}

void WhiskEvidence::end(std::vector<ContactReport>& reports, std::vector<FreeRay>& free_rays) {
  for (const Entry& e : entries_) {
    if (!e.have) continue;
    if (!e.has_r) {
      ++counts_.no_radial;
      continue;
    }
    if (!e.has_phi) {
      ++counts_.no_orientation;
      continue;
    }
    reports.push_back(e.report);
    ++counts_.reports;
  }
  const int ns = static_cast<int>(samples_.size());
  for (int i = 0; i < ns; ++i) {
    const Pose2& p = samples_[static_cast<std::size_t>(i)].pose;
    for (std::size_t w = 0; w < mounts_.size(); ++w) {
      bool clear = true;
      for (int j = std::max(0, i - kFreeGuard); j <= std::min(ns - 1, i + kFreeGuard); ++j) {
        if (samples_[static_cast<std::size_t>(j)].mask & (1u << w)) clear = false;
      }
      if (!clear) continue;
      const WhiskerMount& m = mounts_[w];
      const Vec2 base = p.toWorld(m.base);
      const double dir = p.theta + m.bearing;
      free_rays.push_back({base, base + m.length * Vec2{std::cos(dir), std::sin(dir)}});
    }
  }
}

}  // namespace crunch
