// The Create emulator alone (crunch_sim/create_emulator.h): command parsing, modes, sensors,
// stream timing on the body's clock, its quirks and fault knobs. The test talks to it through
// the pty's slave side with io::SerialPort, as the driver does, and steps a KinematicBase.
#include "crunch_sim/create_emulator.h"

#include <catch2/catch.hpp>

#include <chrono>
#include <thread>
#include <vector>

#include "crunch/io/serial_port.h"
#include "crunch_sim/kinematic_base.h"

using namespace crunch;
using crunch::sim::CreateEmulator;
using crunch::sim::KinematicBase;
namespace oi = crunch::io::oi;

namespace {

struct Bench {
  KinematicBase body;
  std::unique_ptr<CreateEmulator> emu;
  std::unique_ptr<io::SerialPort> port;

  explicit Bench(CreateEmulator::Options options = {}) {
    auto e = CreateEmulator::open(body, options);
    REQUIRE(e.ok());
    emu = std::move(e).value();
    auto p = io::SerialPort::open(emu->slavePath());
    REQUIRE(p.ok());
    port = std::make_unique<io::SerialPort>(std::move(p).value());
  }
  void send(std::vector<std::uint8_t> bytes) {
    REQUIRE(port->writeAll(bytes, 1.0).ok());
    // The bytes cross the tty layer asynchronously: pump until the emulator has them all.
    const std::uint64_t want = emu->counters().bytes_received + bytes.size();
    for (int i = 0; i < 2000 && emu->counters().bytes_received < want; ++i) {
      emu->pump();
      if (emu->counters().bytes_received < want) {
        std::this_thread::sleep_for(std::chrono::microseconds(200));  // bounded: 2000 rounds
      }
    }
    REQUIRE(emu->counters().bytes_received == want);
  }
  // Reads what arrives within `timeout_s` of quiet.
  std::vector<std::uint8_t> receive(double timeout_s = 0.05) {
    std::vector<std::uint8_t> out;
    std::array<std::uint8_t, 512> buf{};
    for (;;) {
      auto r = port->read(buf, timeout_s);
      REQUIRE(r.ok());
      if (r.value() == 0) return out;
      out.insert(out.end(), buf.begin(), buf.begin() + static_cast<long>(r.value()));
    }
  }
  // Steps the body for `seconds` in 1 ms steps, pumping after each.
  void run(double seconds) {
    const int steps = static_cast<int>(std::lround(seconds / 0.001));
    for (int i = 0; i < steps; ++i) {
      body.step(0.001);
      emu->pump();
    }
  }
};

std::vector<std::uint8_t> bytes(std::span<const std::uint8_t> s) { return {s.begin(), s.end()}; }

}  // namespace

TEST_CASE("Create emulator: modes gate the drive commands", "[sim][create]") {
  Bench b;
  b.send({oi::kSafe});  // before Start: ignored
  CHECK(b.emu->mode() == oi::Mode::kOff);
  b.send({oi::kStart});
  CHECK(b.emu->mode() == oi::Mode::kPassive);
  b.send(bytes(oi::drive(200, oi::kRadiusStraight)));  // Passive: ignored
  CHECK(b.body.commandedV() == 0.0);
  b.send({oi::kSafe});
  CHECK(b.emu->mode() == oi::Mode::kSafeMode);
  b.send(bytes(oi::drive(200, oi::kRadiusStraight)));
  CHECK(b.body.commandedV() == Approx(0.2));
  CHECK(b.body.commandedOmega() == 0.0);
  b.send(bytes(oi::drive(129, 1)));  // turn in place counter-clockwise
  CHECK(b.body.commandedV() == Approx(0.0).margin(1e-12));
  CHECK(b.body.commandedOmega() == Approx(0.129 / 0.129));
  b.send(bytes(oi::drive(129, -1)));
  CHECK(b.body.commandedOmega() == Approx(-1.0));
  b.send(bytes(oi::drive(-200, 500)));
  CHECK(b.body.commandedV() == Approx(-0.2));
  CHECK(b.body.commandedOmega() == Approx(-0.4));
  CHECK(b.emu->requestedRadius() == 500);
  b.send(bytes(oi::driveDirect(300, 100)));
  CHECK(b.body.commandedV() == Approx(0.2));
  CHECK(b.body.commandedOmega() == Approx(0.2 / 0.258));
  b.send({oi::kFull});
  CHECK(b.emu->mode() == oi::Mode::kFullMode);
  b.send({oi::kStart});  // back to Passive stops the motors
  CHECK(b.body.commandedV() == 0.0);
  // Bytes that are no opcode are skipped; LEDs (3 data bytes) parsed and ignored.
  const auto unknown = b.emu->counters().unknown_bytes;
  b.send({5, 200, 139, 131, 131, 131, oi::kSafe});
  CHECK(b.emu->counters().unknown_bytes == unknown + 2);
  CHECK(b.emu->mode() == oi::Mode::kSafeMode);  // the 131s inside the LED command were data
}

TEST_CASE("Create emulator: Sensors and Query List answer with data bytes", "[sim][create]") {
  Bench b;
  b.send({oi::kStart, oi::kSafe});
  b.receive();
  b.send(bytes(oi::sensors(oi::kOiMode)));
  CHECK(b.receive() == std::vector<std::uint8_t>{2});
  b.send(bytes(oi::sensors(2)));  // group 2: packets 17..20, 6 bytes
  CHECK(b.receive().size() == 6);
  b.send(bytes(oi::sensors(6)));  // everything: 52 bytes
  CHECK(b.receive().size() == 52);
  b.send(bytes(oi::drive(200, oi::kRadiusStraight)));
  b.run(0.5);
  const std::array<std::uint8_t, 2> ids = {oi::kDistance, oi::kBumpsWheelDrops};
  b.send(bytes(oi::queryList(ids).span()));
  const auto answer = b.receive();
  REQUIRE(answer.size() == 3);
  const int distance = static_cast<std::int16_t>((answer[0] << 8) | answer[1]);
  CHECK(std::abs(distance - 100) <= 1);  // 0.2 m/s for 0.5 s
  CHECK(answer[2] == 0);
  b.send(bytes(oi::sensors(oi::kDistance)));  // read resets: nothing travelled since
  const auto again = b.receive();
  REQUIRE(again.size() == 2);
  CHECK(std::abs(static_cast<std::int16_t>((again[0] << 8) | again[1])) <= 1);
}

TEST_CASE("Create emulator: a stream packet every 15 ms of the body's clock, pausable",
          "[sim][create]") {
  Bench b;
  b.send({oi::kStart, oi::kSafe});
  b.send(bytes(oi::stream(oi::kCreateBaseStream).span()));
  b.run(0.3);  // packets at 0, 15, ..., 300 ms (the last one within float rounding)
  const auto sent = b.emu->counters().packets_sent;
  CHECK(sent >= 20);
  CHECK(sent <= 21);
  oi::SensorTracker tracker(oi::StreamParserOptions{true, 10});
  tracker.feed(b.receive());
  CHECK(tracker.packets() == sent);
  CHECK(tracker.counters().stream.skipped_bytes == 0);
  b.send(bytes(oi::pauseResume(false)));
  const auto paused_at = b.emu->counters().packets_sent;
  b.run(0.1);
  CHECK(b.emu->counters().packets_sent == paused_at);
  b.send(bytes(oi::pauseResume(true)));
  b.run(0.1);
  CHECK(b.emu->counters().packets_sent >= paused_at + 6);
}

TEST_CASE("Create emulator: distance and angle, with the angle remainder carried or dropped",
          "[sim][create]") {
  for (const bool drop : {false, true}) {
    CreateEmulator::Options options;
    options.drop_angle_remainder = drop;
    Bench b(options);
    b.send({oi::kStart, oi::kSafe});
    b.send(bytes(oi::stream(oi::kCreateBaseStream).span()));
    // A slow turn: 0.5 rad/s is 0.43 degrees per 15 ms packet.
    b.send(bytes(oi::driveDirect(65, -64)));
    b.run(2.0);
    b.send(bytes(oi::driveDirect(0, 0)));
    b.run(0.05);
    oi::SensorTracker tracker;
    tracker.feed(b.receive());
    const double truth_deg = b.body.odometry().theta * 180 / kPi;
    const double seen_deg = static_cast<double>(tracker.odometryState().totalAngleDeg());
    INFO("drop " << drop << " truth " << truth_deg << " reported " << seen_deg);
    CHECK(truth_deg > 50);
    if (drop) {
      CHECK(seen_deg == 0);  // every packet under one degree: all of it lost
    } else {
      CHECK(std::abs(seen_deg - truth_deg) < 1.0);
    }
  }
}

TEST_CASE("Create emulator: checksum quirk, corrupt packets, garbage, silence", "[sim][create]") {
  for (const bool include : {true, false}) {
    CreateEmulator::Options options;
    options.checksum_includes_header = include;
    Bench b(options);
    b.send({oi::kStart, oi::kSafe});
    b.send(bytes(oi::stream(oi::kCreateBaseStream).span()));
    b.run(0.1);
    const auto stream = b.receive();
    oi::SensorTracker matching(oi::StreamParserOptions{include, 10});
    oi::SensorTracker other(oi::StreamParserOptions{!include, 10});
    matching.feed(stream);
    other.feed(stream);
    CHECK(matching.packets() == b.emu->counters().packets_sent);
    CHECK(other.packets() == 0);
  }
  Bench b;
  b.send({oi::kStart, oi::kSafe});
  b.send(bytes(oi::stream(oi::kCreateBaseStream).span()));
  b.emu->corruptNextPackets(2);
  const std::array<std::uint8_t, 5> junk = {19, 10, 7, 1, 0xAA};
  b.emu->injectGarbage(junk);
  b.run(0.1);
  oi::SensorTracker t(oi::StreamParserOptions{true, 10});
  t.feed(b.receive());
  CHECK(b.emu->counters().corrupted_packets == 2);
  CHECK(t.counters().stream.checksum_failures == 2);
  CHECK(t.packets() == b.emu->counters().packets_sent - 2);
  CHECK(t.counters().stream.skipped_bytes >= junk.size());

  b.emu->setSilent(true);
  b.receive();
  b.send(bytes(oi::sensors(7)));
  b.run(0.1);
  CHECK(b.receive().empty());
}

TEST_CASE("Create emulator: Safe mode stops and falls to Passive on a wheel drop",
          "[sim][create]") {
  Bench b;
  b.send({oi::kStart, oi::kSafe});
  b.send(bytes(oi::drive(200, oi::kRadiusStraight)));
  b.run(0.01);
  CHECK(b.body.commandedV() > 0);
  b.emu->setWheelDrops(oi::kDropCaster);
  b.run(0.01);
  CHECK(b.body.commandedV() == 0.0);
  CHECK(b.emu->mode() == oi::Mode::kPassive);
  CHECK(b.emu->counters().safety_stops == 1);
}

TEST_CASE("Create emulator: unsupported packet ids get no bytes, are skipped and counted",
          "[sim][create]") {
  Bench b;
  b.send({oi::kStart, oi::kFull});
  b.receive();
  // Sensors(100): no Create 1 packet, no error reply in the manual: nothing comes back.
  b.send(bytes(oi::sensors(100)));
  CHECK(b.receive().empty());
  CHECK(b.emu->counters().unsupported_ids == 1);
  CHECK(b.emu->unsupportedIds().test(100));
  // Query List of a Create 2 id between two Create 1 ids: the known ones answered, in order.
  const std::array<std::uint8_t, 3> mixed = {oi::kOiMode, 43, oi::kRequestedVelocity};
  b.send(bytes(oi::queryList(mixed).span()));
  CHECK(b.receive() == std::vector<std::uint8_t>{3, 0, 0});
  CHECK(b.emu->counters().unsupported_ids == 2);
  // A Create 2 stream (43..58) with distance and mode: frames carry 19 and 35 only.
  std::vector<std::uint8_t> stream_ids = {oi::kDistance};
  for (std::uint8_t id = 43; id <= 58; ++id) stream_ids.push_back(id);
  stream_ids.push_back(oi::kOiMode);
  b.send(bytes(oi::stream(stream_ids).span()));
  CHECK(b.emu->counters().unsupported_ids == 18);
  for (std::uint8_t id = 43; id <= 58; ++id) CHECK(b.emu->unsupportedIds().test(id));
  CHECK(b.emu->unsupportedIds().count() == 17);  // 43..58 and 100
  const std::vector<std::uint8_t> kept(b.emu->streamIds().begin(), b.emu->streamIds().end());
  CHECK(kept == std::vector<std::uint8_t>{oi::kDistance, oi::kOiMode});
  b.run(0.1);
  oi::SensorTracker tracker(oi::StreamParserOptions{true, 5});  // 19 + 2 bytes, 35 + 1 byte
  tracker.feed(b.receive());
  CHECK(tracker.packets() >= 6);
  CHECK(tracker.packets() == b.emu->counters().packets_sent);
  CHECK(tracker.counters().stream.skipped_bytes == 0);
  // A stream of nothing the Create 1 has: no stream at all.
  const std::array<std::uint8_t, 2> create2_only = {100, 101};
  b.send(bytes(oi::stream(create2_only).span()));
  CHECK_FALSE(b.emu->streaming());
  CHECK(b.emu->counters().unsupported_ids == 20);
  const auto sent = b.emu->counters().packets_sent;
  b.run(0.1);
  CHECK(b.emu->counters().packets_sent == sent);
  CHECK(b.receive().empty());
}

TEST_CASE("Create emulator: a group id streams its members' data after the one group id",
          "[sim][create]") {
  Bench b;
  b.send({oi::kStart, oi::kFull});
  b.receive();
  // Group 2 (packets 17..20: IR, buttons, distance, angle: 6 bytes), then 35.
  const std::array<std::uint8_t, 2> ids = {2, oi::kOiMode};
  b.send(bytes(oi::stream(ids).span()));
  b.send(bytes(oi::drive(200, oi::kRadiusStraight)));
  b.run(0.2);
  const auto got = b.receive();
  const std::size_t frame = 2 + (1 + 6) + (1 + 1) + 1;  // 19, n, [2, 6 bytes], [35, 1], checksum
  REQUIRE(got.size() >= frame);
  REQUIRE(got.size() % frame == 0);
  int distance_mm = 0;
  for (std::size_t at = 0; at < got.size(); at += frame) {
    CHECK(got[at] == 19);
    CHECK(got[at + 1] == 9);
    CHECK(got[at + 2] == 2);
    CHECK(got[at + 9] == oi::kOiMode);
    CHECK(got[at + 10] == 3);
    unsigned sum = 0;
    for (std::size_t k = 0; k < frame; ++k) sum += got[at + k];
    CHECK(sum % 256 == 0);  // the Create 1: header included
    distance_mm += static_cast<std::int16_t>((got[at + 5] << 8) | got[at + 6]);
  }
  CHECK(std::abs(distance_mm - 40) <= 4);  // 0.2 m/s for 0.2 s, less what the last frame holds
  CHECK(b.emu->counters().unsupported_ids == 0);
}
