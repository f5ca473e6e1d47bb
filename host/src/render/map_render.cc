#include "crunch/render/map_render.h"

#include "crunch/core/atomic_file.h"
#include "cairo_handles.h"

#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <set>
#include <utility>
#include <vector>

namespace crunch {

int MapCanvas::arenaWidthPx() const { return static_cast<int>(std::lround(width_m_ * ppm_)); }
int MapCanvas::arenaDepthPx() const { return static_cast<int>(std::lround(depth_m_ * ppm_)); }
int MapCanvas::widthPx() const { return kMarginLeft + arenaWidthPx() + kMarginRight; }
int MapCanvas::heightPx() const { return kMarginTop + arenaDepthPx() + kMarginBottom; }

Vec2 MapCanvas::toPixel(const Vec2& metres) const {
  return {kMarginLeft + metres.x() * ppm_, kMarginTop + (depth_m_ - metres.y()) * ppm_};
}

namespace {

using render_detail::ContextPtr;
using render_detail::SurfacePtr;

// Cairo never returns null: a failed creation gives an "error object" whose status says why.
SurfacePtr makeImageSurface(int width, int height) {
  return SurfacePtr(cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height));
}
SurfacePtr makeSvgSurface(const std::string& file, int width, int height) {
  return SurfacePtr(cairo_svg_surface_create(file.c_str(), width, height));
}
ContextPtr makeContext(cairo_surface_t* surface) { return ContextPtr(cairo_create(surface)); }

// ---- Files -------------------------------------------------------------------------------------

// Cairo's largest image side.
constexpr int kMaxPicturePx = 32767;

Error pictureError(const std::string& path, const std::string& why) {
  return Error{"cannot write map picture '" + path + "': " + why};
}

// A file-system failure of the picture's AtomicFile, in the picture's own wording.
Error pictureFileError(const std::string& path, const std::string& why) {
  return pictureError(path, "error while writing: " + why);
}

// The canvas for `truth` after checking the inputs: options.pixels_per_metre, lowered so that
// the picture's larger side stays within options.max_picture_px (a 200 m arena at the default
// 200 px/m would be a 40000 px, 6 GB picture; issue 16).
Result<MapCanvas> canvasFor(const Scene& truth, const std::string& path,
                            const RenderOptions& options) {
  if (path.empty()) return Error{"cannot write map picture: the output path is empty"};
  if (!std::isfinite(options.pixels_per_metre) || options.pixels_per_metre <= 0) {
    return pictureError(path, "pixels_per_metre must be finite and > 0, got " +
                                  std::to_string(options.pixels_per_metre));
  }
  const int margin_w = MapCanvas::kMarginLeft + MapCanvas::kMarginRight;
  const int margin_h = MapCanvas::kMarginTop + MapCanvas::kMarginBottom;
  if (options.max_picture_px < std::max(margin_w, margin_h) + 100 ||
      options.max_picture_px > kMaxPicturePx) {
    std::string why = "max_picture_px must be ";
    why.append(std::to_string(std::max(margin_w, margin_h) + 100))
        .append(" to ")
        .append(std::to_string(kMaxPicturePx))
        .append(", got ")
        .append(std::to_string(options.max_picture_px));
    return pictureError(path, why);
  }
  if (!std::isfinite(truth.width) || !std::isfinite(truth.depth) || truth.width <= 0 ||
      truth.depth <= 0) {
    return pictureError(path, "the arena of scene '" + truth.source + "' has no positive size");
  }
  const double fit = std::min((options.max_picture_px - margin_w) / truth.width,
                              (options.max_picture_px - margin_h) / truth.depth);
  return MapCanvas(truth.width, truth.depth, std::min(options.pixels_per_metre, fit));
}

// ---- Drawing primitives ------------------------------------------------------------------------

struct Rgb {
  double r, g, b;
};

// Palette. Red and blue are far apart in hue and both dark enough to read on the grey tops.
constexpr Rgb kGridMinor{0.91, 0.91, 0.91};
constexpr Rgb kGridMajor{0.80, 0.80, 0.80};
constexpr Rgb kTruthTop{0.85, 0.85, 0.85};
constexpr Rgb kTruthTopEdge{0.62, 0.62, 0.62};
constexpr Rgb kTruthLeg{0.15, 0.15, 0.15};
constexpr Rgb kWall{0.0, 0.0, 0.0};
constexpr Rgb kPoseDot{0.0, 0.0, 0.0};
constexpr Rgb kPlannedPoseDot{0.70, 0.70, 0.70};  // planned poses with no contact
constexpr Rgb kPerPose{0.85, 0.0, 0.0};
constexpr double kPerPoseAlpha = 0.22;  // about five agreeing poses reach near-solid red
constexpr Rgb kShapeletLine{1.0, 0.62, 0.0};
constexpr Rgb kShapeletDot{0.80, 0.38, 0.0};
constexpr Rgb kFused{0.05, 0.30, 0.85};
constexpr Rgb kFusedWall{0.0, 0.70, 0.35};  // green: apart from the true walls' black
constexpr Rgb kText{0.10, 0.10, 0.10};

constexpr double kShapeletLength = 0.04;  // metres, drawn along phi

// Line widths and sizes in pixels: they stay legible whatever the scale.
constexpr double kWallWidth = 4.0;
constexpr double kPerPoseWidth = 1.0;
constexpr double kFusedWidth = 3.0;
constexpr double kFusedLegWidth = 2.0;
constexpr double kShapeletWidth = 2.0;
constexpr double kShapeletDotRadius = 1.25;
constexpr double kPoseDotRadius = 2.0;
constexpr double kTitleFontPx = 15.0;
constexpr double kLabelFontPx = 12.0;
constexpr double kMinFontPx = 7.0;  // a long title shrinks no further, and is clipped

// A cairo context plus the metres-to-pixels mapping; every layer draws through one.
class Painter {
 public:
  Painter(cairo_t* cr, const MapCanvas& canvas) : cr_(cr), canvas_(canvas) {}

  cairo_t* cr() const { return cr_; }
  const MapCanvas& canvas() const { return canvas_; }

  void colour(const Rgb& c, double alpha = 1.0) const {
    cairo_set_source_rgba(cr_, c.r, c.g, c.b, alpha);
  }
  void moveTo(const Vec2& m) const {
    const Vec2 p = canvas_.toPixel(m);
    cairo_move_to(cr_, p.x(), p.y());
  }
  void lineTo(const Vec2& m) const {
    const Vec2 p = canvas_.toPixel(m);
    cairo_line_to(cr_, p.x(), p.y());
  }
  void rectPath(const OrientedRect& r) const {
    const auto c = r.corners();
    moveTo(c[0]);
    for (int i = 1; i < 4; ++i) lineTo(c[i]);
    cairo_close_path(cr_);
  }
  void dotPath(const Vec2& m, double radius_px) const {
    const Vec2 p = canvas_.toPixel(m);
    cairo_new_sub_path(cr_);
    cairo_arc(cr_, p.x(), p.y(), radius_px, 0.0, 2.0 * kPi);
  }
  // Clips to the arena rectangle until the matching restore().
  void clipToArena() const {
    cairo_save(cr_);
    cairo_rectangle(cr_, MapCanvas::kMarginLeft, MapCanvas::kMarginTop, canvas_.arenaWidthPx(),
                    canvas_.arenaDepthPx());
    cairo_clip(cr_);
  }
  void restore() const { cairo_restore(cr_); }

 private:
  cairo_t* cr_;
  MapCanvas canvas_;
};

enum class Align { kLeft, kCentre, kRight };

// Draws `text` with its baseline at y and its left edge, centre or right edge at x.
void drawText(const Painter& p, double x, double y, const std::string& text, Align align) {
  cairo_text_extents_t ext;
  cairo_text_extents(p.cr(), text.c_str(), &ext);
  double left = x - ext.x_bearing;
  if (align == Align::kCentre) left = x - ext.x_bearing - 0.5 * ext.width;
  if (align == Align::kRight) left = x - ext.x_bearing - ext.width;
  cairo_move_to(p.cr(), left, y);
  cairo_show_text(p.cr(), text.c_str());
}

void setFont(const Painter& p, double size_px, bool bold) {
  cairo_select_font_face(p.cr(), "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(p.cr(), size_px);
}

// Centre of the pixel row/column a 1 px line should sit on to stay crisp.
double crisp(double px) { return std::floor(px) + 0.5; }

TableSpec asTableSpec(const MapTable& t) { return TableSpec{t.pose, t.width, t.depth, t.leg}; }

// ---- Layers ------------------------------------------------------------------------------------

void drawBackground(const Painter& p) {
  cairo_set_source_rgb(p.cr(), 1.0, 1.0, 1.0);
  cairo_paint(p.cr());
}

// 0.5 m grid; metre lines a shade darker and labelled below and left of the arena.
void drawGrid(const Painter& p) {
  const MapCanvas& c = p.canvas();
  cairo_set_line_width(p.cr(), 1.0);
  const int half_metres_x = static_cast<int>(std::floor(c.arenaWidth() * 2.0 + 1e-9));
  const int half_metres_y = static_cast<int>(std::floor(c.arenaDepth() * 2.0 + 1e-9));
  for (int pass = 0; pass < 2; ++pass) {  // minor lines first so metre lines sit on top
    const bool major = pass == 1;
    p.colour(major ? kGridMajor : kGridMinor);
    for (int i = 0; i <= half_metres_x; ++i) {
      if ((i % 2 == 0) != major) continue;
      const double x = crisp(c.toPixel({0.5 * i, 0.0}).x());
      cairo_move_to(p.cr(), x, c.toPixel({0.0, 0.0}).y());
      cairo_line_to(p.cr(), x, c.toPixel({0.0, c.arenaDepth()}).y());
    }
    for (int j = 0; j <= half_metres_y; ++j) {
      if ((j % 2 == 0) != major) continue;
      const double y = crisp(c.toPixel({0.0, 0.5 * j}).y());
      cairo_move_to(p.cr(), c.toPixel({0.0, 0.0}).x(), y);
      cairo_line_to(p.cr(), c.toPixel({c.arenaWidth(), 0.0}).x(), y);
    }
    cairo_stroke(p.cr());
  }
}

void drawAxes(const Painter& p) {
  const MapCanvas& c = p.canvas();
  const double tick = 5.0;
  const Vec2 origin = c.toPixel({0.0, 0.0});
  setFont(p, kLabelFontPx, false);
  p.colour(kText);
  cairo_set_line_width(p.cr(), 1.0);
  for (int m = 0; m <= static_cast<int>(std::floor(c.arenaWidth() + 1e-9)); ++m) {
    const double x = crisp(c.toPixel({double(m), 0.0}).x());
    cairo_move_to(p.cr(), x, origin.y() + kWallWidth / 2);
    cairo_line_to(p.cr(), x, origin.y() + kWallWidth / 2 + tick);
    cairo_stroke(p.cr());
    drawText(p, x, origin.y() + 20.0, std::to_string(m), Align::kCentre);
  }
  for (int m = 0; m <= static_cast<int>(std::floor(c.arenaDepth() + 1e-9)); ++m) {
    const double y = crisp(c.toPixel({0.0, double(m)}).y());
    cairo_move_to(p.cr(), origin.x() - kWallWidth / 2, y);
    cairo_line_to(p.cr(), origin.x() - kWallWidth / 2 - tick, y);
    cairo_stroke(p.cr());
    drawText(p, origin.x() - 10.0, y + 0.35 * kLabelFontPx, std::to_string(m), Align::kRight);
  }
  const double arena_mid_x = origin.x() + 0.5 * c.arenaWidthPx();
  drawText(p, arena_mid_x, origin.y() + 38.0, "x (m)", Align::kCentre);
  cairo_save(p.cr());
  cairo_translate(p.cr(), 18.0, origin.y() - 0.5 * c.arenaDepthPx());
  cairo_rotate(p.cr(), -0.5 * kPi);
  drawText(p, 0.0, 0.0, "y (m)", Align::kCentre);
  cairo_restore(p.cr());
}

void drawTruthTables(const Painter& p, const Scene& truth) {
  for (const TableSpec& t : truth.tables) {
    p.rectPath(t.top());
    p.colour(kTruthTop);
    cairo_fill_preserve(p.cr());
    p.colour(kTruthTopEdge);
    cairo_set_line_width(p.cr(), 1.0);
    cairo_stroke(p.cr());
    for (const OrientedRect& leg : t.legs()) p.rectPath(leg);
    p.colour(kTruthLeg);
    cairo_fill(p.cr());
  }
}

void drawWalls(const Painter& p, const Scene& truth) {
  p.colour(kWall);
  cairo_set_line_width(p.cr(), kWallWidth);
  cairo_set_line_cap(p.cr(), CAIRO_LINE_CAP_SQUARE);
  // The boundary as one closed path so its corners join cleanly.
  p.rectPath({{0.5 * truth.width, 0.5 * truth.depth, 0.0}, truth.width, truth.depth});
  for (const WallSpec& w : truth.walls) {
    p.moveTo(w.a);
    p.lineTo(w.b);
  }
  cairo_stroke(p.cr());
  cairo_set_line_cap(p.cr(), CAIRO_LINE_CAP_BUTT);
}

// The fused map's walls (--model walls or rooms): drawn over the true walls in green, thinner, so
// a true wall shows black at both sides of a found one and alone where none was found; a false
// wall shows green alone.
void drawFusedWalls(const Painter& p, const Map& map) {
  if (map.walls.empty()) return;
  p.colour(kFusedWall);
  cairo_set_line_width(p.cr(), kFusedWidth);
  cairo_set_line_cap(p.cr(), CAIRO_LINE_CAP_ROUND);
  for (const MapWall& w : map.walls) {
    p.moveTo(w.a);
    p.lineTo(w.b);
    cairo_stroke(p.cr());
  }
  cairo_set_line_cap(p.cr(), CAIRO_LINE_CAP_BUTT);
}

// Each position drawn once however many headings it was visited with.
std::vector<Vec2> uniquePositions(const std::vector<Pose2>& poses) {
  std::set<std::pair<long long, long long>> seen;  // millimetre cells
  std::vector<Vec2> out;
  for (const Pose2& pose : poses) {
    if (!std::isfinite(pose.x) || !std::isfinite(pose.y)) continue;
    if (seen.insert({std::llround(pose.x * 1000.0), std::llround(pose.y * 1000.0)}).second) {
      out.push_back(pose.position());
    }
  }
  return out;
}

// Robot positions, like the paper's Fig. 6: the scene's planned poses in grey, and in black the
// poses whose contacts were inferred from (map.per_pose).
void drawPoseGrid(const Painter& p, const Map& map, const Scene& truth, bool planned) {
  if (planned) {
    for (const Vec2& pos : uniquePositions(truth.poses)) p.dotPath(pos, kPoseDotRadius);
  }
  p.colour(kPlannedPoseDot);
  cairo_fill(p.cr());
  std::vector<Pose2> inferred;
  for (const PoseMap& pm : map.per_pose) inferred.push_back(pm.pose);
  for (const Vec2& pos : uniquePositions(inferred)) p.dotPath(pos, kPoseDotRadius);
  p.colour(kPoseDot);
  cairo_fill(p.cr());
}

// An exploration run: the driven path, each whisk pose as a small arrow on its heading, and
// each bump as an x.
constexpr Rgb kPath{0.10, 0.35, 0.85};
constexpr Rgb kBump{0.90, 0.45, 0.0};
constexpr double kPathWidth = 1.0;
constexpr double kArrowLength = 0.08;  // metres
constexpr double kBumpSize = 0.04;     // metres, half the x's arm

void drawExploration(const Painter& p, const exploration::ExplorationReport& x) {
  cairo_t* cr = p.cr();
  cairo_set_line_width(cr, kPathWidth);
  p.colour(kPath, 0.8);
  for (std::size_t i = 0; i < x.path.size(); ++i) {
    const Vec2 q = x.path[i].position();
    if (!q.allFinite()) continue;
    if (i == 0) p.moveTo(q); else p.lineTo(q);
  }
  cairo_stroke(cr);
  cairo_set_line_width(cr, 1.5);
  p.colour(kPath);
  for (const Pose2& w : x.whisk_poses) {
    const Vec2 a = w.position();
    const Vec2 d(std::cos(w.theta), std::sin(w.theta));
    const Vec2 n(-d.y(), d.x());
    const Vec2 tip = a + kArrowLength * d;
    p.moveTo(a);
    p.lineTo(tip);
    p.moveTo(tip - 0.03 * d + 0.02 * n);
    p.lineTo(tip);
    p.lineTo(tip - 0.03 * d - 0.02 * n);
  }
  cairo_stroke(cr);
  cairo_set_line_width(cr, 2.0);
  p.colour(kBump);
  for (const Vec2& b : x.bump_points) {
    p.moveTo(b + Vec2(-kBumpSize, -kBumpSize));
    p.lineTo(b + Vec2(kBumpSize, kBumpSize));
    p.moveTo(b + Vec2(-kBumpSize, kBumpSize));
    p.lineTo(b + Vec2(kBumpSize, -kBumpSize));
  }
  cairo_stroke(cr);
}

// A table hypothesis as an outline of its top and its four legs.
void outlineTable(const Painter& p, const MapTable& t) {
  const TableSpec spec = asTableSpec(t);
  p.rectPath(spec.top());
  for (const OrientedRect& leg : spec.legs()) p.rectPath(leg);
}

// Each per-pose table is stroked on its own so overlapping outlines compound into darker red
// where independent poses agree (paper Figs. 11-13).
void drawPerPoseTables(const Painter& p, const Map& map) {
  p.colour(kPerPose, kPerPoseAlpha);
  cairo_set_line_width(p.cr(), kPerPoseWidth);
  for (const PoseMap& pm : map.per_pose) {
    for (const MapTable& t : pm.tables) {
      outlineTable(p, t);
      cairo_stroke(p.cr());
    }
  }
}

void drawShapelets(const Painter& p, const Map& map) {
  p.colour(kShapeletLine);
  cairo_set_line_width(p.cr(), kShapeletWidth);
  cairo_set_line_cap(p.cr(), CAIRO_LINE_CAP_ROUND);
  for (const Shapelet& s : map.shapelets) {
    if (!s.oriented) continue;  // an edge or point contact: its dot only
    const Vec2 centre{s.x, s.y};
    const Vec2 half = 0.5 * kShapeletLength * Vec2{std::cos(s.phi), std::sin(s.phi)};
    p.moveTo(centre - half);
    p.lineTo(centre + half);
  }
  cairo_stroke(p.cr());
  cairo_set_line_cap(p.cr(), CAIRO_LINE_CAP_BUTT);
  for (const Shapelet& s : map.shapelets) p.dotPath({s.x, s.y}, kShapeletDotRadius);
  p.colour(kShapeletDot);
  cairo_fill(p.cr());
}

void drawFusedTables(const Painter& p, const Map& map) {
  p.colour(kFused);
  cairo_set_line_join(p.cr(), CAIRO_LINE_JOIN_ROUND);
  for (const MapTable& t : map.tables) {
    const TableSpec spec = asTableSpec(t);
    cairo_set_line_width(p.cr(), kFusedWidth);
    p.rectPath(spec.top());
    cairo_stroke(p.cr());
    cairo_set_line_width(p.cr(), kFusedLegWidth);
    for (const OrientedRect& leg : spec.legs()) p.rectPath(leg);
    cairo_stroke(p.cr());
  }
  cairo_set_line_join(p.cr(), CAIRO_LINE_JOIN_MITER);
}

std::string titleLine(const Map& map, const Scene& truth, const RenderOptions& options) {
  std::size_t per_pose_tables = 0;
  for (const PoseMap& pm : map.per_pose) per_pose_tables += pm.tables.size();
  // An exploration run whisked where it chose: its whisks are its poses, not the scene's list.
  const std::size_t poses = options.exploration
                                ? static_cast<std::size_t>(options.exploration->whisks)
                                : truth.poses.size();
  std::string line = options.title.empty() ? std::string() : options.title + "   ";
  line += std::to_string(truth.tables.size()) + " true tables | " + std::to_string(poses) +
          " poses (" + std::to_string(map.per_pose.size()) + " with contacts) | " +
          std::to_string(per_pose_tables) + " per-pose tables | " +
          std::to_string(map.tables.size()) + " fused | " + std::to_string(map.shapelets.size()) +
          " shapelets";
  return line;
}

// The title line, shrunk to fit when a small arena makes the picture narrow.
void drawTitle(const Painter& p, const std::string& line) {
  const double room = p.canvas().widthPx() - MapCanvas::kMarginLeft - 8.0;
  double size = kTitleFontPx;
  // Hinted glyph widths do not scale linearly with size, so measure again after each shrink.
  for (int attempt = 0; attempt < 4; ++attempt) {
    setFont(p, size, true);
    cairo_text_extents_t ext;
    cairo_text_extents(p.cr(), line.c_str(), &ext);
    if (ext.x_advance <= room || size <= kMinFontPx) break;
    size = std::max(kMinFontPx, 0.97 * size * room / ext.x_advance);
  }
  p.colour(kText);
  drawText(p, MapCanvas::kMarginLeft, 0.5 * MapCanvas::kMarginTop + 0.35 * kTitleFontPx + 2.0, line,
           Align::kLeft);
}

// Legend in the top-right corner, in the margin beside the arena so it hides no data.
void drawLegend(const Painter& p, const RenderOptions& options, bool fused_walls) {
  cairo_t* cr = p.cr();
  const double x0 = MapCanvas::kMarginLeft + p.canvas().arenaWidthPx() + 18.0;
  const double row = 24.0;
  const double icon_w = 30.0, icon_h = 14.0;
  double y = MapCanvas::kMarginTop + 6.0;  // top of the current row's icon

  const auto label = [&](const char* text) {
    setFont(p, kLabelFontPx, false);
    p.colour(kText);
    drawText(p, x0 + icon_w + 10.0, y + 0.5 * icon_h + 0.35 * kLabelFontPx, text, Align::kLeft);
    y += row;
  };
  const auto tableIcon = [&](double inset) {
    cairo_rectangle(cr, x0 + inset, y + inset, icon_w - 2 * inset, icon_h - 2 * inset);
  };
  const auto legIcons = [&](double side) {
    cairo_rectangle(cr, x0, y, side, side);
    cairo_rectangle(cr, x0 + icon_w - side, y, side, side);
    cairo_rectangle(cr, x0, y + icon_h - side, side, side);
    cairo_rectangle(cr, x0 + icon_w - side, y + icon_h - side, side, side);
  };

  tableIcon(0.0);
  p.colour(kTruthTop);
  cairo_fill(cr);
  legIcons(4.0);
  p.colour(kTruthLeg);
  cairo_fill(cr);
  label("ground truth");

  cairo_set_line_width(cr, kWallWidth);
  p.colour(kWall);
  cairo_move_to(cr, x0, y + 0.5 * icon_h);
  cairo_line_to(cr, x0 + icon_w, y + 0.5 * icon_h);
  cairo_stroke(cr);
  label("walls");

  cairo_arc(cr, x0 + 0.5 * icon_w, y + 0.5 * icon_h, kPoseDotRadius, 0.0, 2.0 * kPi);
  p.colour(kPoseDot);
  cairo_fill(cr);
  label("poses, grey: no touch");

  if (options.draw_per_pose) {
    // Offset outlines show how agreement darkens the red.
    cairo_set_line_width(cr, kPerPoseWidth);
    p.colour(kPerPose, kPerPoseAlpha);
    for (int k = 0; k < 5; ++k) {
      const double d = (k % 3) * 1.5;
      cairo_rectangle(cr, x0 + 0.5 + d, y + 0.5 + (k % 2), icon_w - 4.0, icon_h - 2.0);
      cairo_stroke(cr);
    }
    label("per-pose MAP tables");
  }
  if (options.draw_shapelets) {
    cairo_set_line_width(cr, kShapeletWidth);
    cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
    p.colour(kShapeletLine);
    cairo_move_to(cr, x0 + 0.5 * icon_w - 6.0, y + 0.5 * icon_h + 3.0);
    cairo_line_to(cr, x0 + 0.5 * icon_w + 6.0, y + 0.5 * icon_h - 3.0);
    cairo_stroke(cr);
    cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);
    cairo_arc(cr, x0 + 0.5 * icon_w, y + 0.5 * icon_h, kShapeletDotRadius, 0.0, 2.0 * kPi);
    p.colour(kShapeletDot);
    cairo_fill(cr);
    label("shapelets");
  }
  if (options.draw_fused) {
    cairo_set_line_width(cr, kFusedWidth);
    p.colour(kFused);
    tableIcon(1.5);
    cairo_stroke(cr);
    label("fused map");
    if (fused_walls) {
      cairo_set_line_width(cr, kFusedWidth);
      p.colour(kFusedWall);
      cairo_move_to(cr, x0, y + 0.5 * icon_h);
      cairo_line_to(cr, x0 + icon_w, y + 0.5 * icon_h);
      cairo_stroke(cr);
      label("fused walls");
    }
  }
  if (options.exploration) {
    cairo_set_line_width(cr, 1.5);
    p.colour(kPath);
    cairo_move_to(cr, x0, y + 0.5 * icon_h);
    cairo_line_to(cr, x0 + icon_w, y + 0.5 * icon_h);
    cairo_move_to(cr, x0 + icon_w - 6, y + 0.5 * icon_h - 4);
    cairo_line_to(cr, x0 + icon_w, y + 0.5 * icon_h);
    cairo_line_to(cr, x0 + icon_w - 6, y + 0.5 * icon_h + 4);
    cairo_stroke(cr);
    label("path, whisk poses");
    cairo_set_line_width(cr, 2.0);
    p.colour(kBump);
    const double cx = x0 + 0.5 * icon_w, cy = y + 0.5 * icon_h;
    cairo_move_to(cr, cx - 5, cy - 5);
    cairo_line_to(cr, cx + 5, cy + 5);
    cairo_move_to(cr, cx - 5, cy + 5);
    cairo_line_to(cr, cx + 5, cy - 5);
    cairo_stroke(cr);
    label("bumps");
  }
}

void drawPicture(cairo_t* cr, const MapCanvas& canvas, const Map& map, const Scene& truth,
                 const RenderOptions& options) {
  const Painter p(cr, canvas);
  drawBackground(p);
  drawGrid(p);
  drawTruthTables(p, truth);
  p.clipToArena();  // hypotheses beyond the walls are not drawn over the labels
  if (options.draw_per_pose) drawPerPoseTables(p, map);
  p.restore();
  drawWalls(p, truth);
  // An exploration run draws its own path and whisk poses; the scene's list is not its plan.
  drawPoseGrid(p, map, truth, options.exploration == nullptr);
  p.clipToArena();
  if (options.draw_fused) drawFusedTables(p, map);
  // Shapelets last: they are the evidence, small, and would vanish under the fused legs.
  if (options.draw_shapelets) drawShapelets(p, map);
  if (options.exploration) drawExploration(p, *options.exploration);
  p.restore();
  // Walls over the shapelets (a wall is a line; its shapelets show at its sides), unclipped:
  // the boundary lies on the clip.
  if (options.draw_fused) drawFusedWalls(p, map);
  drawAxes(p);
  drawTitle(p, titleLine(map, truth, options));
  drawLegend(p, options, !map.walls.empty());
}

// ---- Blackboard snapshot layers (Figs. 3-4) ------------------------------------------------------

constexpr Rgb kSnapTable{0.80, 0.0, 0.60};   // magenta wire-frame tables
constexpr Rgb kSnapLeg{0.0, 0.55, 0.15};     // green wire-frame legs
constexpr Rgb kSnapRobot{0.45, 0.45, 0.45};  // robot body
constexpr Rgb kSnapWhisker{0.0, 0.45, 0.55};
constexpr double kSnapFaint = 0.35;  // alpha of the truth and walls under a snapshot

void drawSnapshotLayers(const Painter& p, const BlackboardSnapshot& snap) {
  cairo_t* cr = p.cr();
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  // Tables: non-MAP thin first, MAP bold on top.
  for (int bold = 0; bold < 2; ++bold) {
    p.colour(kSnapTable, bold ? 1.0 : 0.55);
    cairo_set_line_width(cr, bold ? 3.0 : 1.0);
    for (const SnapshotTable& t : snap.tables) {
      if (t.map != (bold == 1)) continue;
      const TableSpec spec{t.pose, snap.table_width, snap.table_depth, snap.leg_side};
      p.rectPath(spec.top());
      for (const OrientedRect& leg : spec.legs()) p.rectPath(leg);
      // A tick from the centre along the table's +x shows its orientation.
      const Vec2 centre = t.pose.position();
      const Vec2 dir{std::cos(t.pose.theta), std::sin(t.pose.theta)};
      const Vec2 tick = centre + 0.15 * dir;
      p.moveTo(centre);
      p.lineTo(tick);
    }
    cairo_stroke(cr);
  }
  for (int bold = 0; bold < 2; ++bold) {
    p.colour(kSnapLeg, bold ? 1.0 : 0.75);
    cairo_set_line_width(cr, bold ? 2.5 : 1.0);
    for (const SnapshotLeg& l : snap.legs) {
      if (l.map != (bold == 1)) continue;
      p.rectPath({l.pose, l.side, l.side});
    }
    cairo_stroke(cr);
  }
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_MITER);
  // The robot: body circle, heading line, whiskers from base along bearing for length.
  const Pose2& r = snap.robot;
  p.dotPath(r.position(), kRobotRadius * p.canvas().ppm());
  p.colour(kSnapRobot, 0.25);
  cairo_fill_preserve(cr);
  p.colour(kSnapRobot);
  cairo_set_line_width(cr, 1.5);
  cairo_stroke(cr);
  const Vec2 centre = r.position();
  const Vec2 heading{std::cos(r.theta), std::sin(r.theta)};
  const Vec2 nose = centre + kRobotRadius * heading;
  p.moveTo(centre);
  p.lineTo(nose);
  cairo_set_line_width(cr, 2.0);
  cairo_stroke(cr);
  const double cth = std::cos(r.theta), sth = std::sin(r.theta);
  const auto toWorld = [&](const Vec2& v) -> Vec2 {
    return Vec2{centre.x() + cth * v.x() - sth * v.y(), centre.y() + sth * v.x() + cth * v.y()};
  };
  p.colour(kSnapWhisker);
  cairo_set_line_width(cr, 1.5);
  for (const WhiskerMount& w : snap.whiskers) {
    const Vec2 tip{w.base.x() + w.length * std::cos(w.bearing),
                   w.base.y() + w.length * std::sin(w.bearing)};
    p.moveTo(toWorld(w.base));
    p.lineTo(toWorld(tip));
  }
  cairo_stroke(cr);
  // Shapelets on top: the evidence.
  p.colour(kShapeletLine);
  cairo_set_line_width(cr, 3.0);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  for (const Shapelet& s : snap.shapelets) {
    if (!s.oriented) {  // an edge or point contact: a dot
      p.dotPath({s.x, s.y}, 0.25 * kShapeletLength);
      continue;
    }
    const double hx = 0.5 * kShapeletLength * std::cos(s.phi);
    const double hy = 0.5 * kShapeletLength * std::sin(s.phi);
    p.moveTo(Vec2{s.x - hx, s.y - hy});
    p.lineTo(Vec2{s.x + hx, s.y + hy});
  }
  cairo_stroke(cr);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);
}

void drawSnapshotLegend(const Painter& p) {
  cairo_t* cr = p.cr();
  const double x0 = MapCanvas::kMarginLeft + p.canvas().arenaWidthPx() + 18.0;
  const double row = 24.0, icon_w = 30.0, icon_h = 14.0;
  double y = MapCanvas::kMarginTop + 6.0;
  const auto label = [&](const char* text) {
    setFont(p, kLabelFontPx, false);
    p.colour(kText);
    drawText(p, x0 + icon_w + 10.0, y + 0.5 * icon_h + 0.35 * kLabelFontPx, text, Align::kLeft);
    y += row;
  };
  const auto box = [&](const Rgb& c, double width, double inset) {
    cairo_rectangle(cr, x0 + inset, y + inset, icon_w - 2 * inset, icon_h - 2 * inset);
    p.colour(c);
    cairo_set_line_width(cr, width);
    cairo_stroke(cr);
  };
  cairo_rectangle(cr, x0, y, icon_w, icon_h);
  p.colour(kTruthTop, kSnapFaint);
  cairo_fill(cr);
  label("ground truth (faint)");
  box(kSnapTable, 3.0, 1.5);
  label("table hyp., MAP");
  box(kSnapTable, 1.0, 0.5);
  label("table hyp., other");
  box(kSnapLeg, 2.5, 3.0);
  label("leg hyp., in a table");
  box(kSnapLeg, 1.0, 3.0);
  label("leg hyp., orphan");
  p.colour(kShapeletLine);
  cairo_set_line_width(cr, 3.0);
  cairo_move_to(cr, x0 + 9.0, y + 0.5 * icon_h + 3.0);
  cairo_line_to(cr, x0 + 21.0, y + 0.5 * icon_h - 3.0);
  cairo_stroke(cr);
  label("shapelets (memory)");
  cairo_arc(cr, x0 + 0.5 * icon_w, y + 0.5 * icon_h, 7.0, 0.0, 2.0 * kPi);
  p.colour(kSnapRobot, 0.25);
  cairo_fill(cr);
  p.colour(kSnapWhisker);
  cairo_move_to(cr, x0 + 0.5 * icon_w + 7.0, y + 0.5 * icon_h);
  cairo_line_to(cr, x0 + icon_w + 4.0, y + 0.5 * icon_h);
  cairo_stroke(cr);
  label("robot, whiskers");
}

void drawSnapshot(cairo_t* cr, const MapCanvas& canvas, const BlackboardSnapshot& snap,
                  const Scene& truth) {
  const Painter p(cr, canvas);
  drawBackground(p);
  drawGrid(p);
  // The truth faint: drawn opaque into a group, painted with alpha.
  cairo_push_group(cr);
  drawTruthTables(p, truth);
  drawWalls(p, truth);
  cairo_pop_group_to_source(cr);
  cairo_paint_with_alpha(cr, kSnapFaint);
  p.clipToArena();
  drawSnapshotLayers(p, snap);
  p.restore();
  drawAxes(p);
  int map_tables = 0, map_legs = 0;
  for (const SnapshotTable& t : snap.tables) map_tables += t.map;
  for (const SnapshotLeg& l : snap.legs) map_legs += l.map;
  std::string line = snap.title.empty() ? std::string() : snap.title + "   ";
  line += std::to_string(snap.tables.size()) + " tables (" + std::to_string(map_tables) +
          " MAP) | " + std::to_string(snap.legs.size()) + " legs (" + std::to_string(map_legs) +
          " in tables) | " + std::to_string(snap.shapelets.size()) + " shapelets";
  drawTitle(p, line);
  drawSnapshotLegend(p);
}

Error cairoError(const std::string& path, cairo_status_t status) {
  return pictureError(path, cairo_status_to_string(status));
}

// Draws with `draw(cairo_t*)` on a canvas-sized image and writes it as a PNG into `file`'s
// temporary (committed by the caller): the one PNG writer of the map and snapshot pictures.
template <typename Draw>
Status writePng(const MapCanvas& canvas, AtomicFile& file, Draw&& draw) {
  const std::string& path = file.target();
  SurfacePtr surface = makeImageSurface(canvas.widthPx(), canvas.heightPx());
  if (cairo_status_t st = cairo_surface_status(surface.get()); st != CAIRO_STATUS_SUCCESS) {
    return cairoError(path, st);
  }
  {
    ContextPtr cr = makeContext(surface.get());
    draw(cr.get());
    if (cairo_status_t st = cairo_status(cr.get()); st != CAIRO_STATUS_SUCCESS) {
      return cairoError(path, st);
    }
  }
  cairo_surface_flush(surface.get());
  if (cairo_status_t st = cairo_surface_write_to_png(surface.get(), file.tempPath().c_str());
      st != CAIRO_STATUS_SUCCESS) {
    return cairoError(path, st);
  }
  return okStatus();
}

// The same as an SVG document written straight into `file`'s temporary. The surface (which
// holds the temporary open) is gone before this returns, so a caller's discard closes nothing
// under it.
template <typename Draw>
Status writeSvg(const MapCanvas& canvas, AtomicFile& file, Draw&& draw) {
  const std::string& path = file.target();
  SurfacePtr surface = makeSvgSurface(file.tempPath(), canvas.widthPx(), canvas.heightPx());
  if (cairo_status_t st = cairo_surface_status(surface.get()); st != CAIRO_STATUS_SUCCESS) {
    return cairoError(path, st);
  }
  {
    ContextPtr cr = makeContext(surface.get());
    draw(cr.get());
    if (cairo_status_t st = cairo_status(cr.get()); st != CAIRO_STATUS_SUCCESS) {
      return cairoError(path, st);
    }
  }
  cairo_surface_finish(surface.get());  // writes the document and closes the temp file
  if (cairo_status_t st = cairo_surface_status(surface.get()); st != CAIRO_STATUS_SUCCESS) {
    return cairoError(path, st);
  }
  return okStatus();
}

// `write(file)` into a new AtomicFile at `path`, committed when it succeeds.
template <typename Write>
Status writeCommitted(const std::string& path, Write&& write) {
  Result<AtomicFile> file = AtomicFile::create(path, pictureFileError);
  if (!file) return file.error();
  if (Status s = write(file.value()); !s) return s;
  return file.value().commit();
}

}  // namespace

Status renderMapPng(const Map& map, const Scene& truth, AtomicFile& into,
                    const RenderOptions& options) {
  auto fitted = canvasFor(truth, into.target(), options);
  if (!fitted) return fitted.error();
  const MapCanvas& canvas = fitted.value();
  return writePng(canvas, into,
                  [&](cairo_t* cr) { drawPicture(cr, canvas, map, truth, options); });
}

Status renderMapSvg(const Map& map, const Scene& truth, AtomicFile& into,
                    const RenderOptions& options) {
  auto fitted = canvasFor(truth, into.target(), options);
  if (!fitted) return fitted.error();
  const MapCanvas& canvas = fitted.value();
  return writeSvg(canvas, into,
                  [&](cairo_t* cr) { drawPicture(cr, canvas, map, truth, options); });
}

Status renderSnapshotPng(const BlackboardSnapshot& snap, const Scene& truth, AtomicFile& into,
                         double pixels_per_metre) {
  RenderOptions options;
  options.pixels_per_metre = pixels_per_metre;
  auto fitted = canvasFor(truth, into.target(), options);
  if (!fitted) return fitted.error();
  const MapCanvas& canvas = fitted.value();
  return writePng(canvas, into, [&](cairo_t* cr) { drawSnapshot(cr, canvas, snap, truth); });
}

Status renderSnapshotSvg(const BlackboardSnapshot& snap, const Scene& truth, AtomicFile& into,
                         double pixels_per_metre) {
  RenderOptions options;
  options.pixels_per_metre = pixels_per_metre;
  auto fitted = canvasFor(truth, into.target(), options);
  if (!fitted) return fitted.error();
  const MapCanvas& canvas = fitted.value();
  return writeSvg(canvas, into, [&](cairo_t* cr) { drawSnapshot(cr, canvas, snap, truth); });
}

Status renderMapPng(const Map& map, const Scene& truth, const std::string& path,
                    const RenderOptions& options) {
  // The options are checked before a temporary is made, as before.
  if (auto fitted = canvasFor(truth, path, options); !fitted) return fitted.error();
  return writeCommitted(path, [&](AtomicFile& f) { return renderMapPng(map, truth, f, options); });
}

Status renderMapSvg(const Map& map, const Scene& truth, const std::string& path,
                    const RenderOptions& options) {
  if (auto fitted = canvasFor(truth, path, options); !fitted) return fitted.error();
  return writeCommitted(path, [&](AtomicFile& f) { return renderMapSvg(map, truth, f, options); });
}

Status renderSnapshotPng(const BlackboardSnapshot& snap, const Scene& truth,
                         const std::string& path, double pixels_per_metre) {
  return writeCommitted(
      path, [&](AtomicFile& f) { return renderSnapshotPng(snap, truth, f, pixels_per_metre); });
}

Status renderSnapshotSvg(const BlackboardSnapshot& snap, const Scene& truth,
                         const std::string& path, double pixels_per_metre) {
  return writeCommitted(
      path, [&](AtomicFile& f) { return renderSnapshotSvg(snap, truth, f, pixels_per_metre); });
}

}  // namespace crunch
