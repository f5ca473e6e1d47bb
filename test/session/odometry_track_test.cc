#include "crunch/session/odometry_track.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <functional>

namespace {

using crunch::Pose2;
using crunch::session::OdometryTrack;

constexpr std::uint64_t kPacketNs = 15000000;  // the Create's stream period
constexpr double kDegPerRad = 180.0 / crunch::kPi;

// The Create's side (sim/src/create_emulator.cc): the true heading (degrees) is accumulated and
// reported in whole degrees per packet, the remainder carried (trunc toward zero).
struct CreateQuantiser {
  double acc = 0.0, last_true = 0.0;
  std::int64_t total = 0;
  void packet(double true_deg) {
    acc += true_deg - last_true;
    last_true = true_deg;
    const double whole = std::trunc(acc);
    acc -= whole;
    total += static_cast<std::int64_t>(whole);
  }
};

// Streams packets of `heading(t)` (degrees; t in seconds from 0) into a track for `seconds`.
OdometryTrack streamed(const std::function<double(double)>& heading, double seconds) {
  OdometryTrack track;
  CreateQuantiser q;
  for (std::uint64_t t = 0; t <= static_cast<std::uint64_t>(seconds * 1e9); t += kPacketNs) {
    q.packet(heading(static_cast<double>(t) / 1e9));
    track.add(t + 1000, q.total, Pose2{});  // arrives 1 us after it was sent
  }
  return track;
}

double worstError(const OdometryTrack& track, const std::function<double(double)>& heading,
                  double from_s, double to_s) {
  double worst = 0.0;
  for (double t = from_s; t < to_s; t += 0.0005) {
    const auto ns = static_cast<std::uint64_t>(t * 1e9);
    worst = std::max(worst, std::abs(track.levelAt(ns) - heading(t)));
  }
  return worst;
}

}  // namespace

TEST_CASE("OdometryTrack: a slow turn's heading between whole-degree packets is right to a "
          "tenth of a degree, where holding the last packet is off by up to one",
          "[unit]") {
  // The body whisk's turn, pi/24 rad/s = 7.5 deg/s, from rest at 0.5 s, for 3 s, then at rest.
  const double rate = 7.5;
  auto heading = [&](double t) { return t < 0.5 ? 0.0 : rate * (std::min(t, 3.5) - 0.5); };
  const OdometryTrack track = streamed(heading, 5.0);
  // At rest before the turn the heading is exactly the start's.
  CHECK(worstError(track, heading, 0.0, 0.45) == 0.0);
  // Through the turn after its first whole degree: the knots' timing (+-7.5 ms) is all that
  // is left, 0.06 degrees at this rate.
  const double during = worstError(track, heading, 0.5 + 1.0 / rate, 3.5 - 1.0 / rate);
  INFO("worst heading error during the turn " << during << " deg");
  CHECK(during < 0.1);
  // Holding each packet's total (the staircase) is off by up to a whole degree.
  CreateQuantiser q;
  double stair = 0.0;
  for (std::uint64_t t = 0; t < 3'000'000'000; t += kPacketNs) {
    q.packet(heading(static_cast<double>(t) / 1e9));
    if (t > 700'000'000) stair = std::max(stair, std::abs(static_cast<double>(q.total) -
                                                          heading((static_cast<double>(t) + 14e6) / 1e9)));
  }
  CHECK(stair > 0.9);
  // The turn's start and its stop are within the unobservable fraction of a degree.
  CHECK(worstError(track, heading, 0.0, 5.0) <= 0.75);
  // Radians, with the position.
  const Pose2 p = track.poseAt(2'000'000'000);
  CHECK(p.theta * kDegPerRad == Approx(heading(2.0)).margin(0.1));
}

TEST_CASE("OdometryTrack: both directions, reversals and a pause mid-turn", "[unit]") {
  // Toward (+7.5 deg/s for 2 s), away (-7.5 deg/s for 4 s), a 1 s pause, back (+7.5 for 2 s): the
  // body whisk's sweep with a stop inside.
  auto heading = [](double t) {
    if (t < 0.2) return 0.0;
    if (t < 2.2) return 7.5 * (t - 0.2);
    if (t < 6.2) return 15.0 - 7.5 * (t - 2.2);
    if (t < 7.2) return -15.0;
    if (t < 9.2) return -15.0 + 7.5 * (t - 7.2);
    return 0.0;
  };
  const OdometryTrack track = streamed(heading, 10.0);
  // Through the turns and their reversals (the peak placed from the gap between the knots on
  // either side), as exact as a steady turn.
  CHECK(worstError(track, heading, 0.5, 6.0) < 0.1);
  CHECK(worstError(track, heading, 7.5, 9.0) < 0.1);
  // Stopping and starting again: within the unobservable fraction of a degree.
  CHECK(worstError(track, heading, 0.0, 10.0) <= 0.75);
}

TEST_CASE("OdometryTrack: poses settle after the next knots or the longest gap, position is "
          "interpolated between packets",
          "[unit]") {
  OdometryTrack track;
  CHECK(track.empty());
  CHECK(track.settledUntil() == 0);
  CHECK(track.poseAt(5).x == 0.0);
  // Driving straight at 0.1 m/s: 1.5 mm per packet, no heading knots.
  for (int k = 0; k <= 40; ++k) {
    track.add(static_cast<std::uint64_t>(k) * kPacketNs, 0, Pose2{0.0015 * k, 0.0, 0.0});
  }
  const std::uint64_t latest = 40 * kPacketNs;
  CHECK(track.latest() == latest);
  CHECK(track.settledUntil() == latest - 450'000'000);  // max_gap_s, 0.45 s
  CHECK(track.poseAt(kPacketNs / 3).x == Approx(0.0005));
  CHECK(track.poseAt(latest + kPacketNs).x == Approx(0.06));  // after the last: held
  // A knot: the earlier of the last two knots bounds what is settled.
  track.add(latest + kPacketNs, 1, Pose2{0.06, 0.0, 0.0});
  track.add(latest + 2 * kPacketNs, 2, Pose2{0.06, 0.0, 0.0});
  CHECK(track.settledUntil() == latest + kPacketNs / 2);
}

TEST_CASE("OdometryTrack: a long run keeps the last packets and knots without growing",
          "[unit]") {
  OdometryTrack track;
  for (int k = 0; k < 5000; ++k) {
    track.add(static_cast<std::uint64_t>(k) * kPacketNs, k, Pose2{});  // 1 degree per packet
  }
  const auto t = static_cast<std::uint64_t>(4990.5 * kPacketNs);
  CHECK(track.levelAt(t) == Approx(4990.0 + 0.5 + 0.5).margin(1e-6));
  CHECK(track.levelAt(0) == Approx(5000.0 - OdometryTrack::kCapacity + 0.0).margin(1.0));
}
