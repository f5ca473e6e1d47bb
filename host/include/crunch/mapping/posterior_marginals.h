// Posterior marginals of objects from MCMC samples (issue 13, "the fused map as posterior
// marginals"): the probability that the room holds an object at a given place, estimated as the
// fraction of samples (blackboard states) that hold a matching object.
//
// Each sample is one state of a chain (e.g. after one sweep at the coldest temperatures of one of
// the global inference's chains). Objects of every sample are clustered: two objects match when
// their centres lie within `radius` and their angles within `angle` modulo `angle_period`
// (pi for tables and walls, whose poses mean the same turned by pi), and their shape parameters
// (table width/depth/leg, a wall's length: `shape`) within `shape_tolerance` each. A cluster's
// score is the number of distinct samples with a member over the number of samples; its pose is
// the mean of one member per sample (the member nearest the cluster's centre), angles averaged
// on the circle of period angle_period (half of it for near-square tables when
// square_half_period). Generic over the object's kind: tables and walls use it
// alike; what a kind forbids (two tables overlapping) is the caller's to resolve.
//
// Greedy clustering: items are taken as seeds in order of how many items match them (computed
// once), a seed's unused matches form its cluster, re-centred once on their mean. Cost about
// O(n k) with a spatial grid of cell `radius` (k: items per neighbourhood). Deterministic.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/core/result.h"

namespace crunch {

struct ObjectSample {
  int sample = 0;  // which sample (0 .. n_samples - 1) holds it
  Pose2 pose;
  std::array<double, 3> shape{};  // kind-specific sizes (unused entries 0)
};

struct MarginalOptions {
  double radius = 0.10;                // metres between matching centres
  double angle = 10.0 * kPi / 180.0;  // radians between matching angles (modulo angle_period)
  double angle_period = kPi;
  double shape_tolerance = 0.05;  // metres per shape entry
  // Tables: an object whose first two shape entries (width, depth) differ by at most
  // shape_tolerance is near-square, and its angle means the same turned by angle_period / 2 (a
  // square chair at theta and at theta + pi/2 is one chair). Its cluster matches and averages
  // angles modulo angle_period / 2. Off: every angle modulo angle_period.
  bool square_half_period = false;

  // radius in (0, 10], angle in (0, pi], angle_period in (0, 2 pi], shape_tolerance in [0, 10].
  Status validate() const;
};

struct MarginalObject {
  Pose2 pose;
  std::array<double, 3> shape{};
  double score = 0.0;  // fraction of samples holding it, in [0, 1]
  int samples = 0;     // samples holding it
};

// The clusters of `objects` over `n_samples` samples (n_samples >= 1, every objects[i].sample in
// [0, n_samples)), best score first (ties: order of discovery).
std::vector<MarginalObject> posteriorMarginals(std::span<const ObjectSample> objects,
                                               int n_samples, const MarginalOptions& opt);

}  // namespace crunch
