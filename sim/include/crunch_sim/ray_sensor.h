// The paper's shapelet-level sensor for the mapping experiment (§2.8): ODE finds whisker
// contacts, and each report gets the i.i.d. Gaussian noise of eqs. 4-5,
//   r_hat = r + eps_r,  eps_r ~ N(0, sigma_r)        (eq. 4)
//   phi_hat = phi + eps_phi,  eps_phi ~ N(0, sigma_phi)  (eq. 5)
// (texture, eq. 6, is not reported: every surface has tau = 1).
//
// At each pose the robot performs the body whisk of §2.3: it rotates in place at pi/24 rad/s
// toward and then away, so its heading sweeps theta0 -> theta0 + A -> theta0 - A -> theta0.
// A = pi/12: two seconds at pi/24 rad/s, the length of the paper's 2 s recording window (§2.5);
// with the default whisker bearings it makes the 16 whisker directions of a pose's four headings
// sweep the whole circle (docs/DESIGN.md).
// Each whisker is a rigid ray of its mount's length from its base along its bearing, in the
// plane z = Options::z. Over the whisk, the sample with the smallest hit distance — the
// deepest bend, the paper's peak deflection (eq. 1) — gives the whisker's one report:
//   r     the distance from the base to the contact along the whisker,
//   phi   the surface's tangent direction (its normal turned by +pi/2) relative to the robot's
//         heading at that sample, in [0, pi),
//   robot the exact pose at that sample (zero odometry noise, §2.8).
// A whisker that touches nothing during the whisk gives no report. Noise may carry r outside
// [0, length]; such reports are kept here and clamped (or, if absurd, rejected and counted) by
// toShapelet().
//
// Ownership: holds a reference to the World, which must outlive the model.
// Thread-safety: none (it uses the World's scratch geoms and its own scratch state).
#pragma once

#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/core/result.h"
#include "crunch/core/rng.h"
#include "crunch/mapping/sensor_model.h"
#include "crunch/robot/shapelet.h"
#include "crunch_sim/world.h"

namespace crunch::sim {

class RaySensorModel final : public SensorModel {
 public:
  struct Options {
    double z = 0.1;                     // height of the whisker plane above the floor, metres
    double whisk_amplitude = kPi / 12;  // A: two seconds at the paper's pi/24 rad/s, radians
    double sweep_step = kPi / 360;      // largest heading step between samples (0.5 deg)

    // okStatus(), or an Error naming the bad field.
    Status validate() const;
  };

  // Asserts that `options` and `noise` are valid (sigmas finite and non-negative).
  RaySensorModel(const World& world, std::vector<WhiskerMount> mounts, NoiseRegime noise,
                 Options options);

  // Appends one report per whisker that touched something during the whisk at `pose`, in
  // whisker order. Draws exactly two normals from `rng` per report (r, then phi), so a seed
  // gives the same reports. Does not allocate beyond growing `out`.
  void sense(const Pose2& pose, Rng& rng, std::vector<ContactReport>& out) override;

  const std::vector<WhiskerMount>& mounts() const override { return mounts_; }
  // The samples of the last whisk in which a whisker touched nothing along its whole length.
  void freeRays(std::vector<FreeRay>& out) const override {
    out.insert(out.end(), free_.begin(), free_.end());
  }
  const NoiseRegime& noise() const { return noise_; }
  const Options& options() const { return options_; }

  // Heading offsets from theta0 sampled by one whisk, in visiting order: 0, +h, ..., +A, then
  // -h, ..., -A, with h = A / ceil(A / sweep_step). The return legs revisit these headings;
  // a ray model has no dynamics, so they would repeat the same samples and are skipped.
  const std::vector<double>& sweepOffsets() const { return offsets_; }

 private:
  struct Peak {  // the deepest contact so far of one whisker during a whisk
    bool hit = false;
    double distance = 0.0;
    Vec2 normal = Vec2::Zero();
    Pose2 robot;
  };

  const World& world_;
  std::vector<WhiskerMount> mounts_;
  NoiseRegime noise_;
  Options options_;
  std::vector<double> offsets_;
  std::vector<Peak> peaks_;  // one per whisker, sized once
  std::vector<FreeRay> free_;  // untouched samples of the last whisk, capacity reserved once
};

}  // namespace crunch::sim
