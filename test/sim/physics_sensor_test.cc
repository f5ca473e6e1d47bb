// The physics sensor (physics_sensor.h): skipping untouchable whisks (issue 12) senses what the
// whisks in ODE sense, and its options are validated.
#include <catch2/catch.hpp>
#include <cmath>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/core/rng.h"
#include "crunch/robot/shapelet.h"
#include "crunch/robot/whiskers.h"
#include "crunch/scene/scene.h"
#include "crunch/signal/models_io.h"
#include "crunch_sim/physics_sensor.h"
#include "crunch_sim/whisk_clearance.h"
#include "crunch_sim/world.h"
#include "support/one_table.h"

using crunch::ContactReport;
using crunch::defaultWhiskerArray;
using crunch::FreeRay;
using crunch::kPi;
using crunch::Pose2;
using crunch::Rng;
using crunch::sim::PhysicsSensorModel;
using crunch::sim::physicsSensorOptions;
using crunch::sim::World;

namespace {

// What one run of the sensor gave at each pose.
struct Sensed {
  std::vector<std::vector<ContactReport>> reports;  // per pose
  std::vector<std::vector<FreeRay>> free;            // per pose
  int skipped = 0;
  int episodes = 0;
  long long partly_free = 0;  // whisker-steps free-running beside whiskers in ODE
  long long ode_whisker_steps = 0;
  std::vector<long long> ode_per_pose;  // whisker-steps in ODE at each pose
};

// The one-table scene (3 x 3 m, the standard table at the centre): whisks that touch a leg, each
// after one that touches nothing, so that a skipped whisk's effect on the detectors
// (their rest tracking saw no ringing) reaches the reports after it.
std::vector<Pose2> scenePoses() {
  return {
      {0.70, 0.70, 0.5},     // free
      {0.85, 1.275, 0.0},    // the near-left leg, from 0.25 m
      {2.20, 2.30, 2.5},     // free
      {2.15, 1.725, kPi},    // the far-right leg, from the right
      {0.30, 0.60, kPi},     // the left wall, 5 mm inside the straight whiskers' reach: an approach
  };
}

Sensed run(bool skip) {
  const auto world = World::build(oneTableScene());
  auto models = crunch::signal::loadModels(std::string(CRUNCH_SOURCE_DIR) +
                                           "/models/sim_models.json");
  REQUIRE(models);
  PhysicsSensorModel::Options o = physicsSensorOptions(1);
  o.skip_untouchable = skip;
  const std::vector<Pose2> poses = scenePoses();
  auto sensor = PhysicsSensorModel::create(*world, defaultWhiskerArray(), models.value(), poses, o);
  REQUIRE(sensor);
  Sensed s;
  Rng rng(1);
  for (const Pose2& p : poses) {
    s.reports.emplace_back();
    const long long before = sensor.value()->rig().robot().odeWhiskerSteps();
    sensor.value()->sense(p, rng, s.reports.back());
    s.ode_per_pose.push_back(sensor.value()->rig().robot().odeWhiskerSteps() - before);
    s.free.emplace_back();
    sensor.value()->freeRays(s.free.back());
  }
  s.skipped = sensor.value()->skippedWhisks();
  s.episodes = sensor.value()->errors().episodes;
  s.partly_free = sensor.value()->rig().robot().partlyFreeWhiskerSteps();
  s.ode_whisker_steps = sensor.value()->rig().robot().odeWhiskerSteps();
  return s;
}

}  // namespace

TEST_CASE("PhysicsSensor: skipping untouchable whisks senses what ODE senses", "[sim][skip]") {
  // Exactly the same: reports (whisker, r, phi, pose) and free rays bit for bit. A skipped whisk
  // turns the base exactly as ODE does and replays ODE's free whisker ringing to 2e-13 rad, 2e-9
  // of a Hall code (WhiskeredRobot, free-running), so every Hall code is the same unless the
  // noise put one within 2e-9 of a rounding edge: about one chance in a thousand over this test's
  // 200 000 readings. (Whiskers held straight instead, base angles 0, moved r by up to 1.6 um and
  // phi by one sample's turn on the default arena: the detectors' rest tracking missed the
  // ringing. Any change of that size fails here.)
  const Sensed ode = run(false);
  const Sensed skipped = run(true);

  const std::size_t n = scenePoses().size();
  REQUIRE(ode.reports.size() == n);
  CHECK(ode.skipped == 0);
  CHECK(skipped.skipped == 2);  // the two free whisks, and only those
  // In the two touching whisks the whiskers on the far side cannot reach the leg: they run free
  // while the near ones run in ODE (setFreeWhiskers), and nothing sensed changes either.
  CHECK(ode.partly_free == 0);
  CHECK(skipped.partly_free > 0);
  CHECK(skipped.episodes == ode.episodes);
  // Time slices: each whisker is in ODE only where it can touch something (and until it is back
  // on its free trajectory), so every touching whisk, the approach's too, simulates fewer
  // whisker-steps in ODE, and the free whisks none.
  for (std::size_t i = 0; i < n; ++i) {
    std::cout << "pose " << i << ": whisker-steps in ODE " << ode.ode_per_pose[i] << " -> "
              << skipped.ode_per_pose[i] << "\n";
    CHECK(skipped.ode_per_pose[i] < ode.ode_per_pose[i]);
  }
  CHECK(skipped.ode_per_pose[0] == 0);
  CHECK(skipped.ode_per_pose[2] == 0);
  int reports = 0;
  for (std::size_t i = 0; i < n; ++i) {
    INFO("pose " << i);
    REQUIRE(skipped.reports[i].size() == ode.reports[i].size());
    for (std::size_t k = 0; k < ode.reports[i].size(); ++k) {
      const ContactReport& a = ode.reports[i][k];
      const ContactReport& b = skipped.reports[i][k];
      INFO("report " << k << " of whisker " << a.whisker);
      CHECK(b.whisker == a.whisker);
      CHECK(b.robot.x == a.robot.x);
      CHECK(b.robot.y == a.robot.y);
      CHECK(b.robot.theta == a.robot.theta);
      CHECK(b.r == a.r);
      CHECK(b.phi == a.phi);
      ++reports;
    }
    REQUIRE(skipped.free[i].size() == ode.free[i].size());
    for (std::size_t k = 0; k < ode.free[i].size(); ++k) {
      CHECK(skipped.free[i][k].a == ode.free[i][k].a);
      CHECK(skipped.free[i][k].b == ode.free[i][k].b);
    }
  }
  // The scene does what it is for: the touching whisks report, the free ones give free rays.
  CHECK(reports >= 2);
  for (const std::size_t free_pose : {0u, 2u}) {
    CHECK(ode.reports[free_pose].empty());
    CHECK(!ode.free[free_pose].empty());
  }
  for (const std::size_t touching : {1u, 3u, 4u}) CHECK(!ode.reports[touching].empty());
}

TEST_CASE("PhysicsSensor: the skip options are validated", "[sim][skip]") {
  PhysicsSensorModel::Options o = physicsSensorOptions(1);
  CHECK(o.skip_untouchable);  // on by default
  CHECK(o.validate());
  o.skip_margin = crunch::sim::kMinSkipMargin;
  CHECK(o.validate());
  o.skip_margin = 0.1;
  CHECK(o.validate());
  for (const double bad : {0.0, 0.004, -0.01, 0.11, std::nan("")}) {
    o.skip_margin = bad;
    const crunch::Status s = o.validate();
    REQUIRE_FALSE(s);
    CHECK_THAT(s.error().message, Catch::Contains("skip_margin"));
  }
  // create() refuses them too.
  const auto world = World::build(oneTableScene());
  auto models = crunch::signal::loadModels(std::string(CRUNCH_SOURCE_DIR) +
                                           "/models/sim_models.json");
  REQUIRE(models);
  o.skip_margin = 0.001;
  auto made = PhysicsSensorModel::create(*world, defaultWhiskerArray(), models.value(),
                                         {{0.7, 0.7, 0.5}}, o);
  REQUIRE_FALSE(made);
  CHECK_THAT(made.error().message, Catch::Contains("skip_margin"));
}
