// Tests of the Create Open Interface byte code (crunch/io/create_oi.h): encoders against the OI
// v2 manual's bytes, the stream parser fed byte by byte, odometry against analytic arcs.
#include "crunch/io/create_oi.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

using namespace crunch;
namespace oi = crunch::io::oi;

namespace {

using Bytes = std::vector<std::uint8_t>;

template <std::size_t N>
Bytes vec(const std::array<std::uint8_t, N>& a) {
  return Bytes(a.begin(), a.end());
}

// A stream packet of CreateBase's layout [7, 19, 20, 35] with the given values.
Bytes packet(int bumps, int distance_mm, int angle_deg, bool include_header = true, int mode = 2) {
  oi::SensorFrame f;
  f.set(oi::kBumpsWheelDrops, bumps);
  f.set(oi::kDistance, distance_mm);
  f.set(oi::kAngle, angle_deg);
  f.set(oi::kOiMode, mode);
  std::array<std::uint8_t, 64> out{};
  const std::size_t n = oi::encodeStreamPacket(oi::kCreateBaseStream, f, include_header, out);
  REQUIRE(n == 13);
  return Bytes(out.begin(), out.begin() + static_cast<long>(n));
}

struct Delivered {
  int distance;
  int angle;
  bool operator==(const Delivered&) const = default;
};

std::vector<Delivered> feedAll(oi::StreamParser& p, const Bytes& bytes) {
  std::vector<Delivered> got;
  const auto take = [&] { got.push_back({p.frame().get(oi::kDistance), p.frame().get(oi::kAngle)}); };
  for (const std::uint8_t b : bytes) {
    if (p.feed(b)) {
      take();
      while (p.drainHeld()) take();
    }
  }
  return got;
}

void checkInvariant(const oi::StreamParser& p) {
  const auto& c = p.counters();
  CHECK(c.bytes == c.packet_bytes + c.skipped_bytes + p.pending());
}

}  // namespace

TEST_CASE("OI encoders: mode and stream commands are the manual's bytes", "[io][create]") {
  CHECK(vec(oi::start()) == Bytes{128});
  CHECK(vec(oi::safe()) == Bytes{131});
  CHECK(vec(oi::full()) == Bytes{132});
  CHECK(vec(oi::pauseResume(false)) == Bytes{150, 0});
  CHECK(vec(oi::pauseResume(true)) == Bytes{150, 1});
  CHECK(vec(oi::sensors(7)) == Bytes{142, 7});
  const std::array<std::uint8_t, 2> ids = {29, 13};  // the manual's Stream example
  const auto s = oi::stream(ids);
  CHECK(Bytes(s.span().begin(), s.span().end()) == Bytes{148, 2, 29, 13});
  const auto q = oi::queryList(ids);
  CHECK(Bytes(q.span().begin(), q.span().end()) == Bytes{149, 2, 29, 13});
}

TEST_CASE("OI encoders: Drive with ordinary and special radii, clamped", "[io][create]") {
  // The manual's example: reverse at -200 mm/s on a 500 mm radius.
  CHECK(vec(oi::drive(-200, 500)) == Bytes{137, 255, 56, 1, 244});
  CHECK(vec(oi::drive(200, 0x8000)) == Bytes{137, 0, 200, 0x80, 0x00});
  CHECK(vec(oi::drive(200, oi::kRadiusStraight)) == Bytes{137, 0, 200, 0x80, 0x00});
  CHECK(vec(oi::drive(200, 32767)) == Bytes{137, 0, 200, 0x7F, 0xFF});
  CHECK(vec(oi::drive(100, -1)) == Bytes{137, 0, 100, 0xFF, 0xFF});
  CHECK(vec(oi::drive(100, 1)) == Bytes{137, 0, 100, 0x00, 0x01});
  CHECK(vec(oi::drive(900, 5000)) == Bytes{137, 0x01, 0xF4, 0x07, 0xD0});   // 500, 2000
  CHECK(vec(oi::drive(-900, -5000)) == Bytes{137, 0xFE, 0x0C, 0xF8, 0x30});  // -500, -2000
}

TEST_CASE("OI encoders: Drive Direct sends right then left, clamped", "[io][create]") {
  CHECK(vec(oi::driveDirect(500, -500)) == Bytes{145, 0x01, 0xF4, 0xFE, 0x0C});
  CHECK(vec(oi::driveDirect(-100, 300)) == Bytes{145, 0xFF, 0x9C, 0x01, 0x2C});
  CHECK(vec(oi::driveDirect(2000, -2000)) == Bytes{145, 0x01, 0xF4, 0xFE, 0x0C});
}

TEST_CASE("OI twist to wheels: clamping keeps the curvature", "[io][create]") {
  auto w = oi::twistToWheels(0.2, 0.0);
  CHECK(w.right_mm_s == 200);
  CHECK(w.left_mm_s == 200);
  CHECK_FALSE(w.clamped);
  w = oi::twistToWheels(0.0, 1.0);
  CHECK(w.right_mm_s == 129);
  CHECK(w.left_mm_s == -129);
  w = oi::twistToWheels(0.5, 2.0);  // right 0.758, left 0.242 m/s before clamping
  CHECK(w.clamped);
  CHECK(w.right_mm_s == 500);
  CHECK(w.left_mm_s == 160);
  const double v = (w.right_mm_s + w.left_mm_s) / 2000.0;
  const double omega = (w.right_mm_s - w.left_mm_s) / 1000.0 / oi::kWheelBase;
  CHECK(omega / v == Approx(2.0 / 0.5).epsilon(0.01));  // curvature kept to rounding
  w = oi::twistToWheels(std::nan(""), 1.0);
  CHECK(w.right_mm_s == 0);
  CHECK(w.left_mm_s == 0);
}

TEST_CASE("OI twist to Drive: special radii for straight and turning in place", "[io][create]") {
  auto d = oi::twistToDrive(0.2, 0.0);
  CHECK(d.velocity_mm_s == 200);
  CHECK(d.radius_mm == oi::kRadiusStraight);
  d = oi::twistToDrive(0.0, 1.0);
  CHECK(d.velocity_mm_s == 129);
  CHECK(d.radius_mm == 1);
  d = oi::twistToDrive(0.0, -1.0);
  CHECK(d.velocity_mm_s == 129);
  CHECK(d.radius_mm == -1);
  d = oi::twistToDrive(0.2, 0.4);
  CHECK(d.velocity_mm_s == 200);
  CHECK(d.radius_mm == 500);
  d = oi::twistToDrive(-0.2, 0.4);
  CHECK(d.velocity_mm_s == -200);
  CHECK(d.radius_mm == -500);
  d = oi::twistToDrive(0.2, 0.01);  // 20 m radius: beyond Drive's 2 m, sent straight
  CHECK(d.radius_mm == oi::kRadiusStraight);
}

TEST_CASE("OI stream parser: the manual's example packet, fed byte by byte", "[io][create]") {
  const Bytes example = {19, 5, 29, 2, 25, 13, 0, 163};
  oi::StreamParser including;  // default: the header counts in the checksum
  int valid = 0;
  for (std::size_t i = 0; i < example.size(); ++i) {
    const bool done = including.feed(example[i]);
    CHECK(done == (i + 1 == example.size()));
    valid += done;
  }
  CHECK(valid == 1);
  CHECK(including.frame().get(29) == 0x0219);
  CHECK(including.frame().get(13) == 0);
  CHECK(including.frame().has(29));
  CHECK_FALSE(including.frame().has(19));

  oi::StreamParser excluding(oi::StreamParserOptions{false, 0});
  for (const std::uint8_t b : example) CHECK_FALSE(excluding.feed(b));
  CHECK(excluding.counters().checksum_failures == 1);
  checkInvariant(excluding);
}

TEST_CASE("OI stream parser: both checksum modes, signed values", "[io][create]") {
  for (const bool include : {true, false}) {
    oi::StreamParser matching(oi::StreamParserOptions{include, 10});
    oi::StreamParser other(oi::StreamParserOptions{!include, 10});
    const Bytes p = packet(0x03, -1234, -90, include);
    const auto got = feedAll(matching, p);
    REQUIRE(got.size() == 1);
    CHECK(got[0] == Delivered{-1234, -90});
    CHECK(matching.frame().get(oi::kBumpsWheelDrops) == 3);
    CHECK(matching.frame().get(oi::kOiMode) == 2);
    CHECK(feedAll(other, p).empty());
    CHECK(other.counters().checksum_failures == 1);
    checkInvariant(matching);
    checkInvariant(other);
  }
}

TEST_CASE("OI stream parser: random garbage between packets costs no packet", "[io][create]") {
  for (const std::uint8_t expected : {std::uint8_t{0}, std::uint8_t{10}}) {
    std::mt19937 rng(42 + expected);
    std::uniform_int_distribution<int> byte(0, 255), len(0, 40), val(-500, 500);
    Bytes stream;
    std::vector<Delivered> sent;
    std::uint64_t garbage = 0;
    for (int k = 0; k < 2000; ++k) {
      const int g = len(rng);
      for (int i = 0; i < g; ++i) {
        // One garbage byte in four is a false header, to make the parser work.
        const std::uint8_t b = (byte(rng) & 3) == 0 ? 19 : static_cast<std::uint8_t>(byte(rng));
        stream.push_back(b);
      }
      garbage += static_cast<std::uint64_t>(g);
      const Delivered d{val(rng), val(rng) / 10};
      const Bytes p = packet(0, d.distance, d.angle);
      stream.insert(stream.end(), p.begin(), p.end());
      sent.push_back(d);
    }
    oi::StreamParser parser(oi::StreamParserOptions{true, expected});
    const auto got = feedAll(parser, stream);
    INFO("expected_length " << int(expected));
    CHECK(got == sent);  // every real packet, in order, nothing else
    const auto& c = parser.counters();
    CHECK(c.skipped_bytes == garbage);
    CHECK(c.checksum_failures + c.bad_length_or_id > 0);
    checkInvariant(parser);
  }
}

TEST_CASE("OI stream parser: every truncation and corruption is counted, never delivered",
          "[io][create]") {
  const Bytes good = packet(0, 321, 7);
  const Bytes next = packet(0, 100, 1);
  for (std::size_t cut = 1; cut < good.size(); ++cut) {
    oi::StreamParser p;
    Bytes s(good.begin(), good.begin() + static_cast<long>(cut));
    s.insert(s.end(), next.begin(), next.end());
    const auto got = feedAll(p, s);
    INFO("cut at " << cut);
    REQUIRE(got.size() == 1);
    CHECK(got[0] == Delivered{100, 1});
    CHECK(p.counters().checksum_failures + p.counters().bad_length_or_id >= 1);
    checkInvariant(p);
  }
  for (std::size_t at = 0; at < good.size(); ++at) {
    for (const std::uint8_t flip : {std::uint8_t{0x01}, std::uint8_t{0x80}, std::uint8_t{0x5A}}) {
      oi::StreamParser p;
      Bytes s = good;
      s[at] ^= flip;
      s.insert(s.end(), next.begin(), next.end());
      const auto got = feedAll(p, s);
      INFO("byte " << at << " xor " << int(flip));
      REQUIRE(got.size() == 1);
      CHECK(got[0] == Delivered{100, 1});
      if (at > 0) CHECK(p.counters().checksum_failures + p.counters().bad_length_or_id >= 1);
      checkInvariant(p);
    }
  }
  // An unknown id and a length that does not match the ids are layout errors.
  oi::StreamParser p;
  feedAll(p, Bytes{19, 2, 99, 0, static_cast<std::uint8_t>(256 - (19 + 2 + 99))});
  CHECK(p.counters().bad_length_or_id == 1);
  feedAll(p, Bytes{19, 2, 22, 0, 0});  // packet 22 needs 2 data bytes: overruns n = 2
  CHECK(p.counters().bad_length_or_id == 2);
  feedAll(p, Bytes{19, 0, 237});
  CHECK(p.counters().bad_length_or_id == 3);
  CHECK(p.counters().packets == 0);
}

TEST_CASE("OI odometry: straight lines, in-place turns and arcs against geometry", "[io][create]") {
  oi::Odometry odo;
  for (int i = 0; i < 100; ++i) odo.update(10, 0);
  CHECK(odo.pose().x == Approx(1.0));
  CHECK(odo.pose().y == Approx(0.0).margin(1e-12));
  for (int i = 0; i < 90; ++i) odo.update(0, 1);
  CHECK(odo.pose().theta == Approx(kPi / 2));
  CHECK(odo.pose().x == Approx(1.0));

  // A half circle: 90 packets of 10 mm and 2 degrees. Radius R = 900 mm / pi.
  oi::Odometry arc;
  for (int i = 0; i < 90; ++i) arc.update(10, 2);
  const double r = 0.9 / kPi;
  // Midpoint integration moves the arc length along the chord direction: error ~ R dtheta^2/24.
  constexpr double kArcTolerance = 0.001;  // metres
  CHECK(arc.pose().x == Approx(0.0).margin(kArcTolerance));
  CHECK(arc.pose().y == Approx(2 * r).margin(kArcTolerance));
  CHECK(std::abs(wrapPi(arc.pose().theta - kPi)) < 1e-12);
  CHECK(arc.totalDistanceMm() == 900);
  CHECK(arc.totalAngleDeg() == 180);

  // Exact heading from integer totals: 3600 single degrees are ten turns, to the last bit.
  oi::Odometry spin(Pose2{0, 0, 0.3});
  for (int i = 0; i < 3600; ++i) spin.update(0, 1);
  CHECK(spin.pose().theta == Approx(0.3).margin(1e-12));
}

TEST_CASE("OI sensor tracker: chunking does not change the result, bumps tracked", "[io][create]") {
  std::mt19937 rng(7);
  Bytes stream;
  for (int k = 0; k < 500; ++k) {
    const Bytes p = packet(k == 300 ? oi::kBumpLeft : 0, 5 + k % 7, (k % 5) - 1);
    stream.insert(stream.end(), p.begin(), p.end());
    if (k % 3 == 0) stream.push_back(static_cast<std::uint8_t>(rng()));
  }
  oi::SensorTracker whole, bytewise, chunked;
  whole.feed(stream);
  for (const std::uint8_t b : stream) bytewise.feed({&b, 1});
  std::uniform_int_distribution<std::size_t> len(1, 40);
  for (std::size_t i = 0; i < stream.size();) {
    const std::size_t n = std::min(len(rng), stream.size() - i);
    chunked.feed({stream.data() + i, n});
    i += n;
  }
  CHECK(whole.packets() == 500);
  for (const auto* t : {&bytewise, &chunked}) {
    CHECK(t->packets() == whole.packets());
    CHECK(t->odometry().x == whole.odometry().x);
    CHECK(t->odometry().y == whole.odometry().y);
    CHECK(t->odometry().theta == whole.odometry().theta);
  }
  CHECK(whole.counters().bump_packets == 1);
  CHECK_FALSE(whole.bumped());  // the last packet has no bump
  oi::SensorTracker t;
  t.feed(packet(oi::kDropCaster, 0, 0));
  CHECK(t.bumped());
  CHECK(t.wheelDropped());
  CHECK(t.mode() == oi::Mode::kSafeMode);
}
