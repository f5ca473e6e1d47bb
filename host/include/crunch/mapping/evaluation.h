// Accuracy of a map against the scene's ground truth (report.json).
#pragma once

#include <vector>

#include "crunch/mapping/map.h"
#include "crunch/scene/scene.h"

namespace crunch {

struct MatchTolerance {
  double position = 0.15;             // metres between centres
  double angle = 15.0 * kPi / 180.0;  // radians, modulo pi
};

// True if a mapped table matches a real one within the tolerance (angle modulo pi).
bool tableMatches(const MapTable& mapped, const TableSpec& truth, const MatchTolerance& tol);

struct Evaluation {
  int true_tables = 0;
  int fused_tables = 0;
  int matched = 0;          // fused tables matched one-to-one to real ones (greedy by distance)
  double precision = 0.0;   // matched / fused (1 when the map is empty: nothing claimed wrongly)
  double recall = 0.0;      // matched / true (1 when the scene has no tables)
  double f1 = 0.0;
  double mean_position_error = 0.0;  // metres, over matches
  double mean_angle_error = 0.0;     // radians modulo pi, over matches
  int per_pose_tables = 0;
  double per_pose_match_fraction = 0.0;  // per-pose MAP tables that match any real table
  int phantoms_near_walls = 0;  // unmatched fused tables whose top is within 0.3 m of a wall
  int phantoms_elsewhere = 0;
};

Evaluation evaluate(const Map& map, const Scene& scene, const MatchTolerance& tol = {});

}  // namespace crunch
