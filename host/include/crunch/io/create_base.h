// The iRobot Create as a MobileBase (paper §2.3): the Open Interface driver of `--robot`, and,
// through the pty emulator (sim/create_emulator.h), of tests and of the simulator's base.
//
// open(): opens the serial port (io/serial_port.h), sends Start, Safe (or Full), and Stream
// [7 bumps/wheel drops, 19 distance, 20 angle, 35 OI mode] (io/create_oi.h), then waits for the
// first VALID stream packet; a Create that never answers gives an Error within
// answer_timeout_s (plus one write timeout at most).
//
// drive(v, omega): sent as Drive Direct, right/left wheel = v +- omega b/2, both scaled down by
// one factor when a wheel would exceed 500 mm/s (the path's curvature is kept, the speed drops),
// rounded to mm/s (oi::twistToWheels; oi::twistToDrive says why not Drive). Non-finite input
// stops. Safety, in the driver and not only in the behaviour:
//   - poll() sends a stop itself as soon as a packet shows a bumper or wheel drop;
//   - while a bumper is pressed, drive() refuses forward motion (v > 0 becomes 0: backing off
//     and turning in place stay allowed); while a wheel is dropped, every motion becomes a stop;
//   - a watchdog thread sends a stop when neither poll() nor drive() has been called for
//     watchdog_s (a stalled control loop), once per stall, and counts it;
//   - drive() returns an Error when the Create reports Passive mode (it left Safe mode after a
//     cliff, wheel drop or charger): call resume() to re-enter Safe/Full.
// odometry() integrates the streamed distance and angle (oi::SensorTracker: whole degrees, the
// remainder is the Create's business, see oi::Odometry). setByteTap() sees every byte read, so
// a recording replayed into a SensorTracker gives the identical odometry.
//
// Thread-safety: one control thread calls everything except the constructor-started watchdog;
// serial writes from both go through one mutex. Allocation: poll() reads into a fixed buffer;
// the parser never allocates (the byte tap's std::function is the caller's).
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>

#include "crunch/robot/mobile_base.h"
#include "crunch/io/create_oi.h"
#include "crunch/io/serial_port.h"

namespace crunch::io {

struct CreateBaseCounters {
  std::uint64_t bytes_read = 0;
  std::uint64_t commands_sent = 0;   // drive commands written (incl. safety stops)
  std::uint64_t safety_stops = 0;    // stops poll() sent on a bump or wheel drop
  std::uint64_t refused_forward = 0; // drive() calls whose forward part a bumper refused
  std::uint64_t clamped = 0;         // drive() calls scaled down to the wheel limit
  // Stops the watchdog sent are counted apart: CreateBase::watchdogStops().
};

class CreateBase final : public MobileBase {
 public:
  struct Options {
    double answer_timeout_s = 1.0;  // open(): first valid packet within this
    double stream_timeout_s = 0.5;  // poll(): Error when no valid packet for this long
    double watchdog_s = 0.5;        // stop when neither poll() nor drive() for this long
    bool full_mode = false;         // Safe by default (the Create stops itself on cliffs/drops)
    bool checksum_includes_header = true;  // the Create 1's checksum quirk (create_oi.h)
    int baud = 57600;
    double wheel_base = 0.258;  // metres
    double write_timeout_s = 0.2;  // one command write
  };

  static Result<std::unique_ptr<CreateBase>> open(const std::string& device,
                                                  const Options& options);
  // Stops the watchdog, stops the motors, pauses the stream, closes the port.
  ~CreateBase() override;
  CreateBase(const CreateBase&) = delete;
  CreateBase& operator=(const CreateBase&) = delete;

  Status drive(double v, double omega) override;
  Pose2 odometry() const override { return tracker_.odometry(); }
  bool bumped() const override { return tracker_.bumped(); }
  Bumper bumper() const override {
    return static_cast<Bumper>(tracker_.bumpsAndDrops() & oi::kBumpMask);
  }
  // Seconds since open() (steady clock).
  double now() const override;

  // Reads what the port has, waiting at most timeout_s for the first bytes, feeds the tracker
  // and the byte tap, and sends a stop on a new bump or wheel drop. Error naming the device when
  // the port fails or no valid packet arrived for stream_timeout_s.
  Status poll(double timeout_s);
  // Re-sends Safe (or Full) after the Create fell back to Passive, e.g. after a wheel drop.
  Status resume();

  void setByteTap(std::function<void(std::span<const std::uint8_t>)> tap) { tap_ = std::move(tap); }

  const oi::SensorTracker& sensors() const { return tracker_; }
  const CreateBaseCounters& counters() const { return counters_; }
  std::uint64_t watchdogStops() const { return watchdog_stops_.load(); }
  // The run is over: stops the motors and ends the watchdog, so the work after the run (the
  // final map's inference, which polls nothing) is not counted as a stalled loop. Later
  // commands still reach the Create, unwatched.
  Status stopAndDisarm();
  const std::string& device() const { return port_.device(); }
  const Options& options() const { return options_; }

 private:
  using Clock = std::chrono::steady_clock;
  CreateBase(SerialPort port, const Options& options);
  Status send(std::span<const std::uint8_t> bytes);
  Status sendWheels(int right_mm_s, int left_mm_s);
  Status readAvailable(double timeout_s, bool* got_packet);
  void touch() { last_activity_ns_.store(Clock::now().time_since_epoch().count()); }
  void watchdogLoop();

  Options options_;
  SerialPort port_;
  oi::SensorTracker tracker_;
  std::function<void(std::span<const std::uint8_t>)> tap_;
  Clock::time_point opened_;
  Clock::time_point last_packet_;
  CreateBaseCounters counters_;
  bool stopped_for_bump_ = false;

  std::mutex write_mutex_;
  std::atomic<Clock::rep> last_activity_ns_{0};
  std::atomic<std::uint64_t> watchdog_stops_{0};
  std::mutex watchdog_mutex_;
  std::condition_variable watchdog_cv_;
  bool quit_ = false;  // under watchdog_mutex_
  std::thread watchdog_;
};

}  // namespace crunch::io
