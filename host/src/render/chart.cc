#include "crunch/render/chart.h"

#include "crunch/core/atomic_file.h"
#include "cairo_handles.h"

#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <utility>

namespace crunch {

ChartColour chartPalette(int index) {
  static constexpr ChartColour kTab10[] = {
      {0.122, 0.467, 0.706}, {1.000, 0.498, 0.055}, {0.173, 0.627, 0.173},
      {0.839, 0.153, 0.157}, {0.580, 0.404, 0.741}, {0.549, 0.337, 0.294},
      {0.890, 0.467, 0.761}, {0.498, 0.498, 0.498}};
  constexpr int n = static_cast<int>(sizeof(kTab10) / sizeof(kTab10[0]));
  return kTab10[((index % n) + n) % n];
}

namespace {

Error chartError(const std::string& what) { return Error{"chart: " + what}; }

bool finite(double v) { return std::isfinite(v); }

}  // namespace

Status ChartOptions::validate() const {
  if (width_px < 200 || width_px > 8000) return chartError("width_px must be in [200, 8000]");
  if (height_px < 200 || height_px > 8000) return chartError("height_px must be in [200, 8000]");
  for (const auto& [name, v] : {std::pair{"x_min", x_min}, {"x_max", x_max}, {"y_min", y_min},
                                {"y_max", y_max}}) {
    if (v && !finite(*v)) return chartError(std::string(name) + " must be finite");
  }
  if (x_min && x_max && !(*x_min < *x_max)) return chartError("x_min must be below x_max");
  if (y_min && y_max && !(*y_min < *y_max)) return chartError("y_min must be below y_max");
  return okStatus();
}

Status Chart::validate() const {
  if (Status s = options.validate(); !s) return s;
  for (size_t i = 0; i < series.size(); ++i) {
    const ChartSeries& s = series[i];
    const std::string name = "series " + std::to_string(i) + " ('" + s.label + "')";
    if (s.x.size() != s.y.size()) {
      return chartError(name + " has " + std::to_string(s.x.size()) + " x values but " +
                        std::to_string(s.y.size()) + " y values");
    }
    if (!s.y_error.empty() && s.y_error.size() != s.y.size()) {
      return chartError(name + " has " + std::to_string(s.y_error.size()) +
                        " error bars for " + std::to_string(s.y.size()) + " points");
    }
    for (const double e : s.y_error) {
      if (!(e >= 0.0)) return chartError(name + " has an error bar that is negative or NaN");
    }
    if (!(s.line_width > 0.0) || !finite(s.line_width)) {
      return chartError(name + " line_width must be finite and > 0");
    }
    if (!(s.marker_size > 0.0) || !finite(s.marker_size)) {
      return chartError(name + " marker_size must be finite and > 0");
    }
    if (s.colour) {
      for (const double c : {s.colour->r, s.colour->g, s.colour->b}) {
        if (!(c >= 0.0 && c <= 1.0)) return chartError(name + " colour must lie in [0, 1]");
      }
    }
  }
  return okStatus();
}

std::vector<double> niceTicks(double lo, double hi, int target) {
  assert(finite(lo) && finite(hi) && lo < hi && target >= 2);
  // The 1-2-5 step nearest (in ratio) to an even split into target - 1 intervals.
  const double raw = (hi - lo) / (target - 1);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (const double m : {2.0, 5.0, 10.0}) {
    if (std::abs(std::log(m * mag / raw)) < std::abs(std::log(step / raw))) step = m * mag;
  }
  const double first = std::floor(lo / step + 1e-9) * step;
  const double last = std::ceil(hi / step - 1e-9) * step;
  std::vector<double> ticks;
  const int n = static_cast<int>(std::lround((last - first) / step));
  for (int i = 0; i <= n; ++i) {
    double t = first + i * step;
    if (std::abs(t) < 1e-12 * step) t = 0.0;  // no "-0"
    ticks.push_back(t);
  }
  return ticks;
}

namespace {

// The range of one axis: explicit ends win; otherwise the finite data, widened to whole ticks.
void axisRange(std::optional<double> want_lo, std::optional<double> want_hi, double data_lo,
               double data_hi, int target, double& lo, double& hi, std::vector<double>& ticks) {
  lo = want_lo.value_or(data_lo);
  hi = want_hi.value_or(data_hi);
  if (!finite(lo) || !finite(hi)) {  // no data at all
    lo = want_lo.value_or(want_hi ? *want_hi - 1.0 : 0.0);
    hi = want_hi.value_or(lo + 1.0);
  }
  if (!(lo < hi)) {  // a single value: a unit-wide (or 10 %) window around it
    const double pad = lo == 0.0 ? 1.0 : 0.1 * std::abs(lo);
    if (!want_lo) lo -= pad;
    if (!want_hi) hi += pad;
    if (!(lo < hi)) hi = lo + pad;
  } else {
    // 3 % of air at automatic ends, so markers at the extremes are not cut by the frame.
    const double pad = 0.03 * (hi - lo);
    if (!want_lo) lo -= pad;
    if (!want_hi) hi += pad;
  }
  std::vector<double> t = niceTicks(lo, hi, target);
  if (!want_lo) lo = t.front();
  if (!want_hi) hi = t.back();
  ticks.clear();
  const double eps = 1e-9 * (hi - lo);
  for (const double v : t) {
    if (v >= lo - eps && v <= hi + eps) ticks.push_back(v);
  }
}

}  // namespace

ChartLayout::ChartLayout(const Chart& chart)
    : width_(chart.options.width_px), height_(chart.options.height_px) {
  assert(chart.validate().ok());
  const double inf = std::numeric_limits<double>::infinity();
  double xl = inf, xh = -inf, yl = inf, yh = -inf;
  for (const ChartSeries& s : chart.series) {
    for (size_t i = 0; i < s.x.size(); ++i) {
      if (!finite(s.x[i]) || !finite(s.y[i])) continue;
      const double e = s.y_error.empty() ? 0.0 : s.y_error[i];
      xl = std::min(xl, s.x[i]);
      xh = std::max(xh, s.x[i]);
      yl = std::min(yl, s.y[i] - (finite(e) ? e : 0.0));
      yh = std::max(yh, s.y[i] + (finite(e) ? e : 0.0));
    }
  }
  const ChartOptions& o = chart.options;
  // About one tick per 100 px across and 60 px up.
  const int xt = std::max(3, static_cast<int>((right() - left()) / 100.0));
  const int yt = std::max(3, static_cast<int>((bottom() - top()) / 60.0));
  axisRange(o.x_min, o.x_max, xl, xh, xt, x_min_, x_max_, x_ticks_);
  axisRange(o.y_min, o.y_max, yl, yh, yt, y_min_, y_max_, y_ticks_);
}

Vec2 ChartLayout::toPixel(double x, double y) const {
  const double px = left() + (x - x_min_) / (x_max_ - x_min_) * (right() - left());
  const double py = bottom() - (y - y_min_) / (y_max_ - y_min_) * (bottom() - top());
  return {px, py};
}

namespace {

using render_detail::ContextPtr;
using render_detail::SurfacePtr;

// ---- Atomic output -----------------------------------------------------------------------------

Error fileError(const std::string& path, const std::string& why) {
  return Error{"cannot write chart '" + path + "': " + why};
}

// Where Cairo's stream output goes: the chart's AtomicFile. Keeps the first write failure, so
// the Error gives the system's reason rather than Cairo's generic one.
struct ChartSink {
  AtomicFile& file;
  Status status = okStatus();

  static cairo_status_t write(void* closure, const unsigned char* data, unsigned int length) {
    auto* self = static_cast<ChartSink*>(closure);
    if (self->status) {
      self->status = self->file.write({reinterpret_cast<const char*>(data), length});
    }
    return self->status ? CAIRO_STATUS_SUCCESS : CAIRO_STATUS_WRITE_ERROR;
  }
};

// ---- Drawing -----------------------------------------------------------------------------------

constexpr ChartColour kText{0.10, 0.10, 0.10};
constexpr ChartColour kAxis{0.25, 0.25, 0.25};
constexpr ChartColour kGrid{0.88, 0.88, 0.88};
constexpr double kTitleFont = 16.0;
constexpr double kLabelFont = 13.0;
constexpr double kTickFont = 11.5;
constexpr double kTickLength = 5.0;

enum class Align { kLeft, kCentre, kRight };

void colour(cairo_t* cr, const ChartColour& c, double alpha = 1.0) {
  cairo_set_source_rgba(cr, c.r, c.g, c.b, alpha);
}

void font(cairo_t* cr, double size, bool bold) {
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
}

// Draws `text` with its baseline at y, aligned at x; returns its advance width.
double text(cairo_t* cr, double x, double y, const std::string& s, Align align) {
  cairo_text_extents_t ext;
  cairo_text_extents(cr, s.c_str(), &ext);
  double left = x - ext.x_bearing;
  if (align == Align::kCentre) left -= 0.5 * ext.width;
  if (align == Align::kRight) left -= ext.width;
  cairo_move_to(cr, left, y);
  cairo_show_text(cr, s.c_str());
  return ext.x_advance;
}

double textWidth(cairo_t* cr, const std::string& s) {
  cairo_text_extents_t ext;
  cairo_text_extents(cr, s.c_str(), &ext);
  return ext.x_advance;
}

// A tick label with as many decimals as the tick step needs.
std::string tickLabel(double v, const std::vector<double>& ticks) {
  double step = 1.0;
  if (ticks.size() >= 2) step = std::abs(ticks[1] - ticks[0]);
  const int decimals = std::clamp(static_cast<int>(std::ceil(-std::log10(step) - 1e-9)), 0, 9);
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, v);
  return buf;
}

double crisp(double px) { return std::floor(px) + 0.5; }

void markerPath(cairo_t* cr, MarkerShape shape, double x, double y, double r) {
  cairo_new_sub_path(cr);
  switch (shape) {
    case MarkerShape::kCircle:
      cairo_arc(cr, x, y, r, 0.0, 2.0 * kPi);
      break;
    case MarkerShape::kSquare:
      cairo_rectangle(cr, x - r, y - r, 2.0 * r, 2.0 * r);
      break;
    case MarkerShape::kDiamond:
      cairo_move_to(cr, x, y - 1.3 * r);
      cairo_line_to(cr, x + 1.3 * r, y);
      cairo_line_to(cr, x, y + 1.3 * r);
      cairo_line_to(cr, x - 1.3 * r, y);
      cairo_close_path(cr);
      break;
    case MarkerShape::kTriangle:
      cairo_move_to(cr, x, y - 1.3 * r);
      cairo_line_to(cr, x + 1.2 * r, y + 0.8 * r);
      cairo_line_to(cr, x - 1.2 * r, y + 0.8 * r);
      cairo_close_path(cr);
      break;
  }
}

void drawAxes(cairo_t* cr, const Chart& chart, const ChartLayout& l) {
  const ChartOptions& o = chart.options;
  cairo_set_line_width(cr, 1.0);
  if (o.grid) {
    colour(cr, kGrid);
    for (const double t : l.xTicks()) {
      const double x = crisp(l.toPixel(t, 0.0).x());
      cairo_move_to(cr, x, l.top());
      cairo_line_to(cr, x, l.bottom());
    }
    for (const double t : l.yTicks()) {
      const double y = crisp(l.toPixel(0.0, t).y());
      cairo_move_to(cr, l.left(), y);
      cairo_line_to(cr, l.right(), y);
    }
    cairo_stroke(cr);
  }
  colour(cr, kAxis);
  cairo_rectangle(cr, crisp(l.left()), crisp(l.top()), std::floor(l.right() - l.left()),
                  std::floor(l.bottom() - l.top()));
  cairo_stroke(cr);

  font(cr, kTickFont, false);
  double widest = 0.0;
  for (const double t : l.xTicks()) {
    const double x = crisp(l.toPixel(t, 0.0).x());
    colour(cr, kAxis);
    cairo_move_to(cr, x, l.bottom());
    cairo_line_to(cr, x, l.bottom() + kTickLength);
    cairo_stroke(cr);
    colour(cr, kText);
    text(cr, x, l.bottom() + kTickLength + 14.0, tickLabel(t, l.xTicks()), Align::kCentre);
  }
  for (const double t : l.yTicks()) {
    const double y = crisp(l.toPixel(0.0, t).y());
    colour(cr, kAxis);
    cairo_move_to(cr, l.left() - kTickLength, y);
    cairo_line_to(cr, l.left(), y);
    cairo_stroke(cr);
    colour(cr, kText);
    const std::string s = tickLabel(t, l.yTicks());
    widest = std::max(widest, textWidth(cr, s));
    text(cr, l.left() - kTickLength - 4.0, y + 0.35 * kTickFont, s, Align::kRight);
  }

  font(cr, kLabelFont, false);
  colour(cr, kText);
  if (!o.x_label.empty()) {
    text(cr, 0.5 * (l.left() + l.right()), l.bottom() + kTickLength + 40.0, o.x_label,
         Align::kCentre);
  }
  if (!o.y_label.empty()) {
    cairo_save(cr);
    const double x = std::max(14.0, l.left() - kTickLength - 12.0 - widest);
    cairo_translate(cr, x, 0.5 * (l.top() + l.bottom()));
    cairo_rotate(cr, -0.5 * kPi);
    text(cr, 0.0, 0.0, o.y_label, Align::kCentre);
    cairo_restore(cr);
  }
  if (!o.title.empty()) {
    font(cr, kTitleFont, true);
    text(cr, 0.5 * (l.left() + l.right()), 0.5 * ChartLayout::kMarginTop + 0.35 * kTitleFont,
         o.title, Align::kCentre);
  }
}

void drawSeries(cairo_t* cr, const ChartSeries& s, const ChartColour& c, const ChartLayout& l) {
  cairo_save(cr);
  cairo_rectangle(cr, l.left(), l.top(), l.right() - l.left(), l.bottom() - l.top());
  cairo_clip(cr);
  colour(cr, c);
  const auto ok = [&](size_t i) { return finite(s.x[i]) && finite(s.y[i]); };

  if (!s.y_error.empty()) {
    cairo_set_line_width(cr, std::max(1.0, 0.6 * s.line_width));
    for (size_t i = 0; i < s.x.size(); ++i) {
      if (!ok(i) || !finite(s.y_error[i]) || s.y_error[i] == 0.0) continue;
      const Vec2 lo = l.toPixel(s.x[i], s.y[i] - s.y_error[i]);
      const Vec2 hi = l.toPixel(s.x[i], s.y[i] + s.y_error[i]);
      const double x = crisp(lo.x());  // a thin bar on a pixel column stays sharp
      const double cap = 0.8 * s.marker_size + 1.0;
      cairo_move_to(cr, x, lo.y());
      cairo_line_to(cr, x, hi.y());
      cairo_move_to(cr, x - cap, crisp(lo.y()));
      cairo_line_to(cr, x + cap, crisp(lo.y()));
      cairo_move_to(cr, x - cap, crisp(hi.y()));
      cairo_line_to(cr, x + cap, crisp(hi.y()));
    }
    cairo_stroke(cr);
  }
  if (s.style != SeriesStyle::kPoints) {
    cairo_set_line_width(cr, s.line_width);
    cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
    if (s.dashed) {
      const double dash[] = {3.0 * s.line_width, 2.0 * s.line_width};
      cairo_set_dash(cr, dash, 2, 0.0);
    }
    bool pen_down = false;
    for (size_t i = 0; i < s.x.size(); ++i) {
      if (!ok(i)) {
        pen_down = false;  // a gap in the data is a gap in the line
        continue;
      }
      const Vec2 p = l.toPixel(s.x[i], s.y[i]);
      if (pen_down) {
        cairo_line_to(cr, p.x(), p.y());
      } else {
        cairo_move_to(cr, p.x(), p.y());
        pen_down = true;
      }
    }
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0.0);
  }
  if (s.style != SeriesStyle::kLine) {
    for (size_t i = 0; i < s.x.size(); ++i) {
      if (!ok(i)) continue;
      const Vec2 p = l.toPixel(s.x[i], s.y[i]);
      markerPath(cr, s.marker, p.x(), p.y(), s.marker_size);
    }
    cairo_fill(cr);
  }
  cairo_restore(cr);
}

void drawLegend(cairo_t* cr, const Chart& chart, const ChartLayout& l) {
  const LegendPosition pos = chart.options.legend;
  if (pos == LegendPosition::kHidden) return;
  font(cr, kLabelFont, false);
  double widest = 0.0;
  int rows = 0;
  for (const ChartSeries& s : chart.series) {
    if (s.label.empty()) continue;
    widest = std::max(widest, textWidth(cr, s.label));
    ++rows;
  }
  if (rows == 0) return;
  const double pad = 8.0, row = 20.0, icon = 28.0;
  const double w = pad + icon + 8.0 + widest + pad;
  const double h = pad + rows * row + pad - 4.0;
  const bool at_left = pos == LegendPosition::kTopLeft || pos == LegendPosition::kBottomLeft;
  const bool at_top = pos == LegendPosition::kTopLeft || pos == LegendPosition::kTopRight;
  const double x0 = at_left ? l.left() + 10.0 : l.right() - 10.0 - w;
  const double y0 = at_top ? l.top() + 10.0 : l.bottom() - 10.0 - h;

  cairo_rectangle(cr, x0, y0, w, h);
  cairo_set_source_rgba(cr, 1.0, 1.0, 1.0, 0.92);
  cairo_fill_preserve(cr);
  colour(cr, kGrid);
  cairo_set_line_width(cr, 1.0);
  cairo_stroke(cr);

  double y = y0 + pad + 0.5 * row - 2.0;  // centre line of the current row
  for (size_t i = 0; i < chart.series.size(); ++i) {
    const ChartSeries& s = chart.series[i];
    if (s.label.empty()) continue;
    const ChartColour c = s.colour.value_or(chartPalette(static_cast<int>(i)));
    colour(cr, c);
    const double ix = x0 + pad;
    if (s.style != SeriesStyle::kPoints) {
      cairo_set_line_width(cr, s.line_width);
      if (s.dashed) {
        const double dash[] = {3.0 * s.line_width, 2.0 * s.line_width};
        cairo_set_dash(cr, dash, 2, 0.0);
      }
      cairo_move_to(cr, ix, y);
      cairo_line_to(cr, ix + icon, y);
      cairo_stroke(cr);
      cairo_set_dash(cr, nullptr, 0, 0.0);
    }
    if (s.style != SeriesStyle::kLine) {
      markerPath(cr, s.marker, ix + 0.5 * icon, y, s.marker_size);
      cairo_fill(cr);
    }
    if (!s.y_error.empty()) {
      cairo_set_line_width(cr, 1.0);
      cairo_move_to(cr, ix + 0.5 * icon, y - 7.0);
      cairo_line_to(cr, ix + 0.5 * icon, y + 7.0);
      cairo_stroke(cr);
    }
    colour(cr, kText);
    text(cr, ix + icon + 8.0, y + 0.35 * kLabelFont, s.label, Align::kLeft);
    y += row;
  }
}

void drawChart(cairo_t* cr, const Chart& chart) {
  const ChartLayout layout(chart);
  cairo_set_source_rgb(cr, 1.0, 1.0, 1.0);
  cairo_paint(cr);
  drawAxes(cr, chart, layout);
  for (size_t i = 0; i < chart.series.size(); ++i) {
    const ChartSeries& s = chart.series[i];
    drawSeries(cr, s, s.colour.value_or(chartPalette(static_cast<int>(i))), layout);
  }
  drawLegend(cr, chart, layout);
}

Status checkInputs(const Chart& chart, const std::string& path) {
  if (path.empty()) return Error{"cannot write chart: the output path is empty"};
  if (Status s = chart.validate(); !s) return fileError(path, s.error().message);
  return okStatus();
}

Error cairoError(const std::string& path, cairo_status_t st) {
  return fileError(path, cairo_status_to_string(st));
}

// A failure while Cairo wrote into `sink`: the write's own Error when there is one.
Error cairoError(const std::string& path, cairo_status_t st, const ChartSink& sink) {
  if (!sink.status) return sink.status.error();
  return cairoError(path, st);
}

}  // namespace

Status renderChartPng(const Chart& chart, const std::string& path) {
  if (Status s = checkInputs(chart, path); !s) return s;
  const ChartOptions& o = chart.options;
  SurfacePtr surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, o.width_px, o.height_px));
  if (cairo_status_t st = cairo_surface_status(surface.get()); st != CAIRO_STATUS_SUCCESS) {
    return cairoError(path, st);
  }
  {
    ContextPtr cr(cairo_create(surface.get()));
    drawChart(cr.get(), chart);
    if (cairo_status_t st = cairo_status(cr.get()); st != CAIRO_STATUS_SUCCESS) {
      return cairoError(path, st);
    }
  }
  cairo_surface_flush(surface.get());
  Result<AtomicFile> file = AtomicFile::create(path, fileError);
  if (!file) return file.error();
  ChartSink sink{file.value()};
  if (cairo_status_t st =
          cairo_surface_write_to_png_stream(surface.get(), &ChartSink::write, &sink);
      st != CAIRO_STATUS_SUCCESS) {
    return cairoError(path, st, sink);
  }
  return file.value().commit();
}

Status renderChartSvg(const Chart& chart, const std::string& path) {
  if (Status s = checkInputs(chart, path); !s) return s;
  const ChartOptions& o = chart.options;
  // Declared before the surface, so the surface (which writes into the file) goes first.
  Result<AtomicFile> file = AtomicFile::create(path, fileError);
  if (!file) return file.error();
  ChartSink sink{file.value()};
  SurfacePtr surface(
      cairo_svg_surface_create_for_stream(&ChartSink::write, &sink, o.width_px, o.height_px));
  if (cairo_status_t st = cairo_surface_status(surface.get()); st != CAIRO_STATUS_SUCCESS) {
    return cairoError(path, st, sink);
  }
  {
    ContextPtr cr(cairo_create(surface.get()));
    drawChart(cr.get(), chart);
    if (cairo_status_t st = cairo_status(cr.get()); st != CAIRO_STATUS_SUCCESS) {
      return cairoError(path, st, sink);
    }
  }
  cairo_surface_finish(surface.get());  // writes the rest of the document
  if (cairo_status_t st = cairo_surface_status(surface.get()); st != CAIRO_STATUS_SUCCESS) {
    return cairoError(path, st, sink);
  }
  surface.reset();
  return file.value().commit();
}

}  // namespace crunch
