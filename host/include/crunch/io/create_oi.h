// The iRobot Create's Open Interface, as the original Create (OI v2, "iRobot Create Open
// Interface (OI) Specification", 2006) speaks it over its serial port at 57600 8N1 (paper §2.3:
// the base is a Create driven over its serial interface). Pure byte code, no I/O: command
// encoders, the sensor packet table, a stream parser fed one byte at a time, odometry from the
// distance and angle packets, and SensorTracker, which is the single piece of code that turns
// received bytes into odometry and bump state for both the live driver (io/create_base.h) and
// an offline replay of recorded serial bytes. docs/CREATE.md describes the protocol subset.
//
// Allocation: none anywhere in this header's classes; encoders return fixed-size arrays.
// Thread-safety: none; one thread owns a parser/tracker. Counters may be read between feeds.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "crunch/core/geometry.h"

namespace crunch::io::oi {

// ---- Opcodes (OI spec, "Open Interface Command Reference") ----------------------------------
inline constexpr std::uint8_t kStart = 128;        // -> Passive mode; no data
inline constexpr std::uint8_t kBaud = 129;         // 1 data byte
inline constexpr std::uint8_t kControl = 130;      // same as Safe (kept for old scripts)
inline constexpr std::uint8_t kSafe = 131;         // -> Safe mode; no data
inline constexpr std::uint8_t kFull = 132;         // -> Full mode; no data
inline constexpr std::uint8_t kDrive = 137;        // velocity int16 mm/s, radius int16 mm
inline constexpr std::uint8_t kSensors = 142;      // 1 data byte: packet id; answered at once
inline constexpr std::uint8_t kDriveDirect = 145;  // right int16 mm/s, left int16 mm/s
inline constexpr std::uint8_t kStream = 148;       // n, n packet ids; a packet every 15 ms
inline constexpr std::uint8_t kQueryList = 149;    // n, n packet ids; answered at once
inline constexpr std::uint8_t kPauseResume = 150;  // 1 data byte: 0 pause, 1 resume

inline constexpr std::uint8_t kStreamHeader = 19;  // first byte of every stream packet
inline constexpr double kStreamPeriod = 0.015;     // seconds between stream packets (OI spec)

// ---- Drive limits and special radii (OI spec, "Drive") ----------------------------------------
inline constexpr int kMaxWheelSpeedMm = 500;      // |velocity| and |wheel| <= 500 mm/s
inline constexpr int kMaxRadiusMm = 2000;         // |radius| <= 2000 mm, except the specials:
inline constexpr std::int16_t kRadiusStraight = static_cast<std::int16_t>(0x8000);  // also 32767
inline constexpr std::int16_t kRadiusStraightAlt = 32767;
inline constexpr std::int16_t kRadiusTurnCw = -1;  // turn in place clockwise
inline constexpr std::int16_t kRadiusTurnCcw = 1;  // turn in place counter-clockwise
inline constexpr double kWheelBase = 0.258;        // metres between the wheels (OI spec, Angle)

// ---- Sensor packets 7..42 (OI spec, "Sensor Packets") -----------------------------------------
inline constexpr std::uint8_t kBumpsWheelDrops = 7;  // 1 B bits: 0 bump R, 1 bump L, 2 drop R,
                                                     //   3 drop L, 4 drop caster
inline constexpr std::uint8_t kWall = 8;             // 1 B
inline constexpr std::uint8_t kCliffLeft = 9;        // 1 B (10 front left, 11 front right, 12 right)
inline constexpr std::uint8_t kDistance = 19;        // int16 mm since last read, + forward
inline constexpr std::uint8_t kAngle = 20;           // int16 degrees since last read, + CCW
inline constexpr std::uint8_t kVoltage = 22;         // uint16 mV
inline constexpr std::uint8_t kOiMode = 35;          // 1 B: 0 off, 1 passive, 2 safe, 3 full
inline constexpr std::uint8_t kRequestedVelocity = 39;  // int16 mm/s
inline constexpr std::uint8_t kRequestedRadius = 40;    // int16 mm
inline constexpr std::uint8_t kRequestedRightVelocity = 41;  // int16 mm/s
inline constexpr std::uint8_t kRequestedLeftVelocity = 42;   // int16 mm/s
inline constexpr std::uint8_t kFirstPacketId = 7;
inline constexpr std::uint8_t kLastPacketId = 42;

inline constexpr std::uint8_t kBumpRight = 0x01, kBumpLeft = 0x02, kDropRight = 0x04,
                              kDropLeft = 0x08, kDropCaster = 0x10;
inline constexpr std::uint8_t kBumpMask = kBumpRight | kBumpLeft;
inline constexpr std::uint8_t kDropMask = kDropRight | kDropLeft | kDropCaster;

enum class Mode : std::uint8_t { kOff = 0, kPassive = 1, kSafeMode = 2, kFullMode = 3 };

// Data bytes of packet `id` (1 or 2), or 0 for an id outside 7..42 (the group ids 0..6 are not
// accepted in a stream by this code: nothing here asks for them).
int packetSize(std::uint8_t id);
// Whether a 2-byte packet is signed (19 distance, 20 angle, 23 current, 39..42 velocities/radius)
// and whether a 1-byte packet is signed (24 battery temperature).
bool packetSigned(std::uint8_t id);

// The packets CreateBase streams: bumps/wheel drops, distance, angle, OI mode. 13 bytes a packet
// (header, n = 10, 4 ids, 6 data bytes, checksum), 867 B/s of the link's 5760 B/s.
inline constexpr std::array<std::uint8_t, 4> kCreateBaseStream = {kBumpsWheelDrops, kDistance,
                                                                  kAngle, kOiMode};

// ---- Command encoders: big-endian int16 as the OI wants, no allocation ------------------------
std::array<std::uint8_t, 1> start();
std::array<std::uint8_t, 1> safe();
std::array<std::uint8_t, 1> full();
// Drive (137): velocity clamped to [-500, 500] mm/s; radius clamped to [-2000, 2000] mm unless
// it is one of the specials (0x8000 / 32767 straight, -1 / +1 turn in place).
std::array<std::uint8_t, 5> drive(int velocity_mm_s, int radius_mm);
// Drive Direct (145): each wheel clamped to [-500, 500] mm/s. Note the OI order: right first.
std::array<std::uint8_t, 5> driveDirect(int right_mm_s, int left_mm_s);
std::array<std::uint8_t, 2> pauseResume(bool resume);
std::array<std::uint8_t, 2> sensors(std::uint8_t id);

// Stream (148) and Query List (149) take up to kMaxIds ids; `size` bytes of `bytes` are used.
inline constexpr std::size_t kMaxIds = 36;
struct IdCommand {
  std::array<std::uint8_t, 2 + kMaxIds> bytes{};
  std::size_t size = 0;
  std::span<const std::uint8_t> span() const { return {bytes.data(), size}; }
};
// Ids beyond kMaxIds are dropped; the caller passes ids it knows (packetSize() != 0).
IdCommand stream(std::span<const std::uint8_t> ids);
IdCommand queryList(std::span<const std::uint8_t> ids);

// ---- Twist to wheel commands ------------------------------------------------------------------
// Differential drive: right = v + omega b/2, left = v - omega b/2 (b the wheel base). If either
// wheel would exceed 500 mm/s, both are scaled down by the same factor, so the curvature
// omega/v (the path) is kept and only the speed along it drops. Rounded to whole mm/s.
struct WheelSpeeds {
  int right_mm_s = 0;
  int left_mm_s = 0;
  bool clamped = false;  // the twist was scaled down to fit
};
WheelSpeeds twistToWheels(double v, double omega, double wheel_base = kWheelBase);

// The same twist as Drive's velocity and radius: omega == 0 -> straight (0x8000); v == 0 ->
// turn in place (radius +1 CCW / -1 CW, velocity = the wheel speed); otherwise radius v/omega
// in mm and velocity the centre's speed, scaled as above so the outer wheel stays <= 500 mm/s.
// Lossy: a radius beyond +-2000 mm becomes "straight" (the curvature is lost), a radius under
// 1 mm rounds away from the specials, and the radius is rounded to whole mm.
// CreateBase uses Drive Direct (twistToWheels) instead, because it is exact where Drive is
// lossy: any curvature (no 2 m radius limit), no special cases near v == 0 or omega == 0, and
// the clamp keeps the path. Drive is here for completeness and for other callers.
struct DriveArgs {
  int velocity_mm_s = 0;
  int radius_mm = kRadiusStraight;
};
DriveArgs twistToDrive(double v, double omega, double wheel_base = kWheelBase);

// Writes a stream packet carrying `ids` with their values from `values` (see SensorFrame) into
// `out`: 19, n, [id, data...]..., checksum. The checksum makes the byte sum zero mod 256 over
// n..checksum, plus the header when `checksum_includes_header`. Returns the bytes written, or 0
// if an id is unknown or `out` is too small. Used by tests (sim::CreateEmulator writes its own
// frames, which may carry the group ids 0..6 that this codec does not accept).
struct SensorFrame;
std::size_t encodeStreamPacket(std::span<const std::uint8_t> ids, const SensorFrame& values,
                               bool checksum_includes_header, std::span<std::uint8_t> out);

// ---- Decoded values ---------------------------------------------------------------------------
// The values of one packet (stream, or a Sensors/Query List answer): `present` has bit `id` set
// for each id it carried; value[id] is the decoded integer (signed where the OI says so).
struct SensorFrame {
  std::uint64_t present = 0;
  std::array<std::int32_t, kLastPacketId + 1> value{};

  bool has(std::uint8_t id) const { return id <= kLastPacketId && ((present >> id) & 1u) != 0; }
  std::int32_t get(std::uint8_t id) const { return has(id) ? value[id] : 0; }
  void set(std::uint8_t id, std::int32_t v) {
    if (id > kLastPacketId) return;
    present |= std::uint64_t{1} << id;
    value[id] = v;
  }
};

// ---- StreamParser -------------------------------------------------------------------------------
// Parses the sensor stream (OI spec, "Stream"): [19][n][id][data]...[id][data][checksum], n the
// number of bytes between n and the checksum. Fed ONE BYTE AT A TIME.
//
// A candidate packet starts at a 19. It is rejected as soon as it cannot be valid: n is 0 or
// differs from Options::expected_length (when set), an id is outside 7..42, an id's data would
// overrun n (all "bad_length_or_id"), or the checksum fails ("checksum_failures"). A rejected
// candidate discards only its header byte: the scan resumes at the byte after it, over the
// bytes already held, so a real packet that began inside the rejected one is still found (the
// rule of io/bridge_stream.h). Garbage therefore costs no real packet unless it happens to form
// a valid packet itself (a 1-in-256 checksum chance once its layout is valid); a real packet
// that follows garbage is found within itself.
//
// Checksum: the OI v2 manual says the bytes from n on, including the checksum, sum to zero; the
// Create 1 is reported to include the header byte too. Default checksum_includes_header = true.
//
// Invariant after every feed(): bytes == packet_bytes + skipped_bytes + pending().
struct StreamParserOptions {
  bool checksum_includes_header = true;
  // Expected n (bytes between n and checksum) or 0 for any: with it, a false header is
  // rejected at its second byte. CreateBase sets it from the ids it streams.
  std::uint8_t expected_length = 0;
};

struct StreamCounters {
  std::uint64_t bytes = 0;              // bytes fed
  std::uint64_t packets = 0;            // valid packets delivered
  std::uint64_t packet_bytes = 0;       // bytes of those packets
  std::uint64_t checksum_failures = 0;  // well-formed candidates whose checksum failed
  std::uint64_t bad_length_or_id = 0;   // candidates rejected for n, an id, or an overrun
  std::uint64_t skipped_bytes = 0;      // bytes discarded (garbage, headers of rejects)
};

class StreamParser {
 public:
  using Options = StreamParserOptions;
  StreamParser() : StreamParser(Options{}) {}
  explicit StreamParser(const Options& options) : options_(options) {}

  // Takes the next byte. Returns true if it completed a valid packet, whose values are then in
  // frame() until the next feed(). Never allocates.
  bool feed(std::uint8_t byte);
  // Rarely, a rejected candidate held more than one complete packet: feed() delivers the first
  // and keeps the rest. drainHeld() delivers the next one from the held bytes without new input;
  // call it after every feed() that returned true until it returns false (SensorTracker does).
  bool drainHeld();

  const SensorFrame& frame() const { return frame_; }
  const StreamCounters& counters() const { return counters_; }
  const Options& options() const { return options_; }
  // Bytes held as a possible packet (0..257).
  std::size_t pending() const { return size_; }
  // Forgets held bytes (counters kept).
  void resync();

 private:
  enum class Verdict { kNeedMore, kValid, kBadLayout, kBadChecksum };
  // Walks the held bytes not yet examined, updating the layout state.
  Verdict examine();
  bool process();
  // Drops the first held byte (a rejected header) and rescans the rest.
  void rejectHead();
  void decode();

  Options options_;
  std::array<std::uint8_t, 258> buf_{};  // 19, n, up to 255 bytes, checksum
  std::size_t size_ = 0;
  // Layout walk over buf_[2 .. 2 + n): index of the next id byte.
  std::size_t next_id_ = 2;
  std::size_t examined_ = 0;  // bytes of buf_ already examined
  SensorFrame frame_{};
  StreamCounters counters_{};
};

// ---- Odometry -----------------------------------------------------------------------------------
// Integrates the Create's per-packet distance (mm, packet 19) and angle (degrees, packet 20)
// into a pose with midpoint integration: theta_mid = theta + dtheta/2, x += d cos theta_mid,
// y += d sin theta_mid, theta += dtheta.
//
// What the Create does: both packets report motion since they were last sent (each stream
// packet or Sensors query resets them), as whole millimetres and whole degrees, the angle
// computed from the wheel encoders as (right - left) / wheel base. The Create's firmware keeps
// the encoder counts and the sub-unit remainder carries to the next read; some Create 1 units are
// reported to lose the remainder of the angle instead, which makes slow turns (under 1 degree per
// 15 ms, i.e. under 67 deg/s) under-read - nothing on this side can recover that. On this side
// nothing is lost: the totals are kept as exact integers and the heading is total_degrees *
// pi/180, never a sum of rounded floats.
class Odometry {
 public:
  explicit Odometry(Pose2 start = {}) : start_(start), pose_(start) {}
  void update(int distance_mm, int angle_deg);
  // Pose in metres/radians; theta wrapped to [-pi, pi).
  Pose2 pose() const { return {pose_.x, pose_.y, wrapPi(pose_.theta)}; }
  std::int64_t totalDistanceMm() const { return total_mm_; }
  std::int64_t totalAngleDeg() const { return total_deg_; }
  void reset(Pose2 start = {});

 private:
  Pose2 start_;
  Pose2 pose_;  // theta unwrapped = start.theta + total_deg * pi/180
  std::int64_t total_mm_ = 0;
  std::int64_t total_deg_ = 0;
};

// ---- SensorTracker ------------------------------------------------------------------------------
// StreamParser + Odometry + bump and wheel-drop state: bytes in, robot state out. The live
// driver and an offline replay of recorded bytes run exactly this code, so a replay of the same
// bytes gives the identical odometry whatever the chunking. Never allocates.
struct TrackerCounters {
  StreamCounters stream;
  std::uint64_t bump_packets = 0;  // valid packets with a bumper or wheel drop set
};

class SensorTracker {
 public:
  SensorTracker() : SensorTracker(StreamParserOptions{}) {}
  explicit SensorTracker(const StreamParserOptions& options, Pose2 start = {})
      : parser_(options), odometry_(start) {}

  void feed(std::span<const std::uint8_t> bytes);

  Pose2 odometry() const { return odometry_.pose(); }
  const Odometry& odometryState() const { return odometry_; }
  // Any bumper or wheel drop in the last valid packet carrying packet 7.
  bool bumped() const { return (bumps_ & (kBumpMask | kDropMask)) != 0; }
  bool wheelDropped() const { return (bumps_ & kDropMask) != 0; }
  std::uint8_t bumpsAndDrops() const { return bumps_; }
  // Last OI mode seen (packet 35), or nullopt-like kOff before any.
  Mode mode() const { return mode_; }
  bool modeKnown() const { return mode_known_; }
  std::uint64_t packets() const { return parser_.counters().packets; }
  TrackerCounters counters() const { return {parser_.counters(), bump_packets_}; }
  const SensorFrame& lastFrame() const { return parser_.frame(); }
  const StreamParser& parser() const { return parser_; }

 private:
  StreamParser parser_;
  Odometry odometry_;
  std::uint8_t bumps_ = 0;
  Mode mode_ = Mode::kOff;
  bool mode_known_ = false;
  std::uint64_t bump_packets_ = 0;
};

}  // namespace crunch::io::oi
