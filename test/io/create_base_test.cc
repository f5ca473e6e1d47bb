// The Create driver (crunch/io/create_base.h) against the Create emulator
// (crunch_sim/create_emulator.h) over a real pseudo-terminal, with a KinematicBase as the body.
// A harness thread plays the robot in real time: it steps the body by the wall-clock time that
// passed and pumps the emulator every millisecond.
#include "crunch/io/create_base.h"

#include <catch2/catch.hpp>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "crunch_sim/create_emulator.h"
#include "crunch_sim/kinematic_base.h"
#include "crunch_sim/world.h"

using namespace crunch;
using crunch::io::CreateBase;
using crunch::sim::CreateEmulator;
using crunch::sim::KinematicBase;
namespace oi = crunch::io::oi;
using Clock = std::chrono::steady_clock;

namespace {

constexpr double kPositionTolerance = 0.01;       // metres: the 1 cm
constexpr double kHeadingTolerance = kPi / 180.0;  // the 1 degree

// The robot: body + emulator, run in real time on their own thread.
class Robot {
 public:
  explicit Robot(const sim::World* world = nullptr, Pose2 start = {},
                 CreateEmulator::Options options = {})
      : body_(world ? KinematicBase(*world, {0.258, 0.5, start})
                    : KinematicBase(KinematicBase::Options{0.258, 0.5, start})) {
    auto emu = CreateEmulator::open(body_, options);
    REQUIRE(emu.ok());
    emu_ = std::move(emu).value();
    thread_ = std::thread([this] { run(); });
  }
  ~Robot() {
    quit_ = true;
    thread_.join();
  }
  const std::string& path() const { return emu_->slavePath(); }
  // Runs f(body, emulator) under the robot's lock.
  template <typename F>
  auto with(F&& f) {
    std::lock_guard lock(mutex_);
    return f(body_, *emu_);
  }

 private:
  void run() {
    auto last = Clock::now();
    while (!quit_) {
      {
        std::lock_guard lock(mutex_);
        const auto now = Clock::now();
        body_.step(std::chrono::duration<double>(now - last).count());
        last = now;
        emu_->pump();
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));  // the robot's own pace
    }
  }
  KinematicBase body_;
  std::unique_ptr<CreateEmulator> emu_;
  std::mutex mutex_;
  std::atomic<bool> quit_{false};
  std::thread thread_;
};

// Polls the driver until `done` holds or `timeout_s` passes; false on timeout.
bool pollUntil(CreateBase& base, double timeout_s, const std::function<bool()>& done) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  while (Clock::now() < deadline) {
    REQUIRE(base.poll(0.01).ok());
    if (done()) return true;
  }
  return false;
}

// The emulated body's wheels are commanded to move (the emulator's side, not the driver's).
bool bodyMoving(Robot& robot) {
  return robot.with([](KinematicBase& b, CreateEmulator&) { return b.commandedV() != 0.0; });
}

// Waits while the body moves, polling nothing (a stalled control loop), at most 2 s; returns the
// seconds waited.
double waitWhileMoving(Robot& robot) {
  const auto t0 = Clock::now();
  while (bodyMoving(robot) && Clock::now() - t0 < std::chrono::seconds(2)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::unique_ptr<CreateBase> openBase(const Robot& robot, CreateBase::Options options = {}) {
  auto base = CreateBase::open(robot.path(), options);
  INFO((base.ok() ? std::string() : base.error().message));
  REQUIRE(base.ok());
  return std::move(base).value();
}

// A base with a 0.2 s watchdog whose robot is driving at 0.2 m/s (the body already moving).
std::unique_ptr<CreateBase> drivingBase(Robot& robot) {
  CreateBase::Options options;
  options.watchdog_s = 0.2;
  auto base = openBase(robot, options);
  REQUIRE(base->drive(0.2, 0.0).ok());
  REQUIRE(pollUntil(*base, 0.1, [&] { return bodyMoving(robot); }));
  return base;
}

// Drive 0.3 m, turn +90 degrees, drive 0.3 m, closed loop on the driver's odometry; then stop
// and wait until the last motion is reported. Optionally calls `during` every loop.
void driveTurnDrive(CreateBase& base, Robot& robot, const std::function<void(int)>& during = {}) {
  int loop = 0;
  const auto step = [&](double v, double omega, const std::function<bool()>& done) {
    REQUIRE(pollUntil(base, 5.0, [&] {
      if (during) during(loop++);
      if (done()) return true;
      REQUIRE(base.drive(v, omega).ok());
      return false;
    }));
  };
  step(0.3, 0.0, [&] { return base.odometry().x >= 0.3; });
  step(0.0, 1.5, [&] { return base.odometry().theta >= kPi / 2 - 0.02; });
  step(0.3, 0.0, [&] { return base.odometry().y >= 0.3; });
  REQUIRE(base.stop().ok());
  // Stopped body, then enough packets that everything it moved has been reported.
  REQUIRE(pollUntil(base, 2.0, [&] {
    return robot.with([](KinematicBase& b, CreateEmulator&) { return b.commandedV() == 0.0; });
  }));
  const std::uint64_t seen = base.sensors().packets();
  REQUIRE(pollUntil(base, 2.0, [&] { return base.sensors().packets() >= seen + 5; }));
}

}  // namespace

TEST_CASE("CreateBase: handshake puts the Create in Safe mode and starts the stream",
          "[io][create][pty]") {
  Robot robot;
  auto base = openBase(robot);
  CHECK(base->sensors().packets() >= 1);
  CHECK(base->device() == robot.path());
  robot.with([](KinematicBase&, CreateEmulator& e) {
    CHECK(e.mode() == oi::Mode::kSafeMode);
    CHECK(e.streaming());
    CHECK(std::vector<std::uint8_t>(e.streamIds().begin(), e.streamIds().end()) ==
          std::vector<std::uint8_t>(oi::kCreateBaseStream.begin(), oi::kCreateBaseStream.end()));
  });
  CHECK(base->sensors().mode() == oi::Mode::kSafeMode);

  Robot robot2;
  CreateBase::Options full;
  full.full_mode = true;
  auto base2 = openBase(robot2, full);
  robot2.with([](KinematicBase&, CreateEmulator& e) { CHECK(e.mode() == oi::Mode::kFullMode); });
}

TEST_CASE("CreateBase: drive reaches the body with the right v and omega, clamped",
          "[io][create][pty]") {
  Robot robot;
  auto base = openBase(robot);
  REQUIRE(base->drive(0.2, 0.5).ok());
  const auto commanded = [&](double v) {
    return robot.with([v](KinematicBase& b, CreateEmulator&) {
      return std::abs(b.commandedV() - v) < 1e-3;
    });
  };
  REQUIRE(pollUntil(*base, 1.0, [&] { return commanded(0.2); }));
  robot.with([](KinematicBase& b, CreateEmulator& e) {
    // Wheels rounded to mm/s: right 265, left 136 (0.2645 / 0.1355 m/s).
    CHECK(b.commandedOmega() == Approx(0.5).margin(0.005));
    CHECK(e.requestedRight() == 265);
    CHECK(e.requestedLeft() == 136);
  });
  REQUIRE(base->drive(1.0, 0.0).ok());  // beyond 0.5 m/s: clamped
  REQUIRE(pollUntil(*base, 1.0, [&] { return commanded(0.5); }));
  CHECK(base->counters().clamped == 1);
  REQUIRE(base->stop().ok());
  REQUIRE(pollUntil(*base, 1.0, [&] { return commanded(0.0); }));
}

TEST_CASE("CreateBase: odometry tracks the true pose over drive-turn-drive, replay identical",
          "[io][create][pty]") {
  Robot robot;
  auto base = openBase(robot);
  std::vector<std::uint8_t> recording;
  // The handshake's bytes are not tapped: start the replay from the tracker's state then.
  const Pose2 at_tap = base->odometry();
  REQUIRE(at_tap.x == 0.0);
  base->setByteTap([&](std::span<const std::uint8_t> b) {
    recording.insert(recording.end(), b.begin(), b.end());
  });
  driveTurnDrive(*base, robot);
  const Pose2 truth = robot.with([](KinematicBase& b, CreateEmulator&) { return b.odometry(); });
  const Pose2 odo = base->odometry();
  const double dpos = std::hypot(odo.x - truth.x, odo.y - truth.y);
  const double dth = std::abs(wrapPi(odo.theta - truth.theta));
  std::printf("create odometry drive-turn-drive: truth (%.4f, %.4f, %.2f deg), odometry "
              "(%.4f, %.4f, %.2f deg), error %.2f mm, %.3f deg, %llu packets\n",
              truth.x, truth.y, truth.theta * 180 / kPi, odo.x, odo.y, odo.theta * 180 / kPi,
              dpos * 1000, dth * 180 / kPi,
              static_cast<unsigned long long>(base->sensors().packets()));
  CHECK(dpos < kPositionTolerance);
  CHECK(dth < kHeadingTolerance);
  CHECK(truth.y > 0.25);  // it really went round the corner

  // Offline replay of the recorded bytes through the same code: the identical odometry, once
  // the packets the handshake read (before the tap) are accounted for: they carried no motion.
  oi::SensorTracker replay(oi::StreamParserOptions{true, 10});
  replay.feed(recording);
  CHECK(replay.odometry().x == odo.x);
  CHECK(replay.odometry().y == odo.y);
  CHECK(replay.odometry().theta == odo.theta);
}

TEST_CASE("CreateBase: a bump stops the motors from inside the driver", "[io][create][pty]") {
  Scene scene;  // 4 x 4 m arena, walled
  auto world = sim::World::build(scene);
  // 0.2 m from the east wall's collision point (x = 4 - robot radius).
  Robot robot(world.get(), Pose2{3.635 - 0.2, 2.0, 0.0});
  auto base = openBase(robot);
  REQUIRE(pollUntil(*base, 5.0, [&] {
    REQUIRE(base->drive(0.3, 0.0).ok());
    return base->bumped();
  }));
  // Keep commanding forward, as a careless behaviour would: the driver must hold the body.
  REQUIRE(pollUntil(*base, 1.0, [&] {
    REQUIRE(base->drive(0.3, 0.0).ok());
    return robot.with([](KinematicBase& b, CreateEmulator&) { return b.commandedV() == 0.0; });
  }));
  CHECK(base->counters().safety_stops >= 1);
  CHECK(base->counters().refused_forward >= 1);
  // Backing off is allowed.
  REQUIRE(base->drive(-0.1, 0.0).ok());
  REQUIRE(pollUntil(*base, 1.0, [&] {
    return robot.with(
        [](KinematicBase& b, CreateEmulator&) { return std::abs(b.commandedV() + 0.1) < 1e-3; });
  }));
  REQUIRE(pollUntil(*base, 2.0, [&] { return !base->bumped(); }));
  CHECK(base->bumper() == Bumper::kReleased);
}

TEST_CASE("CreateBase: the bumper's switches arrive as packet 7's bits", "[io][create][pty]") {
  // Head on into the east wall closes both switches; driving at it 60 degrees to the left of
  // the wall's normal, the wall is met at the body's right: the right switch only.
  Scene scene;  // 4 x 4 m arena, walled
  auto world = sim::World::build(scene);
  for (const double heading : {0.0, kPi / 3}) {
    Robot robot(world.get(), Pose2{3.635 - 0.05, 2.0, heading});
    auto base = openBase(robot);
    REQUIRE(pollUntil(*base, 5.0, [&] {
      REQUIRE(base->drive(0.2, 0.0).ok());
      return base->bumped();
    }));
    CHECK(base->bumper() == (heading == 0.0 ? Bumper::kBoth : Bumper::kRight));
    CHECK((base->sensors().bumpsAndDrops() & oi::kDropMask) == 0);
  }
}

TEST_CASE("CreateBase: the watchdog stops a stalled control loop", "[io][create][pty]") {
  Robot robot;
  auto base = drivingBase(robot);
  // Stall: no poll(), no drive(). Wait on the condition with a bounded deadline.
  const double waited = waitWhileMoving(robot);
  std::printf("create watchdog: stopped %.3f s after the loop stalled (watchdog_s 0.2)\n", waited);
  CHECK_FALSE(bodyMoving(robot));
  CHECK(base->watchdogStops() == 1);
  CHECK(waited > 0.15);  // not before the stall limit (the last poll may predate stalled_at)
  CHECK(waited < 0.6);
}

TEST_CASE("CreateBase: stopAndDisarm stops the motors and ends the watchdog", "[io][create][pty]") {
  // After the run (crunchhost --robot's shut-down) the final inference polls nothing for
  // seconds; the robot is already stopped, and that is not a stalled control loop.
  Robot robot;
  auto base = drivingBase(robot);
  REQUIRE(base->stopAndDisarm().ok());
  (void)waitWhileMoving(robot);
  CHECK_FALSE(bodyMoving(robot));
  // Three watchdog periods without a poll or a command: nothing counted.
  std::this_thread::sleep_for(std::chrono::milliseconds(600));
  CHECK(base->watchdogStops() == 0);
  CHECK(base->stopAndDisarm().ok());  // twice is harmless
}

TEST_CASE("CreateBase: a Create that never answers gives a clear error in bounded time",
          "[io][create][pty]") {
  Robot robot;
  robot.with([](KinematicBase&, CreateEmulator& e) { e.setSilent(true); });
  CreateBase::Options options;
  options.answer_timeout_s = 0.5;
  const auto t0 = Clock::now();
  auto base = CreateBase::open(robot.path(), options);
  const double took = std::chrono::duration<double>(Clock::now() - t0).count();
  REQUIRE_FALSE(base.ok());
  const std::string& msg = base.error().message;
  INFO(msg);
  CHECK(msg.find("Create on " + robot.path() + " did not answer within 0.5 s") != std::string::npos);
  CHECK(msg.find("baud rate 57600") != std::string::npos);
  CHECK(took < options.answer_timeout_s + 0.5);
}

TEST_CASE("CreateBase: a stream that stops gives an error naming the device", "[io][create][pty]") {
  Robot robot;
  CreateBase::Options options;
  options.stream_timeout_s = 0.2;
  auto base = openBase(robot, options);
  robot.with([](KinematicBase&, CreateEmulator& e) { e.setSilent(true); });
  const auto t0 = Clock::now();
  Status s = okStatus();
  while (s.ok() && Clock::now() - t0 < std::chrono::seconds(2)) s = base->poll(0.01);
  REQUIRE_FALSE(s.ok());
  INFO(s.error().message);
  CHECK(s.error().message.find(robot.path()) != std::string::npos);
  CHECK(s.error().message.find("no valid sensor packet") != std::string::npos);
}

TEST_CASE("CreateBase: serial garbage and corrupt packets are counted, odometry stays right",
          "[io][create][pty]") {
  Robot robot;
  auto base = openBase(robot);
  const std::vector<std::uint8_t> junk = {19, 10, 7, 0, 19, 0xFF, 0x13, 19, 19, 0x80, 0x00};
  int corrupted = 0;
  driveTurnDrive(*base, robot, [&](int loop) {
    if (loop % 15 == 0) robot.with([&](KinematicBase&, CreateEmulator& e) { e.injectGarbage(junk); });
    if (loop % 40 == 20 && corrupted < 3) {
      robot.with([](KinematicBase&, CreateEmulator& e) { e.corruptNextPackets(1); });
      ++corrupted;
    }
  });
  const auto emu = robot.with([](KinematicBase&, CreateEmulator& e) { return e.counters(); });
  const Pose2 truth = robot.with([](KinematicBase& b, CreateEmulator&) { return b.odometry(); });
  const auto c = base->sensors().counters().stream;
  std::printf("create garbage: %llu garbage bytes sent, %llu skipped; %llu packets corrupted, "
              "%llu checksum failures, %llu malformed\n",
              static_cast<unsigned long long>(emu.garbage_bytes_sent),
              static_cast<unsigned long long>(c.skipped_bytes),
              static_cast<unsigned long long>(emu.corrupted_packets),
              static_cast<unsigned long long>(c.checksum_failures),
              static_cast<unsigned long long>(c.bad_length_or_id));
  REQUIRE(emu.garbage_bytes_sent > 0);
  CHECK(c.skipped_bytes >= emu.garbage_bytes_sent);
  CHECK(c.checksum_failures >= emu.corrupted_packets);
  CHECK(c.packets + emu.corrupted_packets >= emu.packets_sent - 2);  // at most in flight
  // Garbage costs no packet; a corrupt packet loses the motion it carried (the Create reset its
  // counters when it sent it): at most one period at 0.3 m/s or 1.5 rad/s each.
  const double lost_pos = static_cast<double>(emu.corrupted_packets) * 0.3 * oi::kStreamPeriod;
  const double lost_th = static_cast<double>(emu.corrupted_packets) * 1.5 * oi::kStreamPeriod;
  const Pose2 odo = base->odometry();
  const double dpos = std::hypot(odo.x - truth.x, odo.y - truth.y);
  const double dth = std::abs(wrapPi(odo.theta - truth.theta));
  std::printf("create garbage odometry error: %.2f mm, %.3f deg (allowance for lost packets "
              "%.1f mm, %.2f deg)\n", dpos * 1000, dth * 180 / kPi, lost_pos * 1000,
              lost_th * 180 / kPi);
  CHECK(dpos < kPositionTolerance + lost_pos * 1.5 + lost_th * 0.3);
  CHECK(dth < kHeadingTolerance + lost_th);
}

TEST_CASE("CreateBase: missing device and non-serial paths give actionable errors",
          "[io][create]") {
  auto missing = CreateBase::open("/dev/ttyUSB_crunch_missing", {});
  REQUIRE_FALSE(missing.ok());
  CHECK(missing.error().message.find("/dev/ttyUSB_crunch_missing") != std::string::npos);
  CHECK(missing.error().message.find("no such device") != std::string::npos);
  CHECK(missing.error().message.find("ls /dev/ttyUSB*") != std::string::npos);
  auto not_tty = CreateBase::open("/dev/null", {});
  REQUIRE_FALSE(not_tty.ok());
  CHECK(not_tty.error().message.find("not a tty") != std::string::npos);
  CreateBase::Options bad_baud;
  bad_baud.baud = 12345;
  auto baud = CreateBase::open("/dev/null", bad_baud);
  REQUIRE_FALSE(baud.ok());
  CHECK(baud.error().message.find("unsupported baud rate 12345") != std::string::npos);
}
