// BodyWhisk against a fake MobileBase that integrates the commanded (v, omega) exactly
// (circular arcs) in simulated time: the phases of §2.3 in order, the exact pi/24 rad/s rate, the
// angles swept and distances reversed, the random turns, bumps, and the in-place whisk.
#include "crunch/behaviour/body_whisk.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

using crunch::BodyWhisk;
using crunch::Error;
using crunch::kPi;
using crunch::MobileBase;
using crunch::Pose2;
using crunch::Status;
using crunch::wrapPi;
using Phase = BodyWhisk::Phase;

namespace {

constexpr double kRate = kPi / 24;  // the paper's whisk rate
constexpr double kAmp = kPi / 12;   // the default amplitude
// Bit masks of the default whisker array (-33.75, -11.25, +11.25, +33.75 degrees).
constexpr std::uint32_t kRightOuter = 1u << 0, kRightInner = 1u << 1;
constexpr std::uint32_t kLeftInner = 1u << 2, kLeftOuter = 1u << 3;
// Rounding in the integration and the sweep accumulation, far below any step's motion.
constexpr double kEps = 1e-9;

struct Command {
  double t, v, omega;
};

class FakeBase : public MobileBase {
 public:
  Status drive(double v, double omega) override {
    ++attempts;
    if (refuse > 0) {
      --refuse;
      return Error{"fake base: command refused"};
    }
    v_ = v;
    omega_ = omega;
    commands.push_back({t, v, omega});
    return crunch::okStatus();
  }
  Pose2 odometry() const override { return pose; }
  bool bumped() const override { return bump; }
  double now() const override { return t; }

  // Exact kinematics of a unicycle holding (v, omega) for dt; the heading is reported wrapped,
  // as a real base's odometry is.
  void advance(double dt) {
    if (!stuck) {
      const double th = pose.theta, dth = omega_ * dt;
      if (std::abs(omega_) < 1e-12) {
        pose.x += v_ * std::cos(th) * dt;
        pose.y += v_ * std::sin(th) * dt;
      } else {
        pose.x += v_ / omega_ * (std::sin(th + dth) - std::sin(th));
        pose.y -= v_ / omega_ * (std::cos(th + dth) - std::cos(th));
      }
      pose.theta = wrapPi(th + dth);
    }
    t += dt;
  }

  Pose2 pose;
  double t = 0.0;
  bool bump = false;
  bool stuck = false;  // wheels spin, nothing moves
  int refuse = 0;      // refuse this many drive() calls
  int attempts = 0;
  std::vector<Command> commands;  // the commands the base took

 private:
  double v_ = 0.0, omega_ = 0.0;
};

// A phase as the run saw it: when and where it began.
struct Entry {
  Phase phase;
  double t;
  Pose2 pose;
};

struct Run {
  std::vector<Entry> trace;
  // Phase entry k's pose and the next entry's: the motion during phase k.
  const Entry& at(std::size_t k) const { return trace.at(k); }
};

// Updates every dt (simulated) until `until` returns true or t_max passes. `contact` gives the
// mask at time t; `before` may change the base before each update (bumps).
Run simulate(
    BodyWhisk& bw, FakeBase& base, double dt, double t_max,
    const std::function<std::uint32_t(double)>& contact,
    const std::function<bool()>& until = [] { return false; },
    const std::function<void(FakeBase&, Phase)>& before = nullptr) {
  Run run;
  run.trace.push_back({bw.phase(), base.t, base.pose});
  const double t0 = base.t;
  for (long k = 1; base.t <= t0 + t_max && !until(); ++k) {
    if (before) before(base, bw.phase());
    REQUIRE(bw.update(contact(base.t)).ok());
    if (bw.phase() != run.trace.back().phase) run.trace.push_back({bw.phase(), base.t, base.pose});
    base.advance(dt);
    base.t = t0 + static_cast<double>(k) * dt;  // no drift in the clock
  }
  return run;
}

std::vector<Phase> phases(const Run& run) {
  std::vector<Phase> out;
  for (const auto& e : run.trace) out.push_back(e.phase);
  return out;
}

double distance(const Pose2& a, const Pose2& b) { return std::hypot(a.x - b.x, a.y - b.y); }

std::size_t indexOf(const Run& run, Phase p, std::size_t from = 0) {
  for (std::size_t i = from; i < run.trace.size(); ++i)
    if (run.trace[i].phase == p) return i;
  FAIL("phase " << BodyWhisk::phaseName(p) << " never entered");
  return 0;
}

// One touch of the given whiskers at t in [t0, t0 + 0.2).
std::function<std::uint32_t(double)> touchAt(double t0, std::uint32_t mask) {
  return [=](double t) { return t >= t0 && t < t0 + 0.2 ? mask : 0u; };
}

}  // namespace

TEST_CASE("BodyWhisk: a contact runs back-off, toward, away, clear, turn, forward in order",
          "[behaviour]") {
  FakeBase base;
  BodyWhisk bw(base, {});
  REQUIRE(bw.startRoaming().ok());
  CHECK(bw.phase() == Phase::kForward);
  CHECK(!bw.contactTime());

  const double dt = 0.01;
  const Run run = simulate(bw, base, dt, 30.0, touchAt(1.0, kLeftOuter),
                           [&] { return bw.stats().turns == 1 && bw.phase() == Phase::kForward; });
  CHECK(phases(run) == std::vector<Phase>{Phase::kForward, Phase::kBackOff, Phase::kToward,
                                          Phase::kAway, Phase::kClear, Phase::kTurn,
                                          Phase::kForward});
  // The contact's time is the base's clock at the update that saw it: the window's anchor.
  REQUIRE(bw.contactTime());
  CHECK(*bw.contactTime() == Approx(1.0).margin(kEps));
  CHECK(run.at(1).t == Approx(1.0).margin(kEps));
  CHECK(*bw.whiskStartTime() == Approx(run.at(2).t).margin(kEps));
  CHECK(bw.stats().whisks_started == 1);
  CHECK(bw.stats().whisks_completed == 1);
  CHECK(bw.stats().timeouts == 0);
  CHECK(bw.stats().bumps == 0);

  // Durations: the toward leg sweeps A (2 s at pi/24), the away leg 2A (4 s).
  CHECK(run.at(3).t - run.at(2).t == Approx(kAmp / kRate).margin(dt + kEps));
  // (The toward leg may end one update past A; the away leg then has that much further to go.)
  CHECK(run.at(4).t - run.at(3).t == Approx(2 * kAmp / kRate).margin(2 * dt + kEps));
}

TEST_CASE("BodyWhisk: the whisk turns at exactly pi/24 rad/s toward the touching side first",
          "[behaviour]") {
  struct Case {
    const char* name;
    std::uint32_t mask;
    int side;
  };
  for (const Case& c : {Case{"left outer", kLeftOuter, +1}, Case{"right inner", kRightInner, -1},
                        Case{"two right, one left", kRightOuter | kRightInner | kLeftInner, -1},
                        Case{"symmetric pair: CCW", kLeftInner | kRightInner, +1}}) {
    INFO(c.name);
    FakeBase base;
    BodyWhisk bw(base, {});
    REQUIRE(bw.startRoaming().ok());
    simulate(bw, base, 0.01, 30.0, touchAt(0.5, c.mask), [&] { return bw.stats().turns == 1; });
    CHECK(bw.towardSign() == c.side);
    // The rotation commands of the whisk, in order: toward, then away; nothing else turns at
    // this rate, and neither moves the base forward or back.
    std::vector<double> whisk_omegas;
    for (const auto& cmd : base.commands)
      if (std::abs(std::abs(cmd.omega) - kRate) < 1e-6) {
        CHECK(cmd.v == 0.0);
        whisk_omegas.push_back(cmd.omega);
      }
    REQUIRE(whisk_omegas.size() == 2);
    CHECK(whisk_omegas[0] == c.side * kPi / 24);  // exactly
    CHECK(whisk_omegas[1] == -c.side * kPi / 24);
  }
}

TEST_CASE("BodyWhisk: angles swept and distances reversed, at any update rate", "[behaviour]") {
  for (const double dt : {0.001, 0.02, 0.1, 0.25}) {
    INFO("dt " << dt);
    FakeBase base;
    base.pose = {1.0, 2.0, 3.1};  // near +-pi: the sweep must survive the heading's wrap
    BodyWhisk bw(base, {});
    REQUIRE(bw.startRoaming().ok());
    const Run run = simulate(bw, base, dt, 40.0, touchAt(1.0, kLeftInner), [&] {
      return bw.stats().turns == 1 && bw.phase() == Phase::kForward;
    });
    REQUIRE(phases(run).size() == 7);
    const BodyWhisk::Options o;
    // Step bounds: a phase ends at the first update past its target.
    const double turn_step = kRate * dt + kEps, move_step = o.reverse_speed * dt + kEps;

    const Pose2 contact = run.at(1).pose, theta0 = run.at(2).pose, peak = run.at(3).pose,
                trough = run.at(4).pose, cleared = run.at(5).pose;
    // Forward at forward_speed until the contact (1 s).
    CHECK(contact.x - 1.0 ==
          Approx(o.forward_speed * std::cos(3.1) * run.at(1).t).margin(o.forward_speed * dt));
    // The short reverse: reverse_distance, straight back along the heading.
    const double back = distance(contact, theta0);
    CHECK(back >= o.reverse_distance - kEps);
    CHECK(back <= o.reverse_distance + move_step);
    CHECK(theta0.theta == Approx(contact.theta).margin(kEps));
    CHECK((theta0.x - contact.x) * std::cos(contact.theta) < 0);
    // Toward: +A from theta0 (left contact: CCW); away: to -A; the base turns on the spot.
    const double up = wrapPi(peak.theta - theta0.theta);
    const double down = wrapPi(trough.theta - theta0.theta);
    CHECK(up >= kAmp - kEps);
    CHECK(up <= kAmp + turn_step);
    CHECK(down <= -kAmp + kEps);
    CHECK(down >= -kAmp - turn_step);  // no accumulated overshoot: measured from theta0
    CHECK(distance(trough, theta0) < kEps);
    // The clearing reverse.
    const double clear = distance(trough, cleared);
    CHECK(clear >= o.clear_distance - kEps);
    CHECK(clear <= o.clear_distance + move_step);
  }
}

TEST_CASE("BodyWhisk: random turns stay in [turn_min, turn_max], both ways, fixed by the seed",
          "[behaviour]") {
  BodyWhisk::Options o;
  o.turn_min = kPi / 4;
  o.turn_max = 3 * kPi / 4;
  const double dt = 0.01;

  // Roams with a touch every 20 s for 12 whisks; returns the turns drawn and checks each one's
  // size against the heading the base actually turned.
  auto turns = [&](std::uint64_t seed) {
    o.seed = seed;
    FakeBase base;
    BodyWhisk bw(base, o);
    REQUIRE(bw.startRoaming().ok());
    std::vector<double> drawn;
    const Run run = simulate(bw, base, dt, 12 * 20.0 - 1.0,
                             [](double t) { return std::fmod(t, 20.0) < 0.1 ? kLeftInner : 0u; });
    for (std::size_t i = 0; i + 1 < run.trace.size(); ++i) {
      if (run.trace[i].phase != Phase::kTurn) continue;
      const double turned = wrapPi(run.trace[i + 1].pose.theta - run.trace[i].pose.theta);
      drawn.push_back(turned);
    }
    CHECK(bw.stats().turns == static_cast<int>(drawn.size()));
    CHECK(std::abs(drawn.back()) ==
          Approx(std::abs(bw.lastTurn())).margin(o.turn_rate * dt + kEps));
    return drawn;
  };
  const std::vector<double> a = turns(7), b = turns(7), c = turns(8);
  REQUIRE(a.size() >= 10);
  int left = 0, right = 0;
  for (const double t : a) {
    CHECK(std::abs(t) >= o.turn_min - kEps);
    CHECK(std::abs(t) <= o.turn_max + o.turn_rate * dt + kEps);
    (t > 0 ? left : right)++;
  }
  CHECK(left > 0);
  CHECK(right > 0);
  CHECK(a == b);  // same seed, same turns, bit for bit
  CHECK(a != c);
}

TEST_CASE("BodyWhisk: a bump stops the base at once, backs off, then turns away", "[behaviour]") {
  FakeBase base;
  BodyWhisk bw(base, {});
  REQUIRE(bw.startRoaming().ok());
  double bump_t = -1;
  // Bump once, 0.5 s into the toward leg; the bumper stays pressed for 0.3 s.
  const Run run = simulate(
      bw, base, 0.01, 30.0, touchAt(1.0, kRightOuter),
      [&] { return bw.stats().turns == 1 && bw.phase() == Phase::kForward; },
      [&](FakeBase& b, Phase p) {
        if (bump_t < 0 && p == Phase::kToward && b.t - *bw.whiskStartTime() >= 0.5) bump_t = b.t;
        b.bump = bump_t >= 0 && b.t < bump_t + 0.3;
      });
  CHECK(phases(run) == std::vector<Phase>{Phase::kForward, Phase::kBackOff, Phase::kToward,
                                          Phase::kBumpBackOff, Phase::kTurn, Phase::kForward});
  CHECK(bw.stats().bumps == 1);  // held bumper, one bump
  CHECK(bw.stats().whisks_completed == 0);
  // At the bump's update: a stop; at the next update: the reverse.
  std::size_t k = 0;
  while (base.commands[k].t < bump_t - kEps) ++k;
  CHECK(base.commands[k].t == Approx(bump_t).margin(kEps));
  CHECK(base.commands[k].v == 0.0);
  CHECK(base.commands[k].omega == 0.0);
  CHECK(base.commands[k + 1].t == Approx(bump_t + 0.01).margin(kEps));
  CHECK(base.commands[k + 1].v == -BodyWhisk::Options{}.reverse_speed);
  const std::size_t bk = indexOf(run, Phase::kBumpBackOff);
  const double backed = distance(run.at(bk).pose, run.at(bk + 1).pose);
  CHECK(backed >= BodyWhisk::Options{}.bump_backoff - kEps);
  CHECK(backed <= BodyWhisk::Options{}.bump_backoff + 0.05 * 0.01 + kEps);
}

TEST_CASE("BodyWhisk: the in-place whisk goes toward, away, back to the start heading, done",
          "[behaviour]") {
  for (const int direction : {+1, -1}) {
    for (const double dt : {0.001, 0.05, 0.3}) {
      INFO("direction " << direction << ", dt " << dt);
      FakeBase base;
      base.pose = {2.5, 1.5, -3.0};
      base.t = 12.0;
      const Pose2 start = base.pose;
      BodyWhisk bw(base, {});
      REQUIRE(bw.startInPlace(direction).ok());
      CHECK(bw.phase() == Phase::kToward);
      CHECK(*bw.contactTime() == 12.0);
      CHECK(*bw.whiskStartTime() == 12.0);
      double lo = 0, hi = 0;
      const Run run = simulate(
          bw, base, dt, 30.0, [](double) { return 0u; },
          [&] {
            const double s = wrapPi(base.pose.theta - start.theta);
            lo = std::min(lo, s);
            hi = std::max(hi, s);
            return bw.done();
          });
      CHECK(phases(run) ==
            std::vector<Phase>{Phase::kToward, Phase::kAway, Phase::kReturn, Phase::kDone});
      CHECK(bw.done());
      CHECK(!bw.interrupted());
      const double step = kRate * dt + kEps;
      // The first leg goes the asked way; the sweep spans +-A.
      CHECK(wrapPi(run.at(1).pose.theta - start.theta) * direction > 0);
      CHECK(hi >= kAmp - kEps);
      CHECK(hi <= kAmp + step);
      CHECK(lo <= -kAmp + kEps);
      CHECK(lo >= -kAmp - step);
      // Back at the start heading, not moved, stopped.
      CHECK(std::abs(wrapPi(base.pose.theta - start.theta)) <= step);
      CHECK(distance(base.pose, start) < kEps);
      CHECK(base.commands.back().v == 0.0);
      CHECK(base.commands.back().omega == 0.0);
      CHECK(run.at(3).t - 12.0 == Approx(4 * kAmp / kRate).margin(3 * dt + kEps));
      // Once done, update() commands nothing more.
      const std::size_t n = base.commands.size();
      REQUIRE(bw.update(0).ok());
      CHECK(base.commands.size() == n);
    }
  }
}

TEST_CASE("BodyWhisk: a bump ends the in-place whisk, interrupted, after backing off",
          "[behaviour]") {
  FakeBase base;
  BodyWhisk bw(base, {});
  REQUIRE(bw.startInPlace().ok());
  simulate(
      bw, base, 0.01, 30.0, [](double) { return 0u; }, [&] { return bw.done(); },
      [](FakeBase& b, Phase p) { b.bump = p == Phase::kAway && b.t > 3.0 && b.t < 3.05; });
  CHECK(bw.done());
  CHECK(bw.interrupted());
  CHECK(bw.stats().bumps == 1);
  CHECK(bw.stats().whisks_completed == 0);
  CHECK(distance(base.pose, Pose2{}) >= BodyWhisk::Options{}.bump_backoff - kEps);
}

TEST_CASE("BodyWhisk: without a contact the robot only drives forward", "[behaviour]") {
  FakeBase base;
  BodyWhisk bw(base, {});
  REQUIRE(bw.startRoaming().ok());
  const Run run = simulate(bw, base, 0.01, 10.0, [](double) { return 0u; });
  CHECK(phases(run) == std::vector<Phase>{Phase::kForward});
  CHECK(base.commands.size() == 1);  // a command is sent only when it changes
  CHECK(base.pose.x == Approx(0.1 * base.t).margin(0.1 * 0.01));
  // Contact bits past the configured whiskers are not whiskers.
  simulate(bw, base, 0.01, 1.0, [](double) { return 1u << 4; });
  CHECK(bw.phase() == Phase::kForward);
}

TEST_CASE("BodyWhisk: a refused command is reported and sent again at the next update",
          "[behaviour]") {
  FakeBase base;
  BodyWhisk bw(base, {});
  base.refuse = 1;
  const Status s = bw.startRoaming();
  REQUIRE(!s.ok());
  CHECK(s.error().message.find("fake base") != std::string::npos);
  CHECK(bw.phase() == Phase::kForward);
  CHECK(base.commands.empty());
  REQUIRE(bw.update(0).ok());
  REQUIRE(base.commands.size() == 1);
  CHECK(base.commands[0].v == BodyWhisk::Options{}.forward_speed);
  CHECK(base.attempts == 2);
}

TEST_CASE("BodyWhisk: a base that does not move times the whisk out and says so", "[behaviour]") {
  FakeBase base;
  base.stuck = true;
  BodyWhisk bw(base, {});
  REQUIRE(bw.startInPlace().ok());
  const Run run = simulate(
      bw, base, 0.01, 60.0, [](double) { return 0u; }, [&] { return bw.done(); });
  CHECK(bw.done());
  // Toward and away time out; the heading never left theta0, so the return has nothing to do.
  CHECK(bw.stats().timeouts == 2);
  // Toward: 3 x 2 s + 1 s; away: 3 x 4 s + 1 s.
  CHECK(run.at(1).t == Approx(7.0).margin(0.01 + kEps));
  CHECK(run.at(2).t == Approx(7.0 + 13.0).margin(0.02 + kEps));
}

TEST_CASE("BodyWhisk: options validate, naming the bad field", "[behaviour]") {
  CHECK(BodyWhisk::Options{}.validate().ok());
  const BodyWhisk::Options d;
  CHECK(d.whisk_rate == kPi / 24);
  CHECK(d.whisk_amplitude / d.whisk_rate == Approx(2.0));  // the paper's 2 s window
  struct Case {
    const char* field;
    std::function<void(BodyWhisk::Options&)> spoil;
  };
  const std::vector<Case> cases = {
      {"forward_speed", [](auto& o) { o.forward_speed = 0; }},
      {"reverse_speed", [](auto& o) { o.reverse_speed = -0.1; }},
      {"reverse_distance", [](auto& o) { o.reverse_distance = NAN; }},
      {"whisk_rate", [](auto& o) { o.whisk_rate = INFINITY; }},
      {"whisk_amplitude", [](auto& o) { o.whisk_amplitude = kPi; }},
      {"clear_distance", [](auto& o) { o.clear_distance = -1; }},
      {"turn_min", [](auto& o) { o.turn_min = -0.1; }},
      {"turn_max", [](auto& o) { o.turn_max = o.turn_min / 2; }},
      {"turn_rate", [](auto& o) { o.turn_rate = 0; }},
      {"bump_backoff", [](auto& o) { o.bump_backoff = NAN; }},
      {"timeout_factor", [](auto& o) { o.timeout_factor = 0.5; }},
      {"timeout_slack", [](auto& o) { o.timeout_slack = -1; }},
      {"whisker_bearings", [](auto& o) { o.whisker_bearings.clear(); }},
      {"whisker_bearings", [](auto& o) { o.whisker_bearings[1] = NAN; }},
  };
  for (const Case& c : cases) {
    BodyWhisk::Options o;
    c.spoil(o);
    const Status s = o.validate();
    INFO(c.field);
    REQUIRE(!s.ok());
    CHECK(s.error().message.find(c.field) != std::string::npos);
  }
}

TEST_CASE("BodyWhisk: towardSide is the side of the touching whiskers' mean bearing",
          "[behaviour]") {
  const std::vector<double> b = BodyWhisk::Options{}.whisker_bearings;
  CHECK(BodyWhisk::towardSide(0, b) == 0);
  CHECK(BodyWhisk::towardSide(kLeftInner, b) == +1);
  CHECK(BodyWhisk::towardSide(kRightOuter, b) == -1);
  CHECK(BodyWhisk::towardSide(kRightOuter | kLeftInner, b) == -1);  // outer outweighs inner
  CHECK(BodyWhisk::towardSide(kLeftOuter | kRightInner, b) == +1);
  CHECK(BodyWhisk::towardSide(0xFu, b) == +1);  // all four: straight ahead, CCW by convention
  CHECK(BodyWhisk::towardSide(1u << 7, b) == 0);
  const std::vector<double> behind = {kPi, -kPi + 1e-12};
  CHECK(BodyWhisk::towardSide(1u, behind) == +1);
  CHECK(BodyWhisk::towardSide(2u, behind) == +1);
}
