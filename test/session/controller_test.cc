// RobotController (session/controller.h) driving a simulated base with synthetic bridge chunks:
// four virtual whisker boards (the firmware core) behind Hall models whose deflections the test
// sets, the chunks queued as the SPSC ring would hold them, a kinematic base on an open floor.
// The hil tests run the same controller through real USB and a pty Create; these run in process
// and under the sanitizers.
#include "crunch/session/controller.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "crunch/io/recording.h"
#include "crunch/session/session_settings.h"
#include "crunch/signal/models_io.h"
#include "crunch_sim/hall_model.h"
#include "crunch_sim/kinematic_base.h"
#include "crunch_sim/virtual_whisker_board.h"
#include "support/temp_dir.h"

namespace {

using namespace crunch;
using session::RobotController;

struct Command {
  double t, v, omega;
};

// The robot as the controller sees it. One poll() is 1 ms: two 500 us ticks of every board into
// one bridge chunk (none while unplugged or unpowered), the base moved along.
class FakeRobot final : public MobileBase {
 public:
  explicit FakeRobot(double hall_noise_codes = 4.0) : hall_(hallOptions(hall_noise_codes)) {
    for (int w = 0; w < 4; ++w) {
      boards_.push_back(std::make_unique<sim::VirtualWhiskerBoard>(static_cast<std::uint8_t>(w)));
    }
  }

  Status drive(double v, double omega) override {
    commands.push_back({now(), v, omega});
    return base.drive(v, omega);
  }
  Pose2 odometry() const override { return base.odometry(); }
  bool bumped() const override { return base.bumped(); }
  Bumper bumper() const override { return base.bumper(); }
  double now() const override { return base.now(); }

  Status poll(double /*timeout_s*/) {
    bytes_.clear();
    for (int tick = 0; tick < 2; ++tick) {
      for (int w = 0; w < 4; ++w) {
        const sim::HallCodes c = hall_.sample(deflection[w], 0.0, rng_);
        boards_[w]->sensor().setReading(c.alpha, c.beta);
        const auto out = boards_[w]->tick();
        if (plugged && powered) bytes_.insert(bytes_.end(), out.begin(), out.end());
      }
      base.step(0.0005);
    }
    t_ns_ += 1000000;
    if (!bytes_.empty()) {
      queue_.emplace_back();
      queue_.back().assign(io::StreamId::kBridge, t_ns_, bytes_);
    }
    return okStatus();
  }
  void drain(const std::function<void(const io::Chunk&)>& sink) {
    for (const io::Chunk& c : queue_) sink(c);
    queue_.clear();
  }
  std::uint64_t clockNs() const { return t_ns_; }

  sim::KinematicBase base;
  double deflection[4] = {0.0, 0.0, 0.0, 0.0};  // radians, in-plane, per whisker
  bool plugged = true;                          // the bridge's USB link
  bool powered = true;                          // the whisker boards
  std::vector<Command> commands;

 private:
  static sim::HallSensorModel::Options hallOptions(double noise) {
    sim::HallSensorModel::Options o;
    o.noise_codes = noise;
    return o;
  }
  sim::HallSensorModel hall_;
  Rng rng_{7};
  std::vector<std::unique_ptr<sim::VirtualWhiskerBoard>> boards_;
  std::vector<std::uint8_t> bytes_;
  std::deque<io::Chunk> queue_;
  std::uint64_t t_ns_ = 1;
};

session::RobotSessionOptions sessionOptions() {
  auto models = signal::loadModels(std::string(CRUNCH_SOURCE_DIR) + "/models/sim_models.json");
  REQUIRE(models);
  MappingOptions m;
  m.global_chains = 2;
  session::RobotSessionOptions s = session::sessionOptions(models.value(), m, 3);
  s.start = {1.5, 1.5, 0.0};
  s.area_hi = {3.0, 3.0};
  return s;
}

// A robot, its session and a controller wired to them as `crunchhost --robot` wires the devices.
struct Rig {
  explicit Rig(session::ControllerOptions options = {}, double hall_noise_codes = 4.0)
      : robot(hall_noise_codes) {
    auto created = session::RobotSession::create(sessionOptions());
    REQUIRE(created);
    session = std::move(created).value();
    session::ControllerSources sources;
    sources.poll_base = [this](double t) { return robot.poll(t); };
    sources.drain_bridge = [this](const auto& sink) { robot.drain(sink); };
    sources.link = &link;
    sources.watchdog_stops = [this] { return watchdog_stops; };
    sources.map = [this](Map) { ++maps; };
    sources.clock_ns = [this] { return robot.clockNs(); };
    auto made = RobotController::create(
        robot, *session, options, std::move(sources),
        [this](const session::ControllerEvent& e) { events.push_back(e.name); });
    REQUIRE(made);
    controller = std::move(made).value();
  }

  // Steps until `done` or the run ends, at most `seconds` of base time. The value of done().
  template <typename F>
  bool stepUntil(F done, double seconds) {
    const double until = robot.now() + seconds;
    while (robot.now() < until) {
      if (done()) return true;
      if (!controller->step()) return done();
    }
    return done();
  }
  // Steps for `seconds` of base time; false if the run ended before.
  bool runFor(double seconds) {
    const double until = robot.now() + seconds;
    while (robot.now() < until) {
      if (!controller->step()) return false;
    }
    return true;
  }

  FakeRobot robot;
  session::LinkMonitor link;
  std::uint64_t watchdog_stops = 0;
  int maps = 0;
  std::vector<std::string> events;
  std::unique_ptr<session::RobotSession> session;
  std::unique_ptr<RobotController> controller;
};

using Stage = RobotController::Stage;

}  // namespace

TEST_CASE("RobotController: calibrates, then roams forward", "[session]") {
  Rig rig;
  rig.controller->start("test robot");
  CHECK(rig.controller->stage() == Stage::kCalibrating);
  REQUIRE(rig.stepUntil([&] { return rig.controller->stage() == Stage::kRoaming; }, 3.0));
  CHECK(rig.session->calibrated());
  CHECK(rig.events == std::vector<std::string>{"start", "roaming"});
  REQUIRE(rig.robot.commands.size() == 1);  // nothing was sent while calibrating
  CHECK(rig.robot.commands[0].v > 0.0);
  CHECK(rig.robot.commands[0].omega == 0.0);
}

TEST_CASE("RobotController: no whisker samples within the calibration timeout is an error",
          "[session]") {
  session::ControllerOptions o;
  o.calibrate_timeout_s = 0.5;
  o.bridge = "the whisker bridge 1209:0001";
  Rig rig(o);
  rig.robot.powered = false;
  rig.controller->start("test robot");
  CHECK_FALSE(rig.runFor(2.0));
  CHECK(rig.controller->stage() == Stage::kStopped);
  CHECK(rig.controller->stopReason() == "whiskers not calibrated");
  REQUIRE_FALSE(rig.controller->failure());
  CHECK(rig.controller->failure().error().message.find(
            "the whisker bridge 1209:0001 sent no whisker samples within 0.5") !=
        std::string::npos);
  CHECK(rig.robot.now() == Approx(0.5).margin(0.01));
  CHECK(rig.robot.commands.empty());  // never moved
}

TEST_CASE("RobotController: whiskers that will not settle are a calibration error", "[session]") {
  session::ControllerOptions o;
  o.calibrate_timeout_s = 2.0;
  Rig rig(o, /*hall_noise_codes=*/3000.0);
  rig.controller->start("test robot");
  CHECK_FALSE(rig.runFor(4.0));
  REQUIRE_FALSE(rig.controller->failure());
  CHECK(rig.controller->failure().error().message.find("did not calibrate at rest") !=
        std::string::npos);
  CHECK(rig.robot.commands.empty());
}

TEST_CASE("RobotController: a contact starts a body whisk with start and end marks", "[session]") {
  TempDir dir;
  auto writer = io::RecordingWriter::create(dir.file("run.crec"), "{}");
  REQUIRE(writer);
  session::ControllerOptions o;
  o.map_every_s = 1.0;
  Rig rig(o);
  rig.session->setRecorder(writer.value().get());
  rig.controller->start("test robot");
  REQUIRE(rig.stepUntil([&] { return rig.controller->stage() == Stage::kRoaming; }, 3.0));
  REQUIRE(rig.runFor(0.3));
  const double roam_start = rig.robot.commands.back().t;

  // Whisker 0 (the rightmost, -33.75 degrees) presses on something until the away leg.
  rig.robot.deflection[0] = 0.05;
  const BodyWhisk& whisk = rig.controller->whisk();
  REQUIRE(rig.stepUntil([&] { return whisk.phase() == BodyWhisk::Phase::kAway; }, 3.0));
  rig.robot.deflection[0] = 0.0;
  REQUIRE(rig.stepUntil([&] { return whisk.phase() == BodyWhisk::Phase::kTurn; }, 10.0));
  REQUIRE(writer.value()->close());

  CHECK(rig.session->counts().whisks == 1);
  CHECK(rig.events == std::vector<std::string>{"start", "roaming", "contact", "whisk"});
  CHECK(rig.maps >= 8);  // one snapshot a second
  // The commands: forward; then, with no reverse before the sweep, clockwise toward the object
  // on the right at pi/24 rad/s, counter-clockwise away, reversing clear, the random turn.
  std::vector<Command> after;
  for (const Command& c : rig.robot.commands) {
    if (c.t > roam_start) after.push_back(c);
  }
  REQUIRE(after.size() >= 4);
  CHECK(after[0].v == 0.0);
  CHECK(after[0].omega == Approx(-kPi / 24));
  CHECK(after[1].v == 0.0);
  CHECK(after[1].omega == Approx(kPi / 24));
  CHECK(after[2].v < 0.0);
  CHECK(after[3].omega != 0.0);

  // The recording holds the whisk-start mark, then the whisk-end mark, and no other.
  auto reader = io::RecordingReader::open(dir.file("run.crec"));
  REQUIRE(reader);
  io::Chunk chunk;
  std::vector<int> marks;
  while (reader.value()->next(chunk) == io::RecordingReader::Next::kRecord) {
    if (chunk.stream == io::StreamId::kMark) marks.push_back(chunk.bytes[0]);
  }
  CHECK(marks == std::vector<int>{static_cast<int>(io::MarkKind::kWhiskStart),
                                  static_cast<int>(io::MarkKind::kWhiskEnd)});
}

TEST_CASE("RobotController: the bridge lost pauses the robot, back, it roams again", "[session]") {
  Rig rig;
  rig.controller->start("test robot");
  REQUIRE(rig.stepUntil([&] { return rig.controller->stage() == Stage::kRoaming; }, 3.0));
  REQUIRE(rig.runFor(0.2));

  rig.robot.plugged = false;
  rig.link.report(false, "whisker bridge unplugged");
  REQUIRE(rig.controller->step());
  CHECK(rig.controller->stage() == Stage::kPaused);
  CHECK(rig.events.back() == "bridge_lost");
  CHECK(rig.robot.commands.back().v == 0.0);
  CHECK(rig.robot.commands.back().omega == 0.0);
  const Pose2 stopped = rig.robot.odometry();
  const std::size_t sent = rig.robot.commands.size();
  REQUIRE(rig.runFor(1.0));
  CHECK(rig.robot.commands.size() == sent);  // waits without a command
  CHECK(rig.robot.odometry().x == stopped.x);

  rig.robot.plugged = true;
  rig.link.report(true, "whisker bridge back");
  REQUIRE(rig.controller->step());
  // The session forgets partial frames (a mark); the detectors kept their rest, so the robot
  // goes on at once (they would calibrate first if they had lost it).
  CHECK(rig.session->counts().marks == 1);  // kBridgeReconnected
  REQUIRE(rig.events.size() >= 2);
  CHECK(rig.events[rig.events.size() - 2] == "bridge_back");
  CHECK(rig.events.back() == "roaming");
  CHECK(rig.controller->stage() == Stage::kRoaming);
  CHECK(rig.robot.commands.back().v > 0.0);
  REQUIRE(rig.runFor(0.5));
  CHECK(rig.robot.odometry().x > stopped.x + 0.04);
  CHECK(rig.controller->failure());
}

TEST_CASE("RobotController: a watchdog stop is reported and the command sent again", "[session]") {
  Rig rig;
  rig.controller->start("test robot");
  REQUIRE(rig.stepUntil([&] { return rig.controller->stage() == Stage::kRoaming; }, 3.0));
  const std::size_t sent = rig.robot.commands.size();
  rig.watchdog_stops = 1;
  REQUIRE(rig.controller->step());
  CHECK(rig.events.back() == "watchdog");
  REQUIRE(rig.controller->step());
  REQUIRE(rig.robot.commands.size() == sent + 1);
  CHECK(rig.robot.commands.back().v == rig.robot.commands[sent - 1].v);
}

TEST_CASE("RobotController: the run ends at its duration or when stopped", "[session]") {
  session::ControllerOptions o;
  o.duration_s = 0.25;
  Rig rig(o);
  rig.controller->start("test robot");
  CHECK_FALSE(rig.runFor(1.0));
  CHECK(rig.controller->stopReason() == "--duration reached");
  CHECK(rig.robot.now() == Approx(0.25).margin(0.002));
  CHECK(rig.controller->failure());

  Rig other;
  other.controller->start("test robot");
  other.controller->stop("stopped by SIGINT");
  CHECK_FALSE(other.controller->step());
  CHECK(other.controller->stopReason() == "stopped by SIGINT");
}

TEST_CASE("RobotController: bad options are an error naming the field", "[session]") {
  sim::KinematicBase base;
  auto created = session::RobotSession::create(sessionOptions());
  REQUIRE(created);
  auto make = [&](const session::ControllerOptions& o) {
    return RobotController::create(base, *created.value(), o, {}, {});
  };
  session::ControllerOptions o;
  o.map_every_s = 0.0;
  auto r = make(o);
  REQUIRE_FALSE(r);
  CHECK(r.error().message.find("map_every_s") != std::string::npos);
  o = {};
  o.calibrate_timeout_s = std::nan("");
  r = make(o);
  REQUIRE_FALSE(r);
  CHECK(r.error().message.find("calibrate_timeout_s") != std::string::npos);
  o = {};
  o.whisk.whisk_rate = -1.0;
  r = make(o);
  REQUIRE_FALSE(r);
  CHECK(r.error().message.find("whisk: ") != std::string::npos);
}

TEST_CASE("LinkMonitor: reports between two takes are seen once, the newest", "[session]") {
  session::LinkMonitor link;
  CHECK_FALSE(link.take());
  link.report(false, "gone");
  link.report(true, "back");
  auto e = link.take();
  REQUIRE(e);
  CHECK(e->up);
  CHECK(e->message == "back");
  CHECK_FALSE(link.take());
}
