#include "crunch/session/odometry_track.h"

#include <algorithm>
#include <cmath>

#include "crunch/core/range_check.h"

namespace crunch::session {

namespace {
constexpr double kNsPerS = 1e9;
constexpr double kRadPerDeg = kPi / 180.0;
double sign(double v) { return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0); }
}  // namespace

Status OdometryTrackOptions::validate() const {
  return checkRange("max_gap_s", max_gap_s, 0.01, 10.0);
}

OdometryTrack::OdometryTrack(const OdometryTrackOptions& options)
    : options_(options),
      max_gap_ns_(static_cast<std::uint64_t>(options.max_gap_s * kNsPerS)),
      packets_(kCapacity),
      knots_(kCapacity) {}

std::uint64_t OdometryTrack::latest() const {
  return packets_n_ == 0 ? 0 : packet(packets_n_ - 1).t;
}

void OdometryTrack::pushKnot(const Knot& k) {
  if (knots_n_ == kCapacity) {
    knots_first_ = (knots_first_ + 1) % kCapacity;
    --knots_n_;
  }
  knots_[(knots_first_ + knots_n_) % kCapacity] = k;
  ++knots_n_;
}

void OdometryTrack::add(std::uint64_t t_ns, std::int64_t total_deg, const Pose2& odometry) {
  const bool first = packets_n_ == 0;
  const std::uint64_t t_prev = first ? t_ns : latest();
  const std::uint64_t t = std::max(t_ns, t_prev);
  if (first) pushKnot({t, 0.0, true});  // the start: odometry 0, at rest
  const std::int64_t steps = total_deg - last_total_;
  const std::int64_t m = steps < 0 ? -steps : steps;
  const double dir = steps < 0 ? -1.0 : 1.0;
  // Each whole degree passed between the previous packet and this one: a knot, spread evenly.
  for (std::int64_t j = 1; j <= m; ++j) {
    const double f = (static_cast<double>(j) - 0.5) / static_cast<double>(m);
    const auto tk = t_prev + static_cast<std::uint64_t>(f * static_cast<double>(t - t_prev));
    pushKnot({tk, static_cast<double>(last_total_) + dir * static_cast<double>(j), false});
  }
  last_total_ = total_deg;
  if (packets_n_ == kCapacity) {
    packets_first_ = (packets_first_ + 1) % kCapacity;
    --packets_n_;
  }
  packets_[(packets_first_ + packets_n_) % kCapacity] = {t, odometry.x, odometry.y};
  ++packets_n_;
}

std::uint64_t OdometryTrack::settledUntil() const {
  if (packets_n_ == 0) return 0;
  const std::uint64_t last = latest();
  std::uint64_t settled = last > max_gap_ns_ ? last - max_gap_ns_ : 0;
  if (knots_n_ >= 2) settled = std::max(settled, knot(knots_n_ - 2).t);
  return settled;
}

double OdometryTrack::rate(std::size_t i) const {
  if (i + 1 >= knots_n_ || knot(i).rest) return 0.0;
  const std::uint64_t dt = knot(i + 1).t - knot(i).t;
  if (dt > max_gap_ns_) return 0.0;
  return (knot(i + 1).level - knot(i).level) / (static_cast<double>(std::max<std::uint64_t>(dt, 1000)) / kNsPerS);
}

double OdometryTrack::levelAt(std::uint64_t t) const {
  if (knots_n_ == 0) return 0.0;
  // The last knot at or before t (binary search over the ring's logical order).
  std::size_t lo = 0, hi = knots_n_;
  while (lo < hi) {
    const std::size_t mid = (lo + hi) / 2;
    if (knot(mid).t <= t) lo = mid + 1;
    else hi = mid;
  }
  if (lo == 0) return knot(0).level;
  const std::size_t i = lo - 1;
  const Knot& a = knot(i);
  const bool last = i + 1 == knots_n_;
  const double rp = i >= 1 ? rate(i - 1) : 0.0;
  const double dt_a = static_cast<double>(t - a.t) / kNsPerS;
  if (!last && !a.rest && knot(i + 1).t - a.t <= max_gap_ns_) {
    const Knot& b = knot(i + 1);
    const double gap_s = static_cast<double>(b.t - a.t) / kNsPerS;
    if (rp != 0.0 && sign(rp) != sign(b.level - a.level)) {
      // A reversal: on at the previous rate to a peak f degrees past a, back to b at the next
      // rate; the gap fixes f: f / |rp| + (1 + f) / |rn| = gap.
      double rn = std::abs(rate(i + 1));
      if (rn == 0.0) rn = std::abs(rp);
      const double f = std::clamp((gap_s - 1.0 / rn) / (1.0 / std::abs(rp) + 1.0 / rn), 0.0, 1.0);
      const double peak_s = f / std::abs(rp);
      if (dt_a <= peak_s) return a.level + rp * dt_a;
      const double peak = a.level + sign(rp) * f;
      return peak + (b.level - peak) * (dt_a - peak_s) / (gap_s - peak_s);
    }
    // A turn: linear.
    return a.level + (b.level - a.level) * dt_a / gap_s;
  }
  // A stop after knot i (or nothing known after it): go on at the previous segment's rate to
  // half a degree past the knot, and hold there (exactly at the knot after the rest start).
  double s = sign(rp);
  if (s == 0.0 && i >= 1) s = sign(a.level - knot(i - 1).level);
  const double hold = a.rest ? a.level : a.level + 0.5 * s;
  const double hold_begin_s = rp != 0.0 ? std::abs(hold - a.level) / std::abs(rp) : 0.0;
  if (dt_a < hold_begin_s) return a.level + rp * dt_a;
  if (last) return hold;
  // ... then reach the next knot at the following segment's rate (else the previous one's).
  const Knot& b = knot(i + 1);
  double rn = rate(i + 1);
  if (rn == 0.0) rn = rp;
  const double gap_s = static_cast<double>(b.t - a.t) / kNsPerS;
  const double move_s = std::max(hold_begin_s, rn != 0.0 ? gap_s - std::abs(b.level - hold) / std::abs(rn) : gap_s);
  if (dt_a < move_s) return hold;
  if (gap_s <= move_s) return b.level;
  return hold + (b.level - hold) * (dt_a - move_s) / (gap_s - move_s);
}

Pose2 OdometryTrack::poseAt(std::uint64_t t) const {
  Pose2 p{0.0, 0.0, levelAt(t) * kRadPerDeg};
  if (packets_n_ == 0) return p;
  std::size_t lo = 0, hi = packets_n_;
  while (lo < hi) {
    const std::size_t mid = (lo + hi) / 2;
    if (packet(mid).t <= t) lo = mid + 1;
    else hi = mid;
  }
  if (lo == 0) {
    p.x = packet(0).x;
    p.y = packet(0).y;
  } else if (lo == packets_n_) {
    p.x = packet(lo - 1).x;
    p.y = packet(lo - 1).y;
  } else {
    const Packet& a = packet(lo - 1);
    const Packet& b = packet(lo);
    const double f = b.t == a.t ? 1.0 : static_cast<double>(t - a.t) / static_cast<double>(b.t - a.t);
    p.x = a.x + f * (b.x - a.x);
    p.y = a.y + f * (b.y - a.y);
  }
  return p;
}

}  // namespace crunch::session
