// Overhead pictures of a mapping run against its ground truth, in the style of the paper's
// Fig. 6 (arena, tables, pose grid) and Figs. 11-13 (the collation of every pose's independent
// MAP_t, eq. 27): overlapping per-pose tables build up darker red where poses agree.
//
// Layers, bottom to top: 0.5 m grid with metre ticks, ground-truth tables (grey tops, dark
// legs), arena boundary and interior walls (thick black), pose grid (black dots), per-pose MAP
// tables (thin translucent red), fused map (thick blue), shapelets (orange 4 cm strokes along
// phi, on top so the evidence stays visible). A title line above and a legend in the top-right
// corner, beside the arena.
//
// Files are written atomically (crunch/core/atomic_file.h): the picture goes to a fresh
// temporary file beside `path` and is renamed over `path` only when complete, so a failed render
// never leaves a partial file and never touches an existing one. Functions are thread-safe.
#pragma once

#include <string>
#include <vector>

#include "crunch/core/atomic_file.h"
#include "crunch/core/geometry.h"
#include "crunch/core/result.h"
#include "crunch/exploration/exploration.h"
#include "crunch/mapping/map.h"
#include "crunch/scene/scene.h"

namespace crunch {

struct RenderOptions {
  double pixels_per_metre = 200;  // arena scale; must be finite and > 0
  // The picture's larger side at most (pixels): a large arena is drawn at a lower scale than
  // pixels_per_metre. From the margins + 100 to cairo's limit of 32767.
  int max_picture_px = 8192;
  bool draw_shapelets = true;
  bool draw_per_pose = true;  // the collated per-pose MAP tables (Figs. 11-13)
  bool draw_fused = true;     // the fused map (Map::tables)
  std::string title;          // shown before the counts on the title line; may be empty
  // An exploration run (--explore): its driven path (thin line), whisk poses (small arrows) and
  // bumps (x) are drawn over the map. Not owned; null: none.
  const exploration::ExplorationReport* exploration = nullptr;
};

// Where the arena lands in the picture. The arena occupies width*ppm x depth*ppm pixels (SVG:
// points) inside fixed margins; arena y points up, so the origin is the arena's bottom-left.
class MapCanvas {
 public:
  static constexpr int kMarginLeft = 56;    // y tick labels and axis caption
  static constexpr int kMarginRight = 190;  // legend column
  static constexpr int kMarginTop = 44;     // title line
  static constexpr int kMarginBottom = 48;  // x tick labels and axis caption

  MapCanvas(double arena_width, double arena_depth, double pixels_per_metre)
      : width_m_(arena_width), depth_m_(arena_depth), ppm_(pixels_per_metre) {}

  // Picture size: arena size * ppm (rounded) plus the margins.
  int widthPx() const;
  int heightPx() const;
  int arenaWidthPx() const;
  int arenaDepthPx() const;

  // Arena metres to picture pixels (continuous; pixel (i, j) covers [i, i+1) x [j, j+1)).
  Vec2 toPixel(const Vec2& metres) const;
  double ppm() const { return ppm_; }
  double arenaWidth() const { return width_m_; }
  double arenaDepth() const { return depth_m_; }

 private:
  double width_m_;
  double depth_m_;
  double ppm_;
};

// Renders `map` over the ground truth `truth` as a PNG at `path`. Returns an Error naming the
// path (and cairo's status text) when the options are invalid, the picture would exceed
// cairo's size limit, or the file cannot be written; no file is left behind in that case.
Status renderMapPng(const Map& map, const Scene& truth, const std::string& path,
                    const RenderOptions& options = {});

// The same picture as an SVG document (units: points, one per PNG pixel).
Status renderMapSvg(const Map& map, const Scene& truth, const std::string& path,
                    const RenderOptions& options = {});

// The same two pictures written into `into`'s temporary, for an OutputSet to publish with the
// run's other outputs (atomic_file.h); `into.target()` is the path errors name. Not committed.
Status renderMapPng(const Map& map, const Scene& truth, AtomicFile& into,
                    const RenderOptions& options = {});
Status renderMapSvg(const Map& map, const Scene& truth, AtomicFile& into,
                    const RenderOptions& options = {});

// ---- Blackboard snapshots (paper Figs. 3 and 4) -------------------------------------------------
// The blackboard at one pose: every live table hypothesis as a wire-frame rectangle (its top and
// four legs, magenta), every live leg hypothesis as a wire-frame square (green), the shapelets of
// working memory (orange 4 cm strokes along phi), the robot (a grey circle of kRobotRadius with a
// heading line) and its whiskers (base + bearing + length, dark cyan), over the arena walls and
// the true tables drawn faint. "MAP" hypotheses are drawn bold: tables flagged `map` and legs
// flagged `map` (the caller decides; crunchhost marks the live tables after annealing, which are
// MAP_t of eq. 27, and the legs attached to one of them). Plain data so the renderer does not
// depend on the blackboard.
struct SnapshotTable {
  Pose2 pose;
  bool map = false;
};
struct SnapshotLeg {
  Pose2 pose;
  double side = 0.05;
  bool map = false;
};
struct BlackboardSnapshot {
  int pose_index = -1;
  Pose2 robot;
  std::vector<WhiskerMount> whiskers;  // in the robot frame
  std::vector<Shapelet> shapelets;     // working memory
  std::vector<SnapshotTable> tables;   // live table hypotheses
  std::vector<SnapshotLeg> legs;       // live leg hypotheses
  double table_width = 0.8, table_depth = 0.8, leg_side = 0.05;  // the model's sizes, metres
  std::string title;  // shown before the counts (pose, temperature note)
};

// Renders `snap` over `truth` as a PNG / SVG at `path`; errors and atomicity as renderMapPng.
Status renderSnapshotPng(const BlackboardSnapshot& snap, const Scene& truth,
                         const std::string& path, double pixels_per_metre = 200);
Status renderSnapshotSvg(const BlackboardSnapshot& snap, const Scene& truth,
                         const std::string& path, double pixels_per_metre = 200);
Status renderSnapshotPng(const BlackboardSnapshot& snap, const Scene& truth, AtomicFile& into,
                         double pixels_per_metre = 200);
Status renderSnapshotSvg(const BlackboardSnapshot& snap, const Scene& truth, AtomicFile& into,
                         double pixels_per_metre = 200);

}  // namespace crunch
