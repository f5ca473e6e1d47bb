#include "crunch/mapping/sensor_model.h"

#include <algorithm>
#include <cmath>

#include "crunch/core/range_check.h"

namespace crunch {

Status NoiseRegime::validate() const {
  if (auto s = checkRange("sigma_r", sigma_r, 0.0, 1.0); !s) return s;
  return checkRange("sigma_phi", sigma_phi, 0.0, kPi);
}

Result<NoiseRegime> noiseRegimeByName(const std::string& name) {
  if (name == "ideal") return NoiseRegime::ideal();
  if (name == "realistic") return NoiseRegime::realistic();
  if (name == "noisy") return NoiseRegime::noisy();
  return Error{"noise: unknown regime '" + name + "' (expected ideal, realistic or noisy)"};
}

ModelParams withSensorNoise(ModelParams model, const NoiseRegime& noise) {
  // Eq. 12's kernel exp(-(d / sigma)^2) is a Gaussian of standard deviation sigma / sqrt(2):
  // the walled models take sigma = sqrt(2) x the sensor's, so that the kernel is the noise's own
  // Gaussian; with sigma = the sensor's a wall, which cannot bend to its contacts' noise, paid
  // twice the misfit it should against legs, which can (docs/BLACKBOARD.md "Noisy walls"). The
  // paper's model keeps sigma = the sensor's, and so its figures.
  const double k = model.walled() ? std::sqrt(2.0) : 1.0;
  model.sigma_r_shapelet = std::max(model.sigma_r_shapelet, k * noise.sigma_r);
  model.sigma_theta_shapelet = std::max(model.sigma_theta_shapelet, k * noise.sigma_phi);
  return model;
}

}  // namespace crunch
