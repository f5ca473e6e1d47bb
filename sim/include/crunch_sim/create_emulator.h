// An iRobot Create (OI v2, io/create_oi.h) on a pseudo-terminal: the driver (io/create_base.h)
// opens slavePath() exactly as it opens /dev/ttyUSB0, and every byte goes through the kernel's
// tty layer both ways (ARCHITECTURE.md §5: "a Create emulator on a pseudo-terminal (openpty)
// speaking the OI byte protocol"). The emulator drives any MobileBase: sim::KinematicBase in
// the tests, the ODE WhiskeredRobot in the simulator; it uses only the MobileBase interface
// (drive, odometry() as the true pose, bumped, now()).
//
// pump() never blocks. It reads every pending command byte and acts on it (byte-exact OI v2):
//   - modes: Off until Start (everything else ignored); Start -> Passive (motors stopped);
//     Safe / Control -> Safe; Full -> Full. Drive and Drive Direct reach body.drive(v, omega)
//     only in Safe or Full, clamped like the Create (|velocity|, |wheel| <= 500 mm/s).
//   - Stream (148) selects the packets and starts a packet every stream_period of the BODY's
//     clock (body.now()); Pause/Resume (150) stops and restarts it; Sensors (142, ids 0..42)
//     and Query List (149) are answered at once with the data bytes only. Group ids 0..6 are
//     answered and streamed as their member packets' data in order (a stream frame carries the
//     group id once, then its data), as the manual lists them.
//   - unsupported packet ids (docs/CREATE.md, "Unsupported packet ids"): the Create 1's manual
//     defines ids 0..42 only and has no error reply, so an id outside 0..42 in Sensors, Query
//     List or Stream is skipped: it adds no byte to the answer or the frame, the other ids are
//     served as if it had not been asked for, and a Stream of nothing but such ids streams
//     nothing. Each such id is counted (counters().unsupported_ids) and remembered
//     (unsupportedIds()), so the harness can tell the user why a reply is short. Stream ids past
//     the 43rd (the manual's maximum count) or past a frame of 255 data bytes are skipped and
//     counted the same way.
//   - the other OI opcodes (LEDs, songs, scripts, ...) are parsed by length and ignored;
//     bytes that are no opcode are counted and skipped.
// then writes garbage queued by injectGarbage() and the stream packets due by body.now(),
// each carrying the distance and angle travelled since the previous report. If the body's
// clock jumped more than max_catch_up packets, the missed ones are skipped (the motion is not
// lost: it goes into the next packet).
//
// Distance and angle are measured from the body's pose (the arc length along the motion and
// the heading change, as the Create's wheel encoders see them) and kept in accumulators; a
// report sends the whole units (truncated toward zero) and keeps the remainder, as the
// firmware's encoder counts do. Quirks of the real robot, each an option:
//   - checksum_includes_header (default true): the Create 1's checksum covers the header byte;
//   - drop_angle_remainder (default false): the angle's sub-degree remainder is discarded at each
//     report instead of carried, mimicking reports that a Create 1 under-reads slow turns;
//   - safe_stops_on_wheel_drop (default true): in Safe mode a wheel drop (setWheelDrops) stops
//     the motors and falls back to Passive (OI spec, "Safe mode").
// Bumpers come from body.bumped() (both bumper bits). The Create does NOT stop itself on a bump.
//
// Thread-safety: none; pump() and the body must be used from one thread.
// Allocation: construction only (the command buffer and output buffers are fixed).
#pragma once

#include <array>
#include <bitset>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "crunch/robot/mobile_base.h"
#include "crunch/core/result.h"
#include "crunch/io/create_oi.h"

namespace crunch::sim {

struct CreateEmulatorCounters {
  std::uint64_t bytes_received = 0;
  std::uint64_t commands = 0;           // complete commands parsed (any opcode)
  std::uint64_t ignored_commands = 0;   // complete but ignored (wrong mode, unsupported)
  std::uint64_t unknown_bytes = 0;      // bytes where an opcode was expected but none is
  std::uint64_t drive_commands = 0;     // Drive / Drive Direct applied to the body
  std::uint64_t packets_sent = 0;
  std::uint64_t packets_skipped = 0;    // due packets skipped after a clock jump
  std::uint64_t corrupted_packets = 0;  // sent with a bad checksum (corruptNextPackets)
  std::uint64_t garbage_bytes_sent = 0;
  std::uint64_t bytes_sent = 0;
  std::uint64_t bytes_dropped = 0;      // the pty was full (nobody reading)
  std::uint64_t safety_stops = 0;       // Safe mode stopped on a wheel drop
  std::uint64_t unsupported_ids = 0;    // packet ids asked for and skipped (see the top)
};

class CreateEmulator {
 public:
  struct Options {
    bool checksum_includes_header = true;
    bool drop_angle_remainder = false;
    bool safe_stops_on_wheel_drop = true;
    double stream_period = io::oi::kStreamPeriod;  // seconds of body.now()
    double wheel_base = io::oi::kWheelBase;        // for Drive's radius and Drive Direct
    int max_catch_up = 8;                          // packets sent at most per pump()
  };

  // Opens a pty pair in raw mode. `body` must outlive the emulator. Error if openpty fails.
  static Result<std::unique_ptr<CreateEmulator>> open(MobileBase& body, const Options& options);
  ~CreateEmulator();
  CreateEmulator(const CreateEmulator&) = delete;
  CreateEmulator& operator=(const CreateEmulator&) = delete;

  const std::string& slavePath() const { return slave_path_; }
  void pump();

  // Fault knobs.
  void setSilent(bool silent) { silent_ = silent; }  // reads and discards, never answers
  void injectGarbage(std::span<const std::uint8_t> bytes);  // written before the next packet
  void corruptNextPackets(int n) { corrupt_ += n > 0 ? n : 0; }
  void setWheelDrops(std::uint8_t bits) { drops_ = bits & io::oi::kDropMask; }

  io::oi::Mode mode() const { return mode_; }
  bool streaming() const { return stream_n_ > 0 && !paused_; }
  std::span<const std::uint8_t> streamIds() const { return {stream_ids_.data(), stream_n_}; }
  const CreateEmulatorCounters& counters() const { return counters_; }
  // Bit `id` set for each unsupported packet id a client has asked for (see the top).
  const std::bitset<256>& unsupportedIds() const { return unsupported_seen_; }
  const Options& options() const { return options_; }
  // The last Drive / Drive Direct as the Create reports it (packets 39..42).
  int requestedVelocity() const { return req_velocity_; }
  int requestedRadius() const { return req_radius_; }
  int requestedRight() const { return req_right_; }
  int requestedLeft() const { return req_left_; }

 private:
  CreateEmulator(MobileBase& body, const Options& options, int master, int slave,
                 std::string path);
  void onByte(std::uint8_t b);
  void execute();
  void applyDrive(double v, double omega);
  void accumulateMotion();
  // Values for `ids`; consumes the distance/angle accumulators if 19/20 are among them.
  io::oi::SensorFrame snapshot(std::span<const std::uint8_t> ids);
  void answerSensors(std::span<const std::uint8_t> ids);
  void sendPacket();
  void noteUnsupported(std::uint8_t id);
  void write(std::span<const std::uint8_t> bytes);
  void enterPassive();

  MobileBase& body_;
  Options options_;
  int master_ = -1;
  int slave_ = -1;  // kept open so the master never sees a hang-up between driver sessions
  std::string slave_path_;

  io::oi::Mode mode_ = io::oi::Mode::kOff;
  std::array<std::uint8_t, 600> cmd_{};  // opcode and data of the command being received
  std::size_t cmd_size_ = 0;
  std::size_t cmd_need_ = 0;  // total bytes of the current command once known

  std::array<std::uint8_t, 255> stream_ids_{};
  std::size_t stream_n_ = 0;
  bool paused_ = false;
  double next_due_ = 0.0;

  Pose2 last_pose_{};
  double dist_acc_mm_ = 0.0;
  double angle_acc_deg_ = 0.0;
  int req_velocity_ = 0, req_radius_ = 0, req_right_ = 0, req_left_ = 0;

  bool silent_ = false;
  int corrupt_ = 0;
  std::uint8_t drops_ = 0;
  std::vector<std::uint8_t> garbage_;  // queued by injectGarbage (test knob; may allocate)
  CreateEmulatorCounters counters_{};
  std::bitset<256> unsupported_seen_{};
};

}  // namespace crunch::sim
