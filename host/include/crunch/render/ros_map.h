// A CrunchBot map as the occupancy grid ROS's map_server / nav2_map_server load (issue 17;
// docs/EXPORT.md): `map.pgm` (8-bit binary PGM, P5) and `map.yaml` with image, resolution,
// origin, negate, occupied_thresh, free_thresh and mode, written with yaml-cpp.
//
// A cell is
//   occupied  when a wall segment of the map crosses it or a table's leg square overlaps it
//             (and, with tops_occupied, the table's top: the Create drives under table tops, so
//             by default a top is not an obstacle);
//   free      when the map's free_space (Map::free_space, the floor the whiskers swept without
//             touching) covers it: a swept free-space cell whose centre lies in it, or the swept
//             cell holding its centre;
//   unknown   otherwise. A map file without free_space (older than issue 17) has no free cells.
// Occupied wins over free. Pixels: occupied 0, free 254, unknown 205 (map_saver's values), with
// negate 0, occupied_thresh 0.65 and free_thresh 0.1: unknown's occupancy (255 - 205) / 255 =
// 0.196 sits on map_saver's own free_thresh 0.196, so 0.1 keeps it unknown in every loader.
//
// The grid covers the free-space layer's extent and every wall and table (top included) with
// one cell of margin; map.yaml's origin is the pose of its lower-left pixel (x, y, yaw = 0).
// The PGM's first row is the grid's top row (largest y), as map_server reads it.
//
// Thread-safety: free functions on values. Writing is one OutputSet (core/atomic_file.h): both
// files are renamed into place together once both are complete, or neither is touched.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/core/result.h"
#include "crunch/mapping/map.h"

namespace crunch {

struct RosMapOptions {
  double resolution = 0.02;  // cell side, metres per pixel: --resolution
  bool tops_occupied = false;  // table tops occupied too: --tops-occupied

  // Bounds on resolution: finer than 1 mm is no whisker's precision, coarser than 1 m hides a
  // table; and the grid at most 10^8 cells (checked by rasteriseRosMap).
  static constexpr double kMinResolution = 0.001;
  static constexpr double kMaxResolution = 1.0;
  static constexpr long long kMaxCells = 100'000'000LL;

  // okStatus(), or an Error naming --resolution and its range.
  Status validate() const;
};

// Pixel values of the PGM.
inline constexpr std::uint8_t kRosOccupied = 0;
inline constexpr std::uint8_t kRosFree = 254;
inline constexpr std::uint8_t kRosUnknown = 205;

struct RosMapGrid {
  double resolution = 0.0;
  Vec2 origin{0.0, 0.0};  // world position of the lower-left corner of cell (0, 0)
  int width = 0, height = 0;
  // cells[iy * width + ix], iy = 0 the bottom row (smallest y); values kRos*.
  std::vector<std::uint8_t> cells;

  std::uint8_t at(int ix, int iy) const {
    return cells[static_cast<std::size_t>(iy) * static_cast<std::size_t>(width) +
                 static_cast<std::size_t>(ix)];
  }
  // The centre of cell (ix, iy) in the world.
  Vec2 centre(int ix, int iy) const {
    return origin + Vec2((ix + 0.5) * resolution, (iy + 0.5) * resolution);
  }
};

// The grid of `map` (options validated first; an Error names --resolution, or says the grid would
// exceed kMaxCells). An empty map with no free space is a 1 x 1 unknown grid at the origin.
Result<RosMapGrid> rasteriseRosMap(const Map& map, const RosMapOptions& options);

// The PGM file: "P5", a comment, width, height, 255, then the rows from the top (largest y).
std::string rosMapPgm(const RosMapGrid& grid);
// The YAML file, `image` naming the PGM relative to it.
std::string rosMapYaml(const RosMapGrid& grid, const std::string& image);

struct RosMapSummary {
  int width = 0, height = 0;
  long long occupied = 0, free = 0, unknown = 0;
  bool had_free_space = false;  // the map file held free_space
  std::string pgm_path, yaml_path;
};

// `crunchhost export --format ros-map`: reads the map file `map_json` (strictly,
// core/json_input.h), rasterises it and writes DIR/map.pgm and DIR/map.yaml (DIR created if
// missing). Errors name the file or the flag (a DIR that cannot take the files: "--out ...");
// on any error neither output file is written. `output_failed`, if given, is set true when the
// Error is a failure to write the outputs after every check passed (a full disk: the contract's
// exit 1), false otherwise (bad input or setting: exit 2).
Result<RosMapSummary> exportRosMap(const std::string& map_json, const std::string& out_dir,
                                   const RosMapOptions& options, bool* output_failed = nullptr);

}  // namespace crunch
