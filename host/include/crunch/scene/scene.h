// The simulated world's description: the scene file contract of ARCHITECTURE.md §4.
// Loading validates every field; a bad file is an Error naming the file and the field.
#pragma once

#include <string>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/core/result.h"

namespace crunch {

// The largest arena side a scene may give (metres): a run's memory (the free-space grid) and time
// grow with the arena, so a bound keeps both predictable; 200 m is far beyond any room (issue 16).
inline constexpr double kMaxArenaSide = 200.0;

// The paper's standard table (§2.8, Fig. 6): 0.80 x 0.50 m top, 0.05 m square legs.
inline constexpr double kStandardTableWidth = 0.80;
inline constexpr double kStandardTableDepth = 0.50;
inline constexpr double kStandardLegSide = 0.05;

struct TableSpec {
  Pose2 pose;                          // centre of the top; theta meaningful modulo pi
  double width = kStandardTableWidth;  // along the table's own x
  double depth = kStandardTableDepth;  // along the table's own y
  double leg = kStandardLegSide;       // square leg side; legs sit flush in the four corners

  OrientedRect top() const { return {pose, width, depth}; }
  // The four leg footprints, in corner order (+x+y, -x+y, -x-y, +x-y) of the table frame.
  std::array<OrientedRect, 4> legs() const;
};

struct WallSpec {
  Vec2 a, b;
};

struct Scene {
  double width = 4.0;  // arena [0,width] x [0,depth], walled
  double depth = 4.0;
  std::vector<TableSpec> tables;
  std::vector<WallSpec> walls;  // interior walls only; the boundary is implied
  std::vector<Pose2> poses;     // candidate robot poses, in visiting order
  std::string source = "<built-in default arena>";

  // The four boundary walls followed by the interior walls.
  std::vector<WallSpec> allWalls() const;
};

// Margin between the arena boundary and the outermost grid poses, metres.
inline constexpr double kPoseGridMargin = 0.3;

// Most candidate poses a scene file may ask for (guards against a typo allocating gigabytes).
inline constexpr long kMaxScenePoses = 1'000'000;

// Evenly spaced poses: nx * ny positions inside the arena with kPoseGridMargin, each with
// ntheta compass headings starting at 0. Visiting order: row by row in y, then x, then heading,
// so consecutive poses share a location (the paper's 10x10x4 trajectory, Fig. 6). A count of 1
// along an axis puts that coordinate at the centre; an arena narrower than twice the margin
// shrinks the margin. Requires nx, ny, ntheta > 0.
std::vector<Pose2> poseGrid(double width, double depth, int nx, int ny, int ntheta);

// The built-in default arena: 4 x 4 m, walls, six standard tables, pose grid 10x10x4.
Scene defaultArena();

// Parses a scene from JSON text; `source` names the file in error messages.
Result<Scene> parseScene(const std::string& json_text, const std::string& source);

// Reads and parses a scene file.
Result<Scene> loadScene(const std::string& path);

}  // namespace crunch
