// XY charts with Cairo: the figures of docs/ (the beam validation of docs/WHISKERS.md, and
// charts in the style of the paper's Fig. 9, radial distance estimate against truth with error
// bars, and Fig. 10, orientation error against orientation).
//
// A Chart is data plus options; rendering lays it out (ChartLayout), draws axes with "nice"
// ticks (steps of 1, 2 or 5 times a power of ten) and labels, a title, grid lines, every series
// as lines and/or markers with optional vertical error bars, and a legend, then writes a PNG or
// an SVG.
//
// Data rules: a point whose x or y is not finite is skipped and breaks the series' line there.
// Axis ranges come from ChartOptions when given, otherwise from the finite data (error bars
// included) widened to the enclosing ticks. Data outside the plot area is clipped.
//
// Files are written atomically: the picture goes to a fresh temporary file beside `path` and is
// renamed over it only when complete, so a failed render never leaves a partial file and never
// touches an existing one. Rendering functions are thread-safe (no shared state).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/core/result.h"

namespace crunch {

struct ChartColour {
  double r = 0.0, g = 0.0, b = 0.0;  // each in [0, 1]
};

// The default colours, by series index (wrapping): blue, orange, green, red, purple, brown,
// pink, grey (the colour-blind-friendly "tab10" order).
ChartColour chartPalette(int index);

enum class SeriesStyle { kLine, kPoints, kLineAndPoints };
enum class MarkerShape { kCircle, kSquare, kDiamond, kTriangle };

struct ChartSeries {
  std::string label;              // legend text; an empty label keeps the series out of it
  std::vector<double> x;
  std::vector<double> y;          // same length as x
  std::vector<double> y_error;    // empty, or one half-length >= 0 per point (bar y +- e)
  SeriesStyle style = SeriesStyle::kLineAndPoints;
  MarkerShape marker = MarkerShape::kCircle;
  std::optional<ChartColour> colour;  // default chartPalette(series index)
  double line_width = 2.0;            // pixels, > 0
  double marker_size = 4.0;           // marker half-size in pixels, > 0
  bool dashed = false;
};

enum class LegendPosition { kHidden, kTopLeft, kTopRight, kBottomLeft, kBottomRight };

struct ChartOptions {
  std::string title;    // above the plot; may be empty
  std::string x_label;  // below the x axis
  std::string y_label;  // left of the y axis, rotated
  int width_px = 800;   // picture size (SVG: points), each in [200, 8000]
  int height_px = 500;
  // Axis ranges; unset ends come from the data. A set pair must have min < max.
  std::optional<double> x_min, x_max, y_min, y_max;
  LegendPosition legend = LegendPosition::kTopRight;
  bool grid = true;  // light lines at the ticks

  // okStatus(), or an Error naming the bad field.
  Status validate() const;
};

struct Chart {
  ChartOptions options;
  std::vector<ChartSeries> series;

  // okStatus(), or an Error naming the bad option or series (by index and label).
  Status validate() const;
};

// Tick positions: multiples of a step of 1, 2 or 5 times a power of ten (the one nearest in
// ratio to (hi - lo) / (target - 1)), covering [lo, hi]: the first <= lo, the last >= hi.
// Requires finite lo < hi, target >= 2.
std::vector<double> niceTicks(double lo, double hi, int target);

// Where a chart's data lands in the picture.
class ChartLayout {
 public:
  static constexpr double kMarginLeft = 78.0;    // y tick labels and the rotated y label
  static constexpr double kMarginRight = 24.0;
  static constexpr double kMarginTop = 44.0;     // title
  static constexpr double kMarginBottom = 58.0;  // x tick labels and the x label

  // The layout of a valid chart (asserts chart.validate()).
  explicit ChartLayout(const Chart& chart);

  double xMin() const { return x_min_; }
  double xMax() const { return x_max_; }
  double yMin() const { return y_min_; }
  double yMax() const { return y_max_; }
  const std::vector<double>& xTicks() const { return x_ticks_; }  // inside [xMin, xMax]
  const std::vector<double>& yTicks() const { return y_ticks_; }
  // The plot area in pixels: left, top, right, bottom.
  double left() const { return kMarginLeft; }
  double top() const { return kMarginTop; }
  double right() const { return width_ - kMarginRight; }
  double bottom() const { return height_ - kMarginBottom; }
  // Data to pixel coordinates (y grows downward in the picture).
  Vec2 toPixel(double x, double y) const;

 private:
  double width_, height_;
  double x_min_ = 0.0, x_max_ = 1.0, y_min_ = 0.0, y_max_ = 1.0;
  std::vector<double> x_ticks_, y_ticks_;
};

// Renders `chart` as a PNG (RGB, width_px x height_px) at `path`. Returns an Error naming the
// path when the chart is invalid or the file cannot be written; nothing is left behind then.
Status renderChartPng(const Chart& chart, const std::string& path);

// The same picture as an SVG document (one point per PNG pixel).
Status renderChartSvg(const Chart& chart, const std::string& path);

}  // namespace crunch
