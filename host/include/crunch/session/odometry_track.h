// The robot's pose at any moment between the Create's odometry packets (issue 12; docs/ROBOT.md,
// "Odometry per sample").
//
// The Create streams its motion every 15 ms as whole degrees and whole millimetres, the sub-unit
// remainder carried to the next packet (io/create_oi.h, Odometry). The whisker samples come at
// 2 kHz, and the ramp (signal/contact_ramp.h) fits each one's deflection against the heading of
// a turn at pi/24 rad/s: 7.5 degrees/s, one whole degree every ~130 ms, about three over a ramp.
// A heading held from packet to packet is a staircase of 1-degree steps under a ramp of three, so
// slope and intercept come out wrong by tens of percent.
//
// What the packets do say exactly: the carried total is a quantiser of the true heading, so
// when the reported total steps to level L (degrees), the true heading passed L somewhere between
// the previous packet and this one. OdometryTrack keeps those crossings ("knots") at the middle
// of their packet interval (time error <= 7.5 ms: 0.06 degrees at the whisk's rate) and
// interpolates the heading linearly between them - what one does with an incremental encoder at
// low speed (edge timing). Consecutive knots differ by exactly one degree (or several within one
// packet, spread evenly over it).
//
// A reversal between two knots (the previous segment went the other way) goes on at the previous
// rate to a peak and back at the next rate; the gap between the knots fixes the peak (f degrees
// past the knot: f / |rate before| + (1 + f) / |rate after| = gap).
// A stop between two knots (their gap longer than Options::max_gap_s: slower than any turn the
// robot makes) is not one slow turn: the heading goes on at the previous segment's rate to half a
// degree past its knot, holds, and reaches the next knot at the following segment's rate (the
// stopped heading's fraction of a degree is not observable; half a degree is the unbiased guess).
// The first packet is a knot of the exact start (odometry 0: the robot starts at rest): there
// the heading holds at 0 until it moves. After the last knot the same rule extrapolates.
//
// Position: interpolated linearly in time between packets (millimetre steps; a turn in place
// reports none).
//
// A pose is final once later packets cannot change it: settledUntil() is the time of the
// second-to-last knot (the segment and the one after it are known) or max_gap_s before the last
// packet, whichever is later. The caller (RobotSession) holds its whisker samples until then.
//
// Times are the host's CLOCK_MONOTONIC nanoseconds, non-decreasing (an earlier time is taken as
// the last one). Poses are in the odometry frame (the start is the origin, heading 0).
// Holds the last kCapacity packets and knots (15 s of stream); queries before them answer with
// the oldest kept. Plain value; allocates only at construction; not thread-safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/core/result.h"

namespace crunch::session {

struct OdometryTrackOptions {
  // A gap between two heading knots longer than this is a stop, not a slow turn or a reversal;
  // also how long a pose waits for the knots after it at most. The robot's slowest turn
  // (pi/24 rad/s) steps every 0.13 s, and reversing it between two knots takes up to three
  // degrees of travel, 0.4 s.
  double max_gap_s = 0.45;
  // okStatus(), or an Error naming the bad field (0.01 .. 10 s).
  Status validate() const;
};

class OdometryTrack {
 public:
  static constexpr std::size_t kCapacity = 1024;

  explicit OdometryTrack(const OdometryTrackOptions& options = {});

  // One odometry packet that arrived at t_ns: the Create's total heading in whole degrees since
  // the start (io::oi::Odometry::totalAngleDeg) and the integrated pose (odometry frame).
  void add(std::uint64_t t_ns, std::int64_t total_deg, const Pose2& odometry);

  bool empty() const { return packets_n_ == 0; }
  std::uint64_t latest() const;  // time of the last packet (0 before any)
  // Poses at or before this time no longer change (see the top); 0 before any packet.
  std::uint64_t settledUntil() const;
  // The pose at t_ns, odometry frame, heading unwrapped (start + degrees). Before any packet:
  // the origin.
  Pose2 poseAt(std::uint64_t t_ns) const;
  // The heading in degrees at t_ns (poseAt's, unconverted): for tests and diagnostics.
  double levelAt(std::uint64_t t_ns) const;

 private:
  struct Packet {
    std::uint64_t t = 0;
    double x = 0.0, y = 0.0;
  };
  struct Knot {
    std::uint64_t t = 0;
    double level = 0.0;  // degrees
    bool rest = false;   // the start: the heading holds exactly here until the next knot
  };
  const Packet& packet(std::size_t i) const { return packets_[(packets_first_ + i) % kCapacity]; }
  const Knot& knot(std::size_t i) const { return knots_[(knots_first_ + i) % kCapacity]; }
  void pushKnot(const Knot& k);
  // Signed rate of segment i (knot i to i+1) in degrees/s, or 0 if it is a stop (or absent).
  double rate(std::size_t i) const;

  OdometryTrackOptions options_;
  std::uint64_t max_gap_ns_;
  std::vector<Packet> packets_;
  std::size_t packets_first_ = 0, packets_n_ = 0;
  std::vector<Knot> knots_;
  std::size_t knots_first_ = 0, knots_n_ = 0;
  std::int64_t last_total_ = 0;
};

}  // namespace crunch::session
