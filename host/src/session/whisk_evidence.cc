#include "crunch/session/whisk_evidence.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace crunch {

WhiskEvidence::WhiskEvidence(std::vector<WhiskerMount> mounts, WhiskerBeam beam)
    : mounts_(std::move(mounts)), beam_(beam), entries_(mounts_.size()) {}

void WhiskEvidence::setModels(const signal::SignalModels& models) {
  calibration_ = models.ramp;
  tip_zone_ = models.radial.options.tip_zone;
}

void WhiskEvidence::begin() {
  for (Entry& e : entries_) e = Entry{};
  samples_.clear();
  ++counts_.whisks;
}

void WhiskEvidence::fill(Entry& e, std::size_t w, const signal::ContactEpisode& ep,
                         const signal::WhiskerContact& c, const Pose2& onset, const Pose2& peak,
                         const Pose2& ramp) const {
  e = Entry{};
  e.have = true;
  e.f1 = c.f1;
  e.report.whisker = static_cast<int>(w);
  e.has_r = c.has_r;
  e.has_phi = ep.has_orientation;
  const WhiskerMount& m = mounts_[w];
  e.located = c.ramp.valid;
  if (e.located) {
    // The touch: the straight rest whisker at the ramp's touch heading passes through the point.
    const double lever = m.base.dot(m.direction());
    e.report.r = std::min(distanceFromRampSlope(beam_, c.ramp.slope, lever, calibration_.gain,
                                                calibration_.compliance_scale),
                          m.length);
    e.report.robot = Pose2{ramp.x, ramp.y, c.ramp.touch_heading};
  } else {
    e.report.r = std::clamp(c.r, 0.0, m.length);
    e.report.robot = peak;
  }
  e.tip = e.report.r >= m.length - tip_zone_;
  // A point until classifyFaces() finds the face. The template's angle is relative to the
  // heading at the first contact (the window's alignment, §2.5), the report to its own pose.
  e.report.oriented = false;
  e.report.phi = wrapHalfTurn(ep.orientation.angle + onset.theta - e.report.robot.theta);
}

void WhiskEvidence::classifyFaces() {
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    Entry& a = entries_[i];
    if (!(a.have && a.located && a.tip)) continue;
    for (std::size_t j = i + 1; j < entries_.size(); ++j) {
      Entry& b = entries_[j];
      if (!(b.have && b.located && b.tip)) continue;
      ContactReport& ra = a.report;
      ContactReport& rb = b.report;
      const Vec2 d = mounts_[j].pointAt(rb.robot, rb.r) - mounts_[i].pointAt(ra.robot, ra.r);
      if (d.norm() <= kFlatSpan) continue;
      const double face = std::atan2(d.y(), d.x());
      for (ContactReport* r : {&ra, &rb}) {
        r->oriented = true;
        r->phi = wrapHalfTurn(face - r->robot.theta);
        r->face_span = std::max(r->face_span, d.norm());
      }
    }
  }
}
void WhiskEvidence::discardReports() {
  for (Entry& e : entries_) e = Entry{};
}

void WhiskEvidence::sample(const Pose2& pose, std::uint32_t contact_mask) {
  samples_.push_back({pose, contact_mask});
}

void WhiskEvidence::end(std::vector<ContactReport>& reports, std::vector<FreeRay>& free_rays) {
  classifyFaces();
  for (const Entry& e : entries_) {
    if (!e.have) continue;
    if (!e.has_r) {
      ++counts_.no_radial;
      continue;
    }
    if (!e.located) {
      ++counts_.no_ramp;
      continue;
    }
    if (!e.tip) ++counts_.shaft;
    if (e.report.oriented) ++counts_.flat;
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
