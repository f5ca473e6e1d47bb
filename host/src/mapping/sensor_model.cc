#include "crunch/mapping/sensor_model.h"

#include <algorithm>

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
  model.sigma_r_shapelet = std::max(model.sigma_r_shapelet, noise.sigma_r);
  model.sigma_theta_shapelet = std::max(model.sigma_theta_shapelet, noise.sigma_phi);
  return model;
}

}  // namespace crunch
