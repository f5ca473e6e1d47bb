// Tests of WhiskEvidence (crunch/session/whisk_evidence.h): from synthetic contact episodes and
// negative-evidence samples to the mapper's reports and free rays.
#include "crunch/session/whisk_evidence.h"

#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

using namespace crunch;

namespace {

// Two whiskers with easy numbers, and two more like the default array's.
std::vector<WhiskerMount> mounts() {
  return {{{0.10, 0.05}, 0.3, 0.14},
          {{0.12, -0.02}, -0.4, 0.10},
          {{0.15, 0.00}, 0.0, 0.14},
          {{0.00, 0.16}, 1.5, 0.20}};
}

// The robot's odometry per pipeline sample: moving along +x and turning slowly.
Pose2 poseAt(std::uint64_t i) {
  const double k = static_cast<double>(i);
  return {0.001 * k, 0.5 - 0.0005 * k, 0.2 + 0.002 * k};
}

// A touch at r (metres along the whisker) peaking `peak` samples into its episode; with a ramp
// (located() fills it in) unless `ramp` is false.
signal::WhiskerContact touch(double r, std::int64_t peak, bool has_r = true, bool ramp = true) {
  signal::WhiskerContact c;
  c.touched = true;
  c.onset_sample = 0;
  c.peak_sample = peak;
  c.f1 = 0.01 * static_cast<double>(peak);
  c.has_r = has_r;
  c.r = r;
  c.ramp.valid = ramp;
  return c;
}

// Gives every touch with a ramp the ramp a contact at its r makes on the nominal whisker
// (robot/whisker_beam.h): starting at its peak sample, touched at that sample's heading - dpsi.
template <typename PoseAt>
signal::ContactEpisode located(signal::ContactEpisode ep, PoseAt&& pose_at,
                               const std::vector<WhiskerMount>& m = mounts(), double dpsi = 0.0) {
  const WhiskerBeam beam;
  for (std::size_t w = 0; w < m.size() && w < ep.whiskers.size(); ++w) {
    signal::WhiskerContact& c = ep.whiskers[w];
    if (!c.touched || !c.ramp.valid) continue;
    const double lever = m[w].base.dot(Vec2{std::cos(m[w].bearing), std::sin(m[w].bearing)});
    c.ramp.slope = rampSlope(beam, std::clamp(c.r, 0.005, beam.external_length), lever);
    c.ramp.first_sample = ep.start_sample + static_cast<std::uint64_t>(std::max<std::int64_t>(0, c.peak_sample));
    c.ramp.touch_heading = pose_at(c.ramp.first_sample).theta - dpsi;
    c.ramp.points = 100;
  }
  return ep;
}

signal::ContactEpisode episode(std::uint64_t start, double angle, bool has_orientation = true) {
  signal::ContactEpisode ep;
  ep.start_sample = start;
  ep.has_orientation = has_orientation;
  ep.orientation.angle = angle;
  return ep;
}

bool near(double a, double b, double tol = 1e-12) { return std::abs(a - b) <= tol; }

}  // namespace

TEST_CASE("WhiskEvidence: each whisker reports once per whisk, from its first episode",
          "[mapping][evidence]") {
  WhiskEvidence ev(mounts(), WhiskerBeam{});
  ev.begin();
  signal::ContactEpisode a = episode(100, 0.5);
  a.whiskers[0] = touch(0.05, 10);
  a.whiskers[2] = touch(0.07, 30);
  signal::ContactEpisode b = episode(900, 1.0);
  b.whiskers[0] = touch(0.09, 5);  // second touch of whisker 0: ignored
  b.whiskers[1] = touch(0.04, 20);
  CHECK(ev.take(located(a, poseAt), poseAt) == 0b0101u);
  CHECK(ev.take(located(b, poseAt), poseAt) == 0b0010u);
  CHECK(ev.entry(0).have);
  CHECK(ev.entry(0).f1 == a.whiskers[0].f1);
  CHECK(ev.entry(0).report.r == Approx(0.05).margin(1e-7));
  CHECK_FALSE(ev.entry(3).have);

  std::vector<ContactReport> reports;
  std::vector<FreeRay> rays;
  ev.end(reports, rays);
  REQUIRE(reports.size() == 3);
  auto find = [&](int w) -> const ContactReport* {
    for (const ContactReport& r : reports)
      if (r.whisker == w) return &r;
    return nullptr;
  };
  REQUIRE(find(0) != nullptr);
  REQUIRE(find(1) != nullptr);
  REQUIRE(find(2) != nullptr);
  CHECK(find(3) == nullptr);
  // r from the ramp's slope (robot/whisker_beam.h, inverted).
  CHECK(find(0)->r == Approx(0.05).margin(1e-7));
  CHECK(find(1)->r == Approx(0.04).margin(1e-7));
  CHECK(find(2)->r == Approx(0.07).margin(1e-7));
  // The report's robot pose is the ramp's first sample's position with its touch heading (here
  // that sample's heading: located() with dpsi 0).
  const Pose2 p0 = poseAt(110), p1 = poseAt(920), p2 = poseAt(130);
  CHECK((find(0)->robot.x == p0.x && find(0)->robot.y == p0.y && find(0)->robot.theta == p0.theta));
  CHECK((find(1)->robot.x == p1.x && find(1)->robot.theta == p1.theta));
  CHECK((find(2)->robot.x == p2.x && find(2)->robot.theta == p2.theta));
  CHECK(ev.counts().episodes == 2);
  CHECK(ev.counts().reports == 3);
  CHECK(ev.counts().whisks == 1);
  CHECK(rays.empty());  // no negative-evidence samples taken
}

TEST_CASE("WhiskEvidence: r is clamped to 5 mm .. the mount's length", "[mapping][evidence]") {
  WhiskEvidence ev(mounts(), WhiskerBeam{});
  ev.begin();
  signal::ContactEpisode ep = episode(0, 0.0);
  ep.whiskers[0] = touch(-0.03, 1);  // below the base
  ep.whiskers[1] = touch(0.25, 1);   // past whisker 1's 0.10 m tip
  ep.whiskers[2] = touch(0.0625, 1);
  ep.whiskers[3] = touch(0.20, 1);   // exactly the tip
  ev.take(located(ep, poseAt), poseAt);
  CHECK(ev.entry(0).report.r == Approx(0.005));
  CHECK(ev.entry(1).report.r == 0.10);
  CHECK(ev.entry(2).report.r == Approx(0.0625).margin(1e-7));
  CHECK(ev.entry(3).report.r == Approx(0.14));  // the slope of the beam's own tip
}

TEST_CASE("WhiskEvidence: phi is the template angle turned from the onset heading to the touch "
          "heading, 0 <= phi < pi",
          "[mapping][evidence]") {
  const auto pose_at = [](std::uint64_t i) {
    // Headings chosen per sample: onset at 1000, peaks at 1000 + peak.
    switch (i) {
      case 1000: return Pose2{0, 0, 1.0};
      case 1010: return Pose2{0, 0, 1.3};
      case 1020: return Pose2{0, 0, -2.0};
      case 1030: return Pose2{0, 0, 1.1};
      default: return Pose2{0, 0, 1.0};
    }
  };
  WhiskEvidence ev(mounts(), WhiskerBeam{});
  ev.begin();
  signal::ContactEpisode ep = episode(1000, 0.4);
  ep.whiskers[0] = touch(0.05, 10);  // 0.4 + 1.0 - 1.3 = 0.1
  ep.whiskers[1] = touch(0.05, 20);  // 0.4 + 1.0 + 2.0 = 3.4 -> 3.4 - pi
  ep.whiskers[2] = touch(0.05, 30);  // 0.4 + 1.0 - 1.1 = 0.3
  ep.whiskers[3] = touch(0.05, 0);   // peak at onset: 0.4
  ev.take(located(ep, pose_at), pose_at);
  CHECK(near(ev.entry(0).report.phi, 0.1, 1e-12));
  CHECK(near(ev.entry(1).report.phi, 3.4 - kPi, 1e-12));
  CHECK(near(ev.entry(2).report.phi, 0.3, 1e-12));
  CHECK(near(ev.entry(3).report.phi, 0.4, 1e-12));

  // A turn the other way gives a negative angle, reported as its [0, pi) equivalent.
  ev.begin();
  signal::ContactEpisode ep2 = episode(1000, 0.1);
  ep2.whiskers[0] = touch(0.05, 10);  // 0.1 + 1.0 - 1.3 = -0.2 -> pi - 0.2
  ev.take(located(ep2, pose_at), pose_at);
  CHECK(near(ev.entry(0).report.phi, kPi - 0.2, 1e-12));
  for (int w = 0; w < 4; ++w) {
    if (!ev.entry(w).have) continue;
    CHECK(ev.entry(w).report.phi >= 0.0);
    CHECK(ev.entry(w).report.phi < kPi);
  }
}

TEST_CASE("WhiskEvidence: a negative peak sample is taken as the onset", "[mapping][evidence]") {
  WhiskEvidence ev(mounts(), WhiskerBeam{});
  ev.begin();
  signal::ContactEpisode ep = episode(500, 0.2);
  ep.whiskers[1] = touch(0.05, -1);
  ev.take(located(ep, poseAt), poseAt);
  CHECK(ev.entry(1).report.robot.theta == poseAt(500).theta);
  CHECK(near(ev.entry(1).report.phi, 0.2, 1e-12));
}

TEST_CASE("WhiskEvidence: touches without r or without a ramp are counted, not reported",
          "[mapping][evidence]") {
  WhiskEvidence ev(mounts(), WhiskerBeam{});
  ev.begin();
  signal::ContactEpisode no_phi = episode(0, 0.5, /*has_orientation=*/false);
  no_phi.whiskers[0] = touch(0.05, 3);  // no template orientation: still located and reported
  no_phi.whiskers[1] = touch(0.05, 3, /*has_r=*/false);  // no radial model
  signal::ContactEpisode ok = episode(300, 0.5);
  ok.whiskers[2] = touch(0.05, 3, /*has_r=*/true, /*ramp=*/false);  // never bent through the band
  ok.whiskers[3] = touch(0.05, 3);
  CHECK(ev.take(located(no_phi, poseAt), poseAt) == 0b0011u);
  CHECK(ev.take(located(ok, poseAt), poseAt) == 0b1100u);
  CHECK(ev.entry(0).have);
  CHECK_FALSE(ev.entry(0).has_phi);
  CHECK_FALSE(ev.entry(1).has_r);
  CHECK_FALSE(ev.entry(2).located);
  std::vector<ContactReport> reports;
  std::vector<FreeRay> rays;
  ev.end(reports, rays);
  REQUIRE(reports.size() == 2);
  CHECK(reports[0].whisker == 0);
  CHECK(reports[1].whisker == 3);
  CHECK(ev.counts().reports == 2);
  CHECK(ev.counts().no_radial == 1);
  CHECK(ev.counts().no_ramp == 1);
}

TEST_CASE("WhiskEvidence: a contact is placed where the rest whisker met it at the touch heading",
          "[mapping][evidence]") {
  const std::vector<WhiskerMount> m = defaultWhiskerArray();
  const auto still = [](std::uint64_t i) { return Pose2{1.0, 2.0, 0.3 + 1e-4 * static_cast<double>(i)}; };
  WhiskEvidence ev(m, WhiskerBeam{});
  ev.begin();
  signal::ContactEpisode ep = episode(1000, 0.0);
  ep.whiskers[2] = touch(0.1, 400);
  ev.take(located(ep, still, m, /*dpsi=*/0.03), still);
  const ContactReport& r = ev.entry(2).report;
  CHECK(r.robot.x == 1.0);
  CHECK(r.robot.y == 2.0);
  CHECK(r.robot.theta == Approx(still(1400).theta - 0.03));
  CHECK(r.r == Approx(0.1).margin(1e-7));
  CHECK_FALSE(r.oriented);  // one whisker cannot tell a face from an edge
  CHECK(ev.entry(2).tip);   // 0.1 m of 0.14: within the 50 mm tip zone
}

TEST_CASE("WhiskEvidence: two tip contacts further apart than a leg lie on one face",
          "[mapping][evidence]") {
  const std::vector<WhiskerMount> m = defaultWhiskerArray();
  // A wall along y = 0.25 in front of a robot at the origin facing +y. The default mounts are
  // radial, so whisker w's tip is 0.305 m out along heading + bearing: on the wall at
  // heading + bearing = asin(0.25 / 0.305) (right of the robot) or pi - that (left).
  const Pose2 robot{0.0, 0.0, kPi / 2};
  const double reach = m[0].base.norm() + m[0].length;
  const double a = std::asin(0.25 / reach);
  std::vector<Pose2> at(4, robot);
  at[0] = Pose2{0.0, 0.0, a - m[0].bearing};
  at[3] = Pose2{0.0, 0.0, kPi - a - m[3].bearing};
  WhiskEvidence ev(m, WhiskerBeam{});
  ev.begin();
  signal::ContactEpisode ep = episode(0, 0.0);
  ep.whiskers[0] = touch(m[0].length, 10);
  ep.whiskers[3] = touch(m[3].length, 40);
  const auto pose_at = [&](std::uint64_t i) { return i == 10 ? at[0] : i == 40 ? at[3] : robot; };
  ev.take(located(ep, pose_at, m), pose_at);
  std::vector<ContactReport> reports;
  std::vector<FreeRay> rays;
  ev.end(reports, rays);
  REQUIRE(reports.size() == 2);
  for (const ContactReport& r : reports) {
    INFO("whisker " << r.whisker);
    CHECK(r.oriented);
    // The face runs along x: phi + the robot's heading is 0 modulo pi.
    CHECK(std::abs(wrapPeriod(r.phi + r.robot.theta, kPi)) < 1e-6);
  }
  // Both know how long a stretch of the face they span: the distance between the two tips.
  const Vec2 tip0 = m[0].pointAt(reports[0].robot, reports[0].r);
  const Vec2 tip3 = m[3].pointAt(reports[1].robot, reports[1].r);
  CHECK(reports[0].face_span == Approx((tip0 - tip3).norm()).margin(1e-9));
  CHECK(reports[1].face_span == reports[0].face_span);
  CHECK(reports[0].face_span > 0.12);
  CHECK(ev.counts().flat == 2);
  // Two contacts on one leg (5 cm apart) stay points.
  ev.begin();
  signal::ContactEpisode leg = episode(0, 0.0);
  leg.whiskers[1] = touch(0.14, 10);
  leg.whiskers[2] = touch(0.14, 10);
  ev.take(located(leg, [&](std::uint64_t) { return robot; }, m), [&](std::uint64_t) { return robot; });
  reports.clear();
  ev.end(reports, rays);
  REQUIRE(reports.size() == 2);
  CHECK_FALSE(reports[0].oriented);
  CHECK_FALSE(reports[1].oriented);
  CHECK(reports[0].face_span == 0.0);
  CHECK(reports[1].face_span == 0.0);
}

TEST_CASE("WhiskEvidence: end() appends to what the vectors hold", "[mapping][evidence]") {
  WhiskEvidence ev(mounts(), WhiskerBeam{});
  ev.begin();
  signal::ContactEpisode ep = episode(0, 0.5);
  ep.whiskers[0] = touch(0.05, 3);
  ev.take(located(ep, poseAt), poseAt);
  ev.sample(poseAt(0), 0b0001);
  std::vector<ContactReport> reports(2);
  std::vector<FreeRay> rays(5);
  ev.end(reports, rays);
  CHECK(reports.size() == 3);
  CHECK(rays.size() == 5 + 3);  // whiskers 1..3 were free in the one sample
}

TEST_CASE("WhiskEvidence: discardReports forgets the entries and keeps the free-ray samples",
          "[mapping][evidence]") {
  WhiskEvidence ev(mounts(), WhiskerBeam{});
  ev.begin();
  for (int i = 0; i < 10; ++i) ev.sample(poseAt(static_cast<std::uint64_t>(120 * i)), 0);
  signal::ContactEpisode before = episode(100, 0.5);
  before.whiskers[0] = touch(0.05, 3);
  before.whiskers[1] = touch(0.06, 3);
  CHECK(ev.take(located(before, poseAt), poseAt) == 0b0011u);
  ev.discardReports();
  for (int w = 0; w < 4; ++w) CHECK_FALSE(ev.entry(w).have);
  // A whisker's first touch after the discard counts as its first of the whisk.
  signal::ContactEpisode after = episode(2000, 0.7);
  after.whiskers[1] = touch(0.08, 4);
  CHECK(ev.take(located(after, poseAt), poseAt) == 0b0010u);
  std::vector<ContactReport> reports;
  std::vector<FreeRay> rays;
  ev.end(reports, rays);
  REQUIRE(reports.size() == 1);
  CHECK(reports[0].whisker == 1);
  CHECK(reports[0].r == Approx(0.08).margin(1e-7));
  CHECK(rays.size() == 10 * 4);  // every whisker free in all ten samples kept
}

TEST_CASE("WhiskEvidence: begin() forgets the last whisk's entries and samples",
          "[mapping][evidence]") {
  WhiskEvidence ev(mounts(), WhiskerBeam{});
  ev.begin();
  ev.sample(poseAt(0), 0);
  signal::ContactEpisode ep = episode(0, 0.5);
  ep.whiskers[2] = touch(0.05, 3);
  ev.take(located(ep, poseAt), poseAt);
  ev.begin();
  CHECK_FALSE(ev.entry(2).have);
  std::vector<ContactReport> reports;
  std::vector<FreeRay> rays;
  ev.end(reports, rays);
  CHECK(reports.empty());
  CHECK(rays.empty());
  CHECK(ev.counts().whisks == 2);
}

TEST_CASE("WhiskEvidence: free rays only where the whisker shows no contact within kFreeGuard "
          "samples",
          "[mapping][evidence]") {
  const std::vector<WhiskerMount> m = mounts();
  WhiskEvidence ev(m, WhiskerBeam{});
  ev.begin();
  constexpr int kSamples = 30;
  const int g = WhiskEvidence::kFreeGuard;
  // Whisker 1 touches at sample 12; whisker 3 at samples 1 and 28 (near both ends); bit 7 is
  // no whisker's and changes nothing.
  std::vector<std::uint32_t> mask(kSamples, 0);
  mask[12] |= 1u << 1;
  mask[1] |= 1u << 3;
  mask[28] |= 1u << 3;
  mask[20] |= 1u << 7;
  std::vector<Pose2> poses;
  for (int i = 0; i < kSamples; ++i) {
    poses.push_back({0.3 * i, -0.1 * i, -1.0 + 0.15 * i});  // every ray distinct
    ev.sample(poses.back(), mask[static_cast<std::size_t>(i)]);
  }
  std::vector<ContactReport> reports;
  std::vector<FreeRay> rays;
  ev.end(reports, rays);

  auto free = [&](int w, int i) {
    for (int j = std::max(0, i - g); j <= std::min(kSamples - 1, i + g); ++j)
      if (mask[static_cast<std::size_t>(j)] & (1u << w)) return false;
    return true;
  };
  // The expected rays, computed here from the mount and pose by rotation by hand.
  std::vector<FreeRay> expected;
  for (int i = 0; i < kSamples; ++i) {
    for (int w = 0; w < 4; ++w) {
      if (!free(w, i)) continue;
      const Pose2& p = poses[static_cast<std::size_t>(i)];
      const WhiskerMount& mw = m[static_cast<std::size_t>(w)];
      const double c = std::cos(p.theta), s = std::sin(p.theta);
      const Vec2 a{p.x + c * mw.base.x() - s * mw.base.y(), p.y + s * mw.base.x() + c * mw.base.y()};
      const Vec2 b{a.x() + mw.length * std::cos(p.theta + mw.bearing),
                   a.y() + mw.length * std::sin(p.theta + mw.bearing)};
      expected.push_back({a, b});
    }
  }
  // Whisker 1: samples 12 - g .. 12 + g excluded; whisker 3: 0 .. 1 + g and 28 - g .. 29.
  const std::size_t n1 = kSamples - (2 * g + 1);
  const std::size_t n3 = kSamples - (2 + g) - (2 + g);
  CHECK(expected.size() == 2 * kSamples + n1 + n3);
  REQUIRE(rays.size() == expected.size());
  std::vector<bool> used(rays.size(), false);
  for (const FreeRay& e : expected) {
    bool found = false;
    for (std::size_t k = 0; k < rays.size() && !found; ++k) {
      if (used[k]) continue;
      if ((rays[k].a - e.a).norm() < 1e-12 && (rays[k].b - e.b).norm() < 1e-12) {
        used[k] = true;
        found = true;
      }
    }
    INFO("ray " << e.a.transpose() << " -> " << e.b.transpose());
    CHECK(found);
  }
}

TEST_CASE("WhiskEvidence: a ray starts at the mount's base and points along its bearing",
          "[mapping][evidence]") {
  WhiskEvidence ev({{{0.10, 0.05}, 0.3, 0.14}}, WhiskerBeam{});
  ev.begin();
  ev.sample({1.0, 2.0, kPi / 2}, 0);
  std::vector<ContactReport> reports;
  std::vector<FreeRay> rays;
  ev.end(reports, rays);
  REQUIRE(rays.size() == 1);
  // Base (0.10, 0.05) turned a quarter turn: (-0.05, 0.10) from (1, 2).
  CHECK(near(rays[0].a.x(), 0.95, 1e-12));
  CHECK(near(rays[0].a.y(), 2.10, 1e-12));
  CHECK(near((rays[0].b - rays[0].a).norm(), 0.14, 1e-12));
  CHECK(near(std::atan2(rays[0].b.y() - rays[0].a.y(), rays[0].b.x() - rays[0].a.x()),
             kPi / 2 + 0.3, 1e-12));
}

TEST_CASE("WhiskEvidence: whiskers beyond the mounts are ignored", "[mapping][evidence]") {
  const std::vector<WhiskerMount> two = {{{0.10, 0.05}, 0.3, 0.14}, {{0.10, -0.05}, -0.3, 0.14}};
  WhiskEvidence ev(two, WhiskerBeam{});
  ev.begin();
  signal::ContactEpisode ep = episode(0, 0.5);
  ep.whiskers[1] = touch(0.05, 3);
  ep.whiskers[3] = touch(0.05, 3);
  CHECK(ev.take(located(ep, poseAt, two), poseAt) == 0b0010u);
  std::vector<ContactReport> reports;
  std::vector<FreeRay> rays;
  ev.end(reports, rays);
  REQUIRE(reports.size() == 1);
  CHECK(reports[0].whisker == 1);
}
