#include "crunch/render/chart.h"

// Cairo is a private dependency of `crunch`; the test reads PNGs back through <cairo/cairo.h>.
#include <cairo/cairo.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>
#include "support/temp_dir.h"

using namespace crunch;
namespace fs = std::filesystem;

namespace {


struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
using Png = std::unique_ptr<cairo_surface_t, SurfaceDeleter>;

Png readPng(const std::string& path) {
  Png png(cairo_image_surface_create_from_png(path.c_str()));
  REQUIRE(cairo_surface_status(png.get()) == CAIRO_STATUS_SUCCESS);
  return png;
}

// The RGB of pixel (x, y), each 0..255.
struct Rgb8 {
  int r, g, b;
};
Rgb8 pixel(cairo_surface_t* s, int x, int y) {
  cairo_surface_flush(s);
  const unsigned char* data = cairo_image_surface_get_data(s);
  const int stride = cairo_image_surface_get_stride(s);
  std::uint32_t v;
  std::memcpy(&v, data + y * stride + 4 * x, 4);
  return {static_cast<int>((v >> 16) & 0xFF), static_cast<int>((v >> 8) & 0xFF),
          static_cast<int>(v & 0xFF)};
}
bool near(const Rgb8& p, const ChartColour& c, int tol = 12) {
  return std::abs(p.r - static_cast<int>(std::lround(255 * c.r))) <= tol &&
         std::abs(p.g - static_cast<int>(std::lround(255 * c.g))) <= tol &&
         std::abs(p.b - static_cast<int>(std::lround(255 * c.b))) <= tol;
}
// Some pixel within `radius` of (x, y) has colour c (thin antialiased lines spread over two).
bool nearby(cairo_surface_t* s, double x, double y, const ChartColour& c, int tol, int radius) {
  for (int dy = -radius; dy <= radius; ++dy) {
    for (int dx = -radius; dx <= radius; ++dx) {
      if (near(pixel(s, static_cast<int>(x) + dx, static_cast<int>(y) + dy), c, tol)) return true;
    }
  }
  return false;
}
bool white(const Rgb8& p) { return p.r == 255 && p.g == 255 && p.b == 255; }

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Theory as a line, simulation as points with error bars (a Fig. 9 style chart).
Chart sampleChart() {
  Chart c;
  c.options.title = "Base angle against contact distance";
  c.options.x_label = "d (mm)";
  c.options.y_label = "base angle (deg)";
  ChartSeries theory;
  theory.label = "theory";
  theory.style = SeriesStyle::kLine;
  ChartSeries sim;
  sim.label = "simulation";
  sim.style = SeriesStyle::kPoints;
  sim.marker = MarkerShape::kSquare;
  sim.marker_size = 5.0;
  for (int d = 90; d <= 140; d += 10) {
    theory.x.push_back(d);
    theory.y.push_back(200.0 / d);
    sim.x.push_back(d);
    sim.y.push_back(200.0 / d * 1.03);
    sim.y_error.push_back(0.1);
  }
  c.series = {theory, sim};
  return c;
}

}  // namespace

TEST_CASE("Chart: nice ticks are 1, 2 or 5 steps that cover the range", "[render]") {
  const auto t = niceTicks(0.0, 1.0, 6);
  REQUIRE(t.size() == 6u);
  CHECK(t.front() == 0.0);
  CHECK(t.back() == Approx(1.0));
  CHECK(t[1] == Approx(0.2));

  const auto u = niceTicks(87.0, 141.0, 6);  // 54 / 5 = 10.8: step 10
  CHECK(u.front() == Approx(80.0));
  CHECK(u.back() == Approx(150.0));
  CHECK(u[1] - u[0] == Approx(10.0));
  const auto u3 = niceTicks(87.0, 141.0, 3);  // 27: step 20 (nearer than 50)
  CHECK(u3[1] - u3[0] == Approx(20.0));
  const auto u2 = niceTicks(0.0, 140.0, 3);  // 70: step 50 (nearer than 100... and 20)
  CHECK(u2[1] - u2[0] == Approx(50.0));

  const auto v = niceTicks(-0.013, 0.047, 5);  // step 0.02, through zero exactly
  CHECK(v.front() <= -0.013);
  CHECK(v.back() >= 0.047);
  CHECK(v[1] - v[0] == Approx(0.02));
  CHECK(std::find(v.begin(), v.end(), 0.0) != v.end());
  for (const double lo : {-3e5, 1e-7, 12.3}) {
    const auto w = niceTicks(lo, lo + 7.7 * std::abs(lo), 7);
    const double step = w[1] - w[0];
    const double mantissa = step / std::pow(10.0, std::floor(std::log10(step)));
    CHECK((mantissa == Approx(1.0) || mantissa == Approx(2.0) || mantissa == Approx(5.0)));
    CHECK(w.size() >= 4u);
    CHECK(w.size() <= 12u);
  }
}

TEST_CASE("Chart: layout maps the data range onto the plot area, y up", "[render]") {
  Chart c = sampleChart();
  const ChartLayout l(c);
  CHECK(l.xMin() <= 90.0);
  CHECK(l.xMax() >= 140.0);
  CHECK(l.yMin() <= 200.0 / 140.0 - 0.1);  // error bars are inside the range
  CHECK(l.yMax() >= 200.0 / 90.0 * 1.03 + 0.1);
  CHECK(l.toPixel(l.xMin(), l.yMin()).x() == Approx(l.left()));
  CHECK(l.toPixel(l.xMin(), l.yMin()).y() == Approx(l.bottom()));
  CHECK(l.toPixel(l.xMax(), l.yMax()).x() == Approx(l.right()));
  CHECK(l.toPixel(l.xMax(), l.yMax()).y() == Approx(l.top()));
  for (const double t : l.xTicks()) {
    CHECK(t >= l.xMin() - 1e-9);
    CHECK(t <= l.xMax() + 1e-9);
  }

  c.options.x_min = 0.0;
  c.options.x_max = 200.0;
  c.options.y_min = -1.0;
  const ChartLayout fixed(c);
  CHECK(fixed.xMin() == 0.0);
  CHECK(fixed.xMax() == 200.0);
  CHECK(fixed.yMin() == -1.0);
}

TEST_CASE("Chart: PNG shows the series where the layout says, in their colours", "[render]") {
  TempDir dir;
  const std::string path = dir.file("chart.png");
  Chart c = sampleChart();
  c.options.legend = LegendPosition::kBottomLeft;  // away from the points checked below
  REQUIRE(renderChartPng(c, path).ok());
  const Png png = readPng(path);
  CHECK(cairo_image_surface_get_width(png.get()) == 800);
  CHECK(cairo_image_surface_get_height(png.get()) == 500);

  const ChartLayout l(c);
  const ChartColour sim_colour = chartPalette(1);
  const ChartColour theory_colour = chartPalette(0);
  for (size_t i = 0; i < c.series[1].x.size(); ++i) {
    // The square marker's centre, and the error bar 0.07 above it (outside the marker).
    const Vec2 p = l.toPixel(c.series[1].x[i], c.series[1].y[i]);
    INFO("point " << i);
    CHECK(near(pixel(png.get(), static_cast<int>(p.x()), static_cast<int>(p.y())), sim_colour));
    const Vec2 bar = l.toPixel(c.series[1].x[i], c.series[1].y[i] + 0.07);
    CHECK(nearby(png.get(), bar.x(), bar.y(), sim_colour, 40, 1));
  }
  // The theory line passes through the middle of two of its points.
  const Vec2 a = l.toPixel(110.0, 200.0 / 110.0), b = l.toPixel(120.0, 200.0 / 120.0);
  const Vec2 mid = 0.5 * (a + b);
  CHECK(nearby(png.get(), mid.x(), mid.y(), theory_colour, 40, 1));
  // Empty plot area is white; the title row has ink.
  CHECK(white(pixel(png.get(), static_cast<int>(l.right()) - 3, static_cast<int>(l.bottom()) - 3)));
  int ink = 0;
  for (int x = 0; x < 800; ++x) {
    for (int y = 10; y < 40; ++y) ink += white(pixel(png.get(), x, y)) ? 0 : 1;
  }
  CHECK(ink > 200);
  CHECK(dir.entries() == std::vector<std::string>{"chart.png"});  // no temporary left
}

TEST_CASE("Chart: SVG is a complete document", "[render]") {
  TempDir dir;
  const std::string path = dir.file("chart.svg");
  REQUIRE(renderChartSvg(sampleChart(), path).ok());
  const std::string svg = slurp(path);
  CHECK(svg.rfind("<?xml", 0) == 0);
  CHECK(svg.find("<svg") != std::string::npos);
  CHECK(svg.find("width=\"800\"") != std::string::npos);
  CHECK(svg.size() > 2000u);
  const auto end = svg.find_last_not_of(" \n\r\t");
  CHECK(svg.substr(end - 5, 6) == "</svg>");
  CHECK(dir.entries() == std::vector<std::string>{"chart.svg"});
}

TEST_CASE("Chart: an unwritable path is a clear error and leaves nothing", "[render]") {
  const std::string path = "/nonexistent-crunch-dir/sub/chart.png";
  const Status s = renderChartPng(sampleChart(), path);
  REQUIRE_FALSE(s.ok());
  CHECK_THAT(s.error().message, Catch::Contains(path));
  CHECK_THAT(s.error().message, Catch::Contains("No such file or directory"));
  CHECK_FALSE(renderChartSvg(sampleChart(), path).ok());
  CHECK_FALSE(renderChartPng(sampleChart(), "").ok());
  CHECK_FALSE(fs::exists("/nonexistent-crunch-dir"));
}

TEST_CASE("Chart: invalid data is refused by name and never touches an existing file",
          "[render]") {
  TempDir dir;
  const std::string path = dir.file("keep.png");
  { std::ofstream(path) << "previous picture"; }
  Chart c = sampleChart();
  c.series[1].y.pop_back();
  Status s = renderChartPng(c, path);
  REQUIRE_FALSE(s.ok());
  CHECK_THAT(s.error().message, Catch::Contains("series 1 ('simulation')"));
  c = sampleChart();
  c.series[1].y_error[2] = -1.0;
  CHECK_FALSE(renderChartSvg(c, path).ok());
  c = sampleChart();
  c.options.x_min = 5.0;
  c.options.x_max = 5.0;
  s = renderChartPng(c, path);
  REQUIRE_FALSE(s.ok());
  CHECK_THAT(s.error().message, Catch::Contains("x_min"));
  c = sampleChart();
  c.options.width_px = 10;
  CHECK_FALSE(renderChartPng(c, path).ok());
  CHECK(slurp(path) == "previous picture");
  CHECK(dir.entries() == std::vector<std::string>{"keep.png"});
}

TEST_CASE("Chart: non-finite points are skipped, and an empty chart still draws", "[render]") {
  TempDir dir;
  Chart c = sampleChart();
  c.series[0].y[2] = std::nan("");
  c.series[1].x[0] = INFINITY;
  REQUIRE(renderChartPng(c, dir.file("gaps.png")).ok());
  const ChartLayout l(c);
  CHECK(l.xMax() < 1e6);  // the infinite x did not stretch the axis

  Chart empty;
  empty.options.title = "nothing yet";
  REQUIRE(renderChartPng(empty, dir.file("empty.png")).ok());
  REQUIRE(renderChartSvg(empty, dir.file("empty.svg")).ok());
  const ChartLayout e(empty);
  CHECK(e.xMin() < e.xMax());
  CHECK(e.yMin() < e.yMax());
}
