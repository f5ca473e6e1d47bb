// The sensor-model interface: what the robot reports at one pose. The ray model (sim/) finds
// contacts with ODE rays and adds the Gaussian noise of eqs. 4-5; a later issue plugs in bending
// whiskers and the real classifiers behind the same interface.
#pragma once

#include <string>
#include <vector>

#include "crunch/blackboard/params.h"
#include "crunch/core/geometry.h"
#include "crunch/core/result.h"
#include "crunch/core/rng.h"
#include "crunch/blackboard/free_space.h"
#include "crunch/robot/shapelet.h"

namespace crunch {

// Noise regimes of ARCHITECTURE.md §4.
struct NoiseRegime {
  std::string name = "realistic";
  double sigma_r = 0.005;           // metres
  double sigma_phi = kPi / 32.0;    // radians

  static NoiseRegime ideal() { return {"ideal", 0.0, 0.0}; }
  static NoiseRegime realistic() { return {"realistic", 0.005, kPi / 32.0}; }
  static NoiseRegime noisy() { return {"noisy", 0.025, kPi / 8.0}; }
  // Not injected: the errors the paper measured for its own classifiers (Table 1, all whiskers:
  // sigma_r 4.98 mm; Fig. 10: 21.2 degrees), which the physics chain's reports carry. The
  // blackboard's shapelet sigmas for the physics sensor and the real robot.
  static NoiseRegime classifiers() { return {"physics", 0.00498, 21.2 * kPi / 180.0}; }

  // sigma_r 0..1 m and sigma_phi 0..pi. okStatus(), or an Error naming the field.
  Status validate() const;
};

// "ideal", "realistic" or "noisy" (ARCHITECTURE.md §4 --noise); an Error naming the word and
// the choices otherwise.
Result<NoiseRegime> noiseRegimeByName(const std::string& name);

// Eq. 12's sigma_r^S, sigma_theta^S "model sensor noise": `model` with its shapelet sigmas
// raised to the sensor's where they are smaller; under the walled models (ModelParams::walled())
// to sqrt(2) x the sensor's, so that eq. 12's exp(-(d / sigma)^2) is the noise's Gaussian.
ModelParams withSensorNoise(ModelParams model, const NoiseRegime& noise);

class SensorModel {
 public:
  virtual ~SensorModel() = default;
  // Appends to `out` the reports of one body whisk at `pose`. Uses `rng` for all noise.
  virtual void sense(const Pose2& pose, Rng& rng, std::vector<ContactReport>& out) = 0;
  virtual const std::vector<WhiskerMount>& mounts() const = 0;
  // Appends to `out` the whisker samples of the last sense() call that touched nothing
  // (negative evidence, free_space.h). A model that cannot tell appends nothing.
  virtual void freeRays(std::vector<FreeRay>& out) const { (void)out; }
};

}  // namespace crunch
