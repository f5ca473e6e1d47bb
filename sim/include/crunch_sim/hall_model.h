// The MLX90333 Hall sensor under a whisker's follicle (paper §2.1): turns the base's two
// deflection angles (WhiskeredRobot::baseAngles) into the sensor's two 16-bit outputs, Alpha
// (in-plane, "horizontal" bending) and Beta (vertical bending), as the whisker board reads them
// over SPI (firmware/core/include/whisker/mlx90333.h; feed them to Mlx90333Emulator).
//
//   code = clamp(round(rest + gain * angle + noise_codes * n), clamp_low, clamp_high)
//   n ~ N(0, 1), one draw per output per sample from the caller's Rng (Alpha first, then Beta)
//
// Choices (docs/WHISKERS.md has the sources):
//   - gain: the MLX90333's serial angle output spans 360 degrees over the 16-bit word, so
//     65536 / (2 pi) = 10430.4 codes per radian of field direction, with the field taken to turn
//     with the magnet (1:1: the magnet sits 0.75 mm over the die and tilts with the base).
//   - rest: 32768 for both outputs, the sensor "calibrated to its resting angle" (§2.1) at
//     mid-scale so both directions of bending have the same room.
//   - clamping: the datasheet's programmable clamping levels hold the output once the field
//     leaves the calibrated range; we set them at +-30 degrees of deflection (codes
//     27307..38229), beyond anything the plug allows in normal contact (docs/WHISKERS.md).
//   - noise: sigma = 4 LSB (0.022 degrees). The datasheet quotes 12-bit angular resolution, i.e.
//     one part in 16 of the 16-bit word; the low bits jitter by a few LSB.
//
// Pure value type: thread-safe for concurrent const use with distinct Rngs; never allocates.
#pragma once

#include <cstdint>

#include "crunch/core/result.h"
#include "crunch/core/rng.h"

namespace crunch::sim {

struct HallCodes {
  std::uint16_t alpha = 0;
  std::uint16_t beta = 0;
  bool alpha_clamped = false;  // the output sits at a clamping level (saturated)
  bool beta_clamped = false;
};

class HallSensorModel {
 public:
  struct Options {
    double rest_code = 32768.0;                       // output at zero deflection, both axes
    double gain = 65536.0 / 6.283185307179586;        // codes per radian
    double clamp_angle = 30.0 * 3.141592653589793 / 180.0;  // radians either side of rest
    double noise_codes = 4.0;                         // Gaussian sigma, LSB

    // okStatus(), or an Error naming the bad field (non-finite, gain <= 0, negative noise or
    // clamp angle, or clamping levels outside 0..65535).
    Status validate() const;
  };

  // Asserts that `options` are valid. The default constructor uses the default Options.
  HallSensorModel();
  explicit HallSensorModel(const Options& options);

  // One noisy sample: draws exactly two normals from `rng` (Alpha, then Beta), even when the
  // noise is zero or an output saturates, so a seed gives the same stream whatever the signal.
  // A non-finite angle reads as saturated: +inf high, -inf and NaN low.
  HallCodes sample(double horizontal, double vertical, Rng& rng) const;
  // The noiseless reading (quantised and clamped).
  HallCodes ideal(double horizontal, double vertical) const;

  // The inverse for calibration and tests: the angle a code stands for, (code - rest) / gain.
  double toAngle(std::uint16_t code) const { return (code - options_.rest_code) / options_.gain; }

  std::uint16_t clampLow() const { return clamp_low_; }
  std::uint16_t clampHigh() const { return clamp_high_; }
  const Options& options() const { return options_; }

 private:
  std::uint16_t encode(double angle, double noise, bool& clamped) const;

  Options options_;
  std::uint16_t clamp_low_ = 0;
  std::uint16_t clamp_high_ = 0;
};

}  // namespace crunch::sim
