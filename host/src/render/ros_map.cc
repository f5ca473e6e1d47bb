#include "crunch/render/ros_map.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "crunch/core/atomic_file.h"
#include "crunch/core/json_input.h"
#include "crunch/mapping/map_io.h"
#include "crunch/scene/scene.h"

namespace crunch {

Status RosMapOptions::validate() const {
  if (!(std::isfinite(resolution) && resolution >= kMinResolution &&
        resolution <= kMaxResolution)) {
    std::string why = "--resolution: expected metres per cell from ";
    why.append(std::to_string(kMinResolution)).append(" to ").append(std::to_string(kMaxResolution));
    why.append(", got ").append(std::to_string(resolution));
    return Error{why};
  }
  return okStatus();
}

namespace {

// The axis-aligned box that must be covered: the free-space layer and every object.
struct Box {
  double x0 = std::numeric_limits<double>::infinity(), y0 = x0;
  double x1 = -x0, y1 = -x0;
  void add(const Vec2& p) {
    x0 = std::min(x0, p.x());
    y0 = std::min(y0, p.y());
    x1 = std::max(x1, p.x());
    y1 = std::max(y1, p.y());
  }
  bool empty() const { return !(x0 <= x1 && y0 <= y1); }
};

TableSpec tableSpec(const MapTable& t) {
  TableSpec s;
  s.pose = t.pose;
  s.width = t.width;
  s.depth = t.depth;
  s.leg = t.leg;
  return s;
}

class Raster {
 public:
  explicit Raster(RosMapGrid& g) : g_(g) {}

  std::uint8_t& cell(int ix, int iy) {
    return g_.cells[static_cast<std::size_t>(iy) * static_cast<std::size_t>(g_.width) +
                    static_cast<std::size_t>(ix)];
  }
  // The cell holding p, clamped into the grid.
  void index(const Vec2& p, int& ix, int& iy) const {
    ix = std::clamp(static_cast<int>(std::floor((p.x() - g_.origin.x()) / g_.resolution)), 0,
                    g_.width - 1);
    iy = std::clamp(static_cast<int>(std::floor((p.y() - g_.origin.y()) / g_.resolution)), 0,
                    g_.height - 1);
  }
  OrientedRect cellRect(int ix, int iy) const {
    const Vec2 c = g_.centre(ix, iy);
    return {{c.x(), c.y(), 0.0}, g_.resolution, g_.resolution};
  }
  // The cells of the box [lo, hi] and one more on every side (an edge on a cell boundary),
  // clamped into the grid.
  void range(const Vec2& lo, const Vec2& hi, int& ix0, int& iy0, int& ix1, int& iy1) const {
    index(lo, ix0, iy0);
    index(hi, ix1, iy1);
    ix0 = std::max(ix0 - 1, 0);
    iy0 = std::max(iy0 - 1, 0);
    ix1 = std::min(ix1 + 1, g_.width - 1);
    iy1 = std::min(iy1 + 1, g_.height - 1);
  }
  // Every cell a rectangle's interior overlaps becomes occupied.
  void occupyRect(const OrientedRect& r) {
    Box b;
    for (const Vec2& c : r.corners()) b.add(c);
    int ix0, iy0, ix1, iy1;
    range({b.x0, b.y0}, {b.x1, b.y1}, ix0, iy0, ix1, iy1);
    for (int iy = iy0; iy <= iy1; ++iy) {
      for (int ix = ix0; ix <= ix1; ++ix) {
        if (overlaps(cellRect(ix, iy), r)) cell(ix, iy) = kRosOccupied;
      }
    }
  }
  // Every cell the segment touches becomes occupied.
  void occupySegment(const Vec2& a, const Vec2& b) {
    int ix0, iy0, ix1, iy1;
    range({std::min(a.x(), b.x()), std::min(a.y(), b.y())},
          {std::max(a.x(), b.x()), std::max(a.y(), b.y())}, ix0, iy0, ix1, iy1);
    for (int iy = iy0; iy <= iy1; ++iy) {
      for (int ix = ix0; ix <= ix1; ++ix) {
        // A wall along a cell boundary occupies the cells on both sides (1 nm: rounding of
        // the cell's centre must not decide which).
        if (distanceRectSegment(cellRect(ix, iy), a, b) <= 1e-9) cell(ix, iy) = kRosOccupied;
      }
    }
  }

 private:
  RosMapGrid& g_;
};

}  // namespace

Result<RosMapGrid> rasteriseRosMap(const Map& map, const RosMapOptions& options) {
  if (auto st = options.validate(); !st) return st.error();
  const double res = options.resolution;
  const FreeSpaceLayer& fs = map.free_space;

  Box box;
  if (!fs.empty()) {
    box.add(fs.origin);
    box.add(fs.origin + Vec2(fs.nx * fs.cell, fs.ny * fs.cell));
  }
  for (const MapWall& w : map.walls) {
    box.add(w.a);
    box.add(w.b);
  }
  for (const MapTable& t : map.tables) {
    for (const Vec2& c : tableSpec(t).top().corners()) box.add(c);
  }
  if (box.empty()) box.add({0.0, 0.0});

  RosMapGrid g;
  g.resolution = res;
  // One cell of margin, the corner on a multiple of the resolution (tidy origins in map.yaml).
  const double gx0 = (std::floor(box.x0 / res) - 1.0) * res;
  const double gy0 = (std::floor(box.y0 / res) - 1.0) * res;
  const double cols = std::ceil((box.x1 - gx0) / res - 1e-9) + 1.0;
  const double rows = std::ceil((box.y1 - gy0) / res - 1e-9) + 1.0;
  if (!(cols * rows <= static_cast<double>(RosMapOptions::kMaxCells))) {
    std::string why = "--resolution: ";
    why.append(std::to_string(res)).append(" m makes a grid of more than 10^8 cells for this map");
    return Error{why};
  }
  g.origin = {gx0, gy0};
  g.width = static_cast<int>(cols);
  g.height = static_cast<int>(rows);
  g.cells.assign(static_cast<std::size_t>(g.width) * static_cast<std::size_t>(g.height),
                 kRosUnknown);
  Raster r(g);

  if (!fs.empty()) {
    // A swept free-space cell makes the grid cell holding its centre free...
    for (int iy = 0; iy < fs.ny; ++iy) {
      for (int ix = 0; ix < fs.nx; ++ix) {
        if (!fs.at(ix, iy)) continue;
        int gx, gy;
        r.index(fs.origin + Vec2((ix + 0.5) * fs.cell, (iy + 0.5) * fs.cell), gx, gy);
        r.cell(gx, gy) = kRosFree;
      }
    }
    // ...and a grid cell is free when its centre lies in a swept cell (grid finer than the layer).
    for (int gy = 0; gy < g.height; ++gy) {
      for (int gx = 0; gx < g.width; ++gx) {
        const Vec2 p = (g.centre(gx, gy) - fs.origin) / fs.cell;
        if (fs.at(static_cast<int>(std::floor(p.x())), static_cast<int>(std::floor(p.y())))) {
          r.cell(gx, gy) = kRosFree;
        }
      }
    }
  }
  for (const MapTable& t : map.tables) {
    const TableSpec spec = tableSpec(t);
    if (options.tops_occupied) r.occupyRect(spec.top());
    for (const OrientedRect& leg : spec.legs()) r.occupyRect(leg);
  }
  for (const MapWall& w : map.walls) r.occupySegment(w.a, w.b);
  return g;
}

std::string rosMapPgm(const RosMapGrid& grid) {
  std::string out = "P5\n# CREATOR: crunchhost export --format ros-map, ";
  out.append(std::to_string(grid.resolution)).append(" m/pix\n");
  out.append(std::to_string(grid.width)).append(" ").append(std::to_string(grid.height));
  out.append("\n255\n");
  out.reserve(out.size() + grid.cells.size());
  for (int iy = grid.height - 1; iy >= 0; --iy) {
    const auto* row = grid.cells.data() + static_cast<std::size_t>(iy) * grid.width;
    out.append(reinterpret_cast<const char*>(row), static_cast<std::size_t>(grid.width));
  }
  return out;
}

std::string rosMapYaml(const RosMapGrid& grid, const std::string& image) {
  YAML::Emitter y;
  y.SetDoublePrecision(15);  // 0.1 as 0.1, not 0.10000000000000001
  y << YAML::BeginMap;
  y << YAML::Key << "image" << YAML::Value << image;
  y << YAML::Key << "mode" << YAML::Value << "trinary";
  y << YAML::Key << "resolution" << YAML::Value << grid.resolution;
  y << YAML::Key << "origin" << YAML::Value << YAML::Flow << YAML::BeginSeq << grid.origin.x()
    << grid.origin.y() << 0.0 << YAML::EndSeq;
  y << YAML::Key << "negate" << YAML::Value << 0;
  y << YAML::Key << "occupied_thresh" << YAML::Value << 0.65;
  y << YAML::Key << "free_thresh" << YAML::Value << 0.1;
  y << YAML::EndMap;
  return std::string(y.c_str()) + "\n";
}

Result<RosMapSummary> exportRosMap(const std::string& map_json, const std::string& out_dir,
                                   const RosMapOptions& options, bool* output_failed) {
  if (output_failed != nullptr) *output_failed = false;
  // Past the checks, a failure is the output's (a full disk), not the input's.
  const auto failedWriting = [output_failed](Error e) {
    if (output_failed != nullptr) *output_failed = true;
    return e;
  };
  if (auto st = options.validate(); !st) return st.error();
  auto text = readInputFile(map_json, "map file");
  if (!text) return text.error();
  auto map = parseMapJson(text.value(), map_json);
  if (!map) return map.error();
  auto grid = rasteriseRosMap(map.value(), options);
  if (!grid) return grid.error();
  if (auto st = checkOutputTargets(out_dir, {"map.pgm", "map.yaml"}); !st) {
    return Error{"--out " + st.error().message};
  }
  if (auto st = ensureDirectory(out_dir); !st) return failedWriting(st.error());
  removeStaleTemps(out_dir, {"map.pgm", "map.yaml"});  // a killed export's leftovers

  RosMapSummary sum;
  sum.pgm_path = out_dir + "/map.pgm";
  sum.yaml_path = out_dir + "/map.yaml";
  // Both files complete and synced before either is renamed into place (OutputSet).
  OutputSet out;
  if (auto st = out.stage(sum.pgm_path, rosMapPgm(grid.value())); !st) {
    return failedWriting(st.error());
  }
  if (auto st = out.stage(sum.yaml_path, rosMapYaml(grid.value(), "map.pgm")); !st) {
    return failedWriting(st.error());
  }
  if (auto st = out.publish(); !st) return failedWriting(st.error());

  const RosMapGrid& g = grid.value();
  sum.width = g.width;
  sum.height = g.height;
  for (std::uint8_t c : g.cells) {
    if (c == kRosOccupied) ++sum.occupied;
    else if (c == kRosFree) ++sum.free;
    else ++sum.unknown;
  }
  sum.had_free_space = !map.value().free_space.empty();
  return sum;
}

}  // namespace crunch
