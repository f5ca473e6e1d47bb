// Tests of WhiskEvidence (crunch/session/whisk_evidence.h): from synthetic contact episodes and
// negative-evidence samples to the mapper's reports and free rays.
#include "crunch/session/whisk_evidence.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <random>
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

signal::WhiskerContact touch(double r, std::int64_t peak, bool has_r = true) {
  signal::WhiskerContact c;
  c.touched = true;
  c.onset_sample = 0;
  c.peak_sample = peak;
  c.f1 = 0.01 * static_cast<double>(peak);
  c.has_r = has_r;
  c.r = r;
  return c;
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

TEST_CASE("WhiskEvidence: halfTurn maps any angle to 0 <= a < pi", "[mapping][evidence]") {
  CHECK(halfTurn(0.0) == 0.0);
  CHECK(near(halfTurn(kPi), 0.0));
  CHECK(near(halfTurn(-0.1), kPi - 0.1));
  CHECK(near(halfTurn(2.0 * kPi + 0.2), 0.2, 1e-9));
  CHECK(near(halfTurn(kPi + 0.3), 0.3, 1e-12));
  CHECK(near(halfTurn(-3.0 * kPi + 1.0), 1.0, 1e-9));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-40.0, 40.0);
  for (int i = 0; i < 10000; ++i) {
    const double a = u(rng);
    const double h = halfTurn(a);
    REQUIRE(h >= 0.0);
    REQUIRE(h < kPi);
    // Same orientation modulo pi.
    const double k = std::round((a - h) / kPi);
    REQUIRE(near(a - h, k * kPi, 1e-9));
  }
}

TEST_CASE("WhiskEvidence: each whisker reports once per whisk, from its first episode",
          "[mapping][evidence]") {
  WhiskEvidence ev(mounts());
  ev.begin();
  signal::ContactEpisode a = episode(100, 0.5);
  a.whiskers[0] = touch(0.05, 10);
  a.whiskers[2] = touch(0.07, 30);
  signal::ContactEpisode b = episode(900, 1.0);
  b.whiskers[0] = touch(0.09, 5);  // second touch of whisker 0: ignored
  b.whiskers[1] = touch(0.04, 20);
  CHECK(ev.take(a, poseAt) == 0b0101u);
  CHECK(ev.take(b, poseAt) == 0b0010u);
  CHECK(ev.entry(0).have);
  CHECK(ev.entry(0).f1 == a.whiskers[0].f1);
  CHECK(ev.entry(0).report.r == 0.05);
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
  CHECK(find(0)->r == 0.05);
  CHECK(find(1)->r == 0.04);
  CHECK(find(2)->r == 0.07);
  // The report's robot pose is the pose at the whisker's peak sample.
  const Pose2 p0 = poseAt(110), p1 = poseAt(920), p2 = poseAt(130);
  CHECK((find(0)->robot.x == p0.x && find(0)->robot.y == p0.y && find(0)->robot.theta == p0.theta));
  CHECK((find(1)->robot.x == p1.x && find(1)->robot.theta == p1.theta));
  CHECK((find(2)->robot.x == p2.x && find(2)->robot.theta == p2.theta));
  CHECK(ev.counts().episodes == 2);
  CHECK(ev.counts().reports == 3);
  CHECK(ev.counts().whisks == 1);
  CHECK(rays.empty());  // no negative-evidence samples taken
}

TEST_CASE("WhiskEvidence: r is clamped to 0 .. the mount's length", "[mapping][evidence]") {
  WhiskEvidence ev(mounts());
  ev.begin();
  signal::ContactEpisode ep = episode(0, 0.0);
  ep.whiskers[0] = touch(-0.03, 1);  // below the base
  ep.whiskers[1] = touch(0.25, 1);   // past whisker 1's 0.10 m tip
  ep.whiskers[2] = touch(0.0625, 1);
  ep.whiskers[3] = touch(0.20, 1);   // exactly the tip
  ev.take(ep, poseAt);
  CHECK(ev.entry(0).report.r == 0.0);
  CHECK(ev.entry(1).report.r == 0.10);
  CHECK(ev.entry(2).report.r == 0.0625);
  CHECK(ev.entry(3).report.r == 0.20);
}

TEST_CASE("WhiskEvidence: phi is the template angle turned from the onset heading to the peak "
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
  WhiskEvidence ev(mounts());
  ev.begin();
  signal::ContactEpisode ep = episode(1000, 0.4);
  ep.whiskers[0] = touch(0.05, 10);  // 0.4 + 1.0 - 1.3 = 0.1
  ep.whiskers[1] = touch(0.05, 20);  // 0.4 + 1.0 + 2.0 = 3.4 -> 3.4 - pi
  ep.whiskers[2] = touch(0.05, 30);  // 0.4 + 1.0 - 1.1 = 0.3
  ep.whiskers[3] = touch(0.05, 0);   // peak at onset: 0.4
  ev.take(ep, pose_at);
  CHECK(near(ev.entry(0).report.phi, 0.1, 1e-12));
  CHECK(near(ev.entry(1).report.phi, 3.4 - kPi, 1e-12));
  CHECK(near(ev.entry(2).report.phi, 0.3, 1e-12));
  CHECK(near(ev.entry(3).report.phi, 0.4, 1e-12));

  // A turn the other way gives a negative angle, reported as its [0, pi) equivalent.
  ev.begin();
  signal::ContactEpisode ep2 = episode(1000, 0.1);
  ep2.whiskers[0] = touch(0.05, 10);  // 0.1 + 1.0 - 1.3 = -0.2 -> pi - 0.2
  ev.take(ep2, pose_at);
  CHECK(near(ev.entry(0).report.phi, kPi - 0.2, 1e-12));
  for (int w = 0; w < 4; ++w) {
    if (!ev.entry(w).have) continue;
    CHECK(ev.entry(w).report.phi >= 0.0);
    CHECK(ev.entry(w).report.phi < kPi);
  }
}

TEST_CASE("WhiskEvidence: a negative peak sample is taken as the onset", "[mapping][evidence]") {
  WhiskEvidence ev(mounts());
  ev.begin();
  signal::ContactEpisode ep = episode(500, 0.2);
  ep.whiskers[1] = touch(0.05, -1);
  ev.take(ep, poseAt);
  CHECK(ev.entry(1).report.robot.theta == poseAt(500).theta);
  CHECK(near(ev.entry(1).report.phi, 0.2, 1e-12));
}

TEST_CASE("WhiskEvidence: touches without r or without orientation are counted, not reported",
          "[mapping][evidence]") {
  WhiskEvidence ev(mounts());
  ev.begin();
  signal::ContactEpisode no_phi = episode(0, 0.5, /*has_orientation=*/false);
  no_phi.whiskers[0] = touch(0.05, 3);
  no_phi.whiskers[1] = touch(0.05, 3, /*has_r=*/false);  // neither r nor orientation
  signal::ContactEpisode ok = episode(300, 0.5);
  ok.whiskers[2] = touch(0.05, 3, /*has_r=*/false);
  ok.whiskers[3] = touch(0.05, 3);
  CHECK(ev.take(no_phi, poseAt) == 0b0011u);
  CHECK(ev.take(ok, poseAt) == 0b1100u);
  CHECK(ev.entry(0).have);
  CHECK_FALSE(ev.entry(0).has_phi);
  CHECK_FALSE(ev.entry(2).has_r);
  std::vector<ContactReport> reports;
  std::vector<FreeRay> rays;
  ev.end(reports, rays);
  REQUIRE(reports.size() == 1);
  CHECK(reports[0].whisker == 3);
  CHECK(ev.counts().reports == 1);
  CHECK(ev.counts().no_radial >= 1);       // whisker 2 (and whisker 1 if r is checked first)
  CHECK(ev.counts().no_orientation >= 1);  // whisker 0
  // Every touched whisker without a report is counted exactly once.
  CHECK(ev.counts().no_radial + ev.counts().no_orientation == 3);
}

TEST_CASE("WhiskEvidence: end() appends to what the vectors hold", "[mapping][evidence]") {
  WhiskEvidence ev(mounts());
  ev.begin();
  signal::ContactEpisode ep = episode(0, 0.5);
  ep.whiskers[0] = touch(0.05, 3);
  ev.take(ep, poseAt);
  ev.sample(poseAt(0), 0b0001);
  std::vector<ContactReport> reports(2);
  std::vector<FreeRay> rays(5);
  ev.end(reports, rays);
  CHECK(reports.size() == 3);
  CHECK(rays.size() == 5 + 3);  // whiskers 1..3 were free in the one sample
}

TEST_CASE("WhiskEvidence: discardReports forgets the entries and keeps the free-ray samples",
          "[mapping][evidence]") {
  WhiskEvidence ev(mounts());
  ev.begin();
  for (int i = 0; i < 10; ++i) ev.sample(poseAt(static_cast<std::uint64_t>(120 * i)), 0);
  signal::ContactEpisode before = episode(100, 0.5);
  before.whiskers[0] = touch(0.05, 3);
  before.whiskers[1] = touch(0.06, 3);
  CHECK(ev.take(before, poseAt) == 0b0011u);
  ev.discardReports();
  for (int w = 0; w < 4; ++w) CHECK_FALSE(ev.entry(w).have);
  // A whisker's first touch after the discard counts as its first of the whisk.
  signal::ContactEpisode after = episode(2000, 0.7);
  after.whiskers[1] = touch(0.08, 4);
  CHECK(ev.take(after, poseAt) == 0b0010u);
  std::vector<ContactReport> reports;
  std::vector<FreeRay> rays;
  ev.end(reports, rays);
  REQUIRE(reports.size() == 1);
  CHECK(reports[0].whisker == 1);
  CHECK(reports[0].r == 0.08);
  CHECK(rays.size() == 10 * 4);  // every whisker free in all ten samples kept
}

TEST_CASE("WhiskEvidence: begin() forgets the last whisk's entries and samples",
          "[mapping][evidence]") {
  WhiskEvidence ev(mounts());
  ev.begin();
  ev.sample(poseAt(0), 0);
  signal::ContactEpisode ep = episode(0, 0.5);
  ep.whiskers[2] = touch(0.05, 3);
  ev.take(ep, poseAt);
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
  WhiskEvidence ev(m);
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
  WhiskEvidence ev({{{0.10, 0.05}, 0.3, 0.14}});
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
  WhiskEvidence ev({{{0.10, 0.05}, 0.3, 0.14}, {{0.10, -0.05}, -0.3, 0.14}});
  ev.begin();
  signal::ContactEpisode ep = episode(0, 0.5);
  ep.whiskers[1] = touch(0.05, 3);
  ep.whiskers[3] = touch(0.05, 3);
  CHECK(ev.take(ep, poseAt) == 0b0010u);
  std::vector<ContactReport> reports;
  std::vector<FreeRay> rays;
  ev.end(reports, rays);
  REQUIRE(reports.size() == 1);
  CHECK(reports[0].whisker == 1);
}
