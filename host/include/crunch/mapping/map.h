// The result of a mapping run: the map file contract of ARCHITECTURE.md §4 as C++ values.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "crunch/blackboard/moves.h"
#include "crunch/core/geometry.h"
#include "crunch/core/result.h"
#include "crunch/robot/shapelet.h"
#include "crunch/scene/scene.h"

namespace crunch {

struct MapTable {
  Pose2 pose;  // theta meaningful modulo pi
  double width = kStandardTableWidth;
  double depth = kStandardTableDepth;
  double leg = kStandardLegSide;
  double score = 0.0;  // fused map only: posterior probability, see ChainFusion (mapping_options.h)
  int support = 0;     // fused map only: number of per-pose MAPs in the cluster
};

struct MapWall {
  Vec2 a, b;
  double score = 0.0;
};

// One pose's independent MAP_t (eq. 27).
struct PoseMap {
  Pose2 pose;
  int shapelets = 0;  // new shapelets sensed at this pose
  std::vector<MapTable> tables;
};

struct MapStats {
  int poses = 0;
  int skipped_poses = 0;
  int shapelets = 0;
  int rejected_reports = 0;  // non-finite or out-of-range reports, never entered the blackboard
  long long proposals = 0;
  double wall_s = 0.0;
  // Model size (issue 6, "model no more than a scene needs"): the most live table / leg
  // hypotheses the blackboard held at the end of any annealing (Blackboard::liveTables(),
  // liveLegs(), read after Sampler::anneal() returns, i.e. after the last temperature's pruning;
  // the count inside a temperature may be higher). The maximum over every pose's annealing
  // (Mapper::addPose) and, when the fused map is a global inference (Mapper::finish with
  // global_sweeps > 0), over each of its chains too. 0 for a run that never annealed.
  int peak_live_tables = 0;
  int peak_live_legs = 0;
  // The global inference (Mapper::finish): its wall time, part of wall_s, and the threads its
  // chains ran on (0: none ran). Measured, machine-dependent: in report.json, not in map.json.
  double global_s = 0.0;
  int global_threads = 0;
  // The global inference's proposals and acceptances by move family, summed over its chains
  // and the pool's sampler (report.json's global_inference.moves).
  MoveCounts global_moves{};
};

// A leg of a posterior draw that no table of the draw holds (eq. 13's null parent).
struct MapLeg {
  Pose2 pose;  // centre; theta meaningful modulo pi/2
  double side = kStandardLegSide;
};

// One draw of the map from a sampler's chain (Mapper::drawSamples): its live tables (each of
// its own size under the rooms model), its orphan legs (touched, no table placed over them yet)
// and walls. What exploration predicts from.
struct MapSample {
  std::vector<MapTable> tables;
  std::vector<MapLeg> legs;
  std::vector<MapWall> walls;
};

// The floor the whiskers swept without touching anything (issue 17): the cells of the mapper's
// negative-evidence grid (blackboard/free_space.h) that at least one free whisker sample passed
// through. Cell (ix, iy) covers origin + [ix, ix + 1) x [iy, iy + 1) cells; swept[iy * nx + ix]
// is 1 when swept. Empty (nx == 0) when the run had none or the map file predates it. It is what
// a robotics tool's occupancy grid calls "free"; docs/EXPORT.md.
struct FreeSpaceLayer {
  Vec2 origin{0.0, 0.0};
  double cell = 0.0;
  int nx = 0, ny = 0;
  std::vector<std::uint8_t> swept;

  bool empty() const { return nx == 0 || ny == 0; }
  bool at(int ix, int iy) const {
    return ix >= 0 && iy >= 0 && ix < nx && iy < ny &&
           swept[static_cast<std::size_t>(iy) * static_cast<std::size_t>(nx) +
                 static_cast<std::size_t>(ix)] != 0;
  }
};

struct Map {
  std::vector<MapTable> tables;  // the fused map
  std::vector<MapWall> walls;    // none yet: walls are not modelled (paper's future work)
  std::vector<PoseMap> per_pose;
  std::vector<Shapelet> shapelets;  // every shapelet of the run, for pictures
  MapStats stats;
  FreeSpaceLayer free_space;  // map.json's optional "free_space" (map_io.h)
};

}  // namespace crunch
