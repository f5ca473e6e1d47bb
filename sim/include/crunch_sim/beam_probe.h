// The quasi-static push experiment that checks the ODE whisker chain against tapered-cantilever
// theory (WhiskerBeam, docs/WHISKERS.md), shared by the test, the beam_validation tool and the
// benchmark so they measure the same thing.
//
// Set-up: one WhiskeredRobot with the default four whiskers at (2, 2, 0.3) in an empty 4 x 4 m
// arena, plus one table whose leg stands with a vertical edge (the leg turned 45 degrees to the
// whisker) kGap to the left of whisker 2's rest line at distance d from its base; the rest of the
// table extends away from the robot. The default whiskers point radially outward, so turning the
// base in place at pi/24 rad/s (the body whisk's speed, §2.3) moves the edge across the whisker
// purely sideways, keeping its distance along the whisker. The base turns until the edge is
// delta past the rest line (beyond the whisker's own radius there), stops, and the whisker
// settles for `settle_s` seconds. Friction is off, as theory assumes.
//
// Thread-safety: each call builds and owns its own World and robot; calls must not overlap in
// time (ODE's collision scratch is global, world.h).
#pragma once

#include "crunch/core/result.h"
#include "crunch_sim/whisker_physics.h"

namespace crunch::sim {

struct BeamPush {
  double d = 0.0;           // contact distance from the base along the rest whisker, metres
  double delta = 0.0;       // sideways push of the whisker's centreline at d, metres
  double simulated = 0.0;   // |horizontal base angle| after settling, radians
  double predicted = 0.0;   // WhiskerBeam::baseAngle(delta, d), radians
  double vertical = 0.0;    // |vertical base angle| after settling, radians
  double contact_r = -1.0;  // WhiskeredRobot::contact(2)->r after settling, -1 if none
  double base_moment = 0.0;  // simulated angle times the follicle stiffness, N m

  // (simulated - predicted) / predicted.
  double relativeError() const { return (simulated - predicted) / predicted; }
};

inline constexpr double kBeamProbeGap = 0.003;  // edge's start offset from the rest line, m

// Runs the experiment for distance d in (0, external_length) and push delta > 0 with the given
// options (friction is forced to 0). Error if the options are invalid, d or delta is out of
// range, or the whisker is not touching the edge after settling.
Result<BeamPush> pushWhisker(const WhiskeredRobot::Options& options, double d, double delta,
                             double settle_s = 1.0);

}  // namespace crunch::sim
