// Noise regimes and eq. 12's shapelet sigmas matched to them (mapping/sensor_model.h).
#include <catch2/catch.hpp>
#include <cmath>

#include "crunch/blackboard/factors.h"
#include "crunch/mapping/sensor_model.h"

using namespace crunch;

TEST_CASE("noiseRegimeByName: the three regimes, and an error naming a wrong word", "[mapping]") {
  CHECK(noiseRegimeByName("noisy").value().sigma_r == NoiseRegime::noisy().sigma_r);
  CHECK(noiseRegimeByName("ideal").value().sigma_r == 0.0);
  const auto bad = noiseRegimeByName("loud");
  REQUIRE_FALSE(bad);
  CHECK(bad.error().message.find("loud") != std::string::npos);
}

TEST_CASE("withSensorNoise: the walled models' kernel is the sensor noise's Gaussian",
          "[mapping]") {
  const NoiseRegime noisy = NoiseRegime::noisy();
  ModelParams paper;
  ModelParams walls;
  walls.objects = ObjectModel::kWalls;
  // The paper's model: sigma raised to the sensor's (its figures as they were).
  CHECK(withSensorNoise(paper, noisy).sigma_r_shapelet == noisy.sigma_r);
  CHECK(withSensorNoise(paper, noisy).sigma_theta_shapelet == noisy.sigma_phi);
  // Walls: a shapelet one sensor sigma off a wall, at the wall's own angle, has the kernel
  // exp(-1/2) of a Gaussian with the sensor's sigma, in distance and in angle.
  const ModelParams m = withSensorNoise(walls, noisy);
  WallHyp w;
  w.a = {0, 0};
  w.b = {2, 0};
  Shapelet s;
  s.x = 1.0;
  s.y = noisy.sigma_r;
  s.ox = 1.0;
  s.oy = 0.1;
  s.phi = 0.0;
  CHECK(deltaWS(w, s, m) == Approx(0.5));
  s.y = 0.0;
  s.phi = noisy.sigma_phi;
  CHECK(deltaWS(w, s, m) == Approx(0.5));
  // Never below the model's own sigmas: an ideal sensor leaves them.
  CHECK(withSensorNoise(walls, NoiseRegime::ideal()).sigma_r_shapelet == walls.sigma_r_shapelet);
}
