#include "crunch/render/map_render.h"

// Cairo is a private dependency of `crunch`, so its include directory does not propagate to the
// tests; /usr/include/cairo/cairo.h is reachable as <cairo/cairo.h>. The test only reads PNGs.
#include <cairo/cairo.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>

#include "crunch/core/rng.h"
#include "support/temp_dir.h"

using namespace crunch;
namespace fs = std::filesystem;

namespace {

// ---- Builders (the scene loader and defaultArena are other areas' work: build by hand) ----

TableSpec makeTable(double x, double y, double theta) {
  TableSpec t;
  t.pose = {x, y, theta};
  return t;
}

MapTable makeMapTable(double x, double y, double theta) {
  MapTable t;
  t.pose = {x, y, theta};
  return t;
}

// A 4 x 4 m arena with three tables, one interior wall and a 6 x 6 x 4 pose grid.
Scene makeScene() {
  Scene s;
  s.width = 4.0;
  s.depth = 4.0;
  s.source = "render_test scene";
  s.tables = {makeTable(1.0, 1.0, 0.0), makeTable(2.8, 1.3, 0.5), makeTable(1.4, 2.9, 1.4)};
  s.walls = {{{2.6, 4.0}, {2.6, 3.2}}};
  for (int j = 0; j < 6; ++j) {
    for (int i = 0; i < 6; ++i) {
      for (int k = 0; k < 4; ++k) {
        s.poses.push_back({0.3 + 0.68 * i, 0.3 + 0.68 * j, 0.5 * kPi * k});
      }
    }
  }
  return s;
}

// A plausible mapping run over `scene`: each pose near a table "sees" it with jitter, poses
// near the boundary hallucinate wall tables (as in the paper), shapelets lie on the leg faces
// facing the robot, and the fused map is the truth slightly off plus one false positive.
Map makeMap(const Scene& scene) {
  Rng rng(7);
  Map map;
  for (std::size_t pi = 0; pi < scene.poses.size(); ++pi) {
    const Pose2& pose = scene.poses[pi];
    PoseMap pm;
    pm.pose = pose;
    for (const TableSpec& t : scene.tables) {
      if ((t.pose.position() - pose.position()).norm() > 1.1) continue;
      pm.tables.push_back(makeMapTable(t.pose.x + 0.03 * rng.normal(),
                                       t.pose.y + 0.03 * rng.normal(),
                                       t.pose.theta + 0.05 * rng.normal()));
      for (const OrientedRect& leg : t.legs()) {
        const Vec2 to_robot = leg.pose.toLocal(pose.position());
        if (to_robot.norm() > 0.6) continue;
        // The face of the leg that points at the robot.
        const bool x_face = std::abs(to_robot.x()) > std::abs(to_robot.y());
        const Vec2 local = x_face ? Vec2{std::copysign(0.5 * leg.size_x, to_robot.x()), 0.0}
                                  : Vec2{0.0, std::copysign(0.5 * leg.size_y, to_robot.y())};
        const Vec2 at = leg.pose.toWorld(local + Vec2{0.005 * rng.normal(), 0.005 * rng.normal()});
        Shapelet s;
        s.x = at.x();
        s.y = at.y();
        s.phi = leg.pose.theta + (x_face ? 0.5 * kPi : 0.0) + 0.05 * rng.normal();
        s.pose_index = static_cast<int>(pi);
        map.shapelets.push_back(s);
        ++pm.shapelets;
      }
    }
    if (pose.x < 0.5 && rng.uniform() < 0.3) {  // wall contacts explained as a table
      pm.tables.push_back(makeMapTable(0.26 + 0.02 * rng.normal(), pose.y + 0.2 * rng.normal(),
                                       0.5 * kPi + 0.05 * rng.normal()));
      for (int k = 0; k < 3; ++k) {
        Shapelet s;
        s.x = 0.0;
        s.y = pose.y + rng.uniform(-0.15, 0.15);
        s.phi = 0.5 * kPi;
        map.shapelets.push_back(s);
      }
    }
    map.per_pose.push_back(pm);
  }
  map.tables = {makeMapTable(1.01, 0.99, 0.01), makeMapTable(2.82, 1.27, 0.47),
                makeMapTable(1.42, 2.88, 1.43), makeMapTable(0.27, 2.1, 0.5 * kPi)};
  map.stats.poses = static_cast<int>(map.per_pose.size());
  map.stats.shapelets = static_cast<int>(map.shapelets.size());
  return map;
}


std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
using SurfacePtr = std::unique_ptr<cairo_surface_t, SurfaceDeleter>;

SurfacePtr loadPng(const std::string& path) {
  return SurfacePtr(cairo_image_surface_create_from_png(path.c_str()));
}

struct Rgb8 {
  int r, g, b;
};

// The colour of the pixel containing arena point `m` (alpha is ignored: the picture is opaque).
Rgb8 pixelAt(cairo_surface_t* image, const MapCanvas& canvas, const Vec2& m) {
  cairo_surface_flush(image);
  const Vec2 px = canvas.toPixel(m);
  const int x = static_cast<int>(std::floor(px.x()));
  const int y = static_cast<int>(std::floor(px.y()));
  const unsigned char* row =
      cairo_image_surface_get_data(image) + y * cairo_image_surface_get_stride(image);
  uint32_t v;
  std::memcpy(&v, row + 4 * x, sizeof v);  // native-endian xRGB
  return {static_cast<int>((v >> 16) & 0xff), static_cast<int>((v >> 8) & 0xff),
          static_cast<int>(v & 0xff)};
}

// Colour thresholds on 0-255 channels; antialiasing only blends within a pixel or so of an
// edge, so a sample a few pixels inside a shape shows its colour nearly exactly.
constexpr int kDarkMax = 80;     // a truth leg is 15% grey (38)
constexpr int kWhiteMin = 250;   // background is pure white
constexpr int kBlueMargin = 80;  // the fused blue is (13, 77, 217)

bool isDark(const Rgb8& c) { return c.r <= kDarkMax && c.g <= kDarkMax && c.b <= kDarkMax; }
bool isWhite(const Rgb8& c) { return c.r >= kWhiteMin && c.g >= kWhiteMin && c.b >= kWhiteMin; }
bool isBlueish(const Rgb8& c) { return c.b > c.r + kBlueMargin && c.b > c.g + kBlueMargin; }

std::string describe(const Rgb8& c) {
  return "rgb(" + std::to_string(c.r) + ", " + std::to_string(c.g) + ", " + std::to_string(c.b) +
         ")";
}

// One axis-aligned table, fused exactly on the truth, a few poses, nothing else: every pixel
// probed by the colour test has a known layer on top.
struct SimpleCase {
  Scene scene;
  Map map;
};
SimpleCase makeSimpleCase() {
  SimpleCase c;
  c.scene.width = 4.0;
  c.scene.depth = 3.0;
  c.scene.tables = {makeTable(1.0, 1.0, 0.0)};
  c.scene.poses = {{0.3, 0.3, 0.0}, {0.3, 0.3, kPi}, {2.0, 2.0, 0.0}};
  c.map.tables = {makeMapTable(1.0, 1.0, 0.0)};
  PoseMap pm;
  pm.pose = {0.3, 0.3, 0.0};
  pm.tables = {makeMapTable(1.0, 1.0, 0.0)};
  c.map.per_pose = {pm};
  return c;
}

}  // namespace

TEST_CASE("Render: PNG has the signature and arena size times scale plus margins", "[render]") {
  TempDir dir;
  const Scene scene = makeScene();
  const Map map = makeMap(scene);
  const std::string path = dir.file("map.png");
  RenderOptions options;
  options.pixels_per_metre = 150;

  const Status st = renderMapPng(map, scene, path, options);
  REQUIRE(st.ok());
  REQUIRE(fs::exists(path));
  CHECK_FALSE(fs::exists(path + ".tmp"));

  const std::string bytes = readFile(path);
  const std::string kPngSignature = "\x89PNG\r\n\x1a\n";
  REQUIRE(bytes.size() > kPngSignature.size());
  CHECK(bytes.compare(0, kPngSignature.size(), kPngSignature) == 0);

  SurfacePtr image = loadPng(path);
  REQUIRE(cairo_surface_status(image.get()) == CAIRO_STATUS_SUCCESS);
  CHECK(cairo_image_surface_get_width(image.get()) ==
        MapCanvas::kMarginLeft + 4.0 * 150 + MapCanvas::kMarginRight);
  CHECK(cairo_image_surface_get_height(image.get()) ==
        MapCanvas::kMarginTop + 4.0 * 150 + MapCanvas::kMarginBottom);
}

TEST_CASE("Render: a large arena is drawn smaller, within max_picture_px", "[render]") {
  TempDir dir;
  Scene scene = makeScene();
  scene.width = 200.0;  // kMaxArenaSide: at 200 px/m a 40000 px picture
  scene.depth = 50.0;
  const Map map = makeMap(scene);
  const std::string path = dir.file("map.png");
  RenderOptions options;  // 200 px/m, at most 8192 px a side
  REQUIRE(renderMapPng(map, scene, path, options).ok());
  SurfacePtr image = loadPng(path);
  REQUIRE(cairo_surface_status(image.get()) == CAIRO_STATUS_SUCCESS);
  CHECK(cairo_image_surface_get_width(image.get()) == options.max_picture_px);
  const double ppm = (options.max_picture_px - MapCanvas::kMarginLeft - MapCanvas::kMarginRight) / 200.0;
  CHECK(cairo_image_surface_get_height(image.get()) ==
        static_cast<int>(MapCanvas::kMarginTop + 50.0 * ppm + MapCanvas::kMarginBottom));
  // A max_picture_px out of range is an Error naming it; no file.
  options.max_picture_px = 40000;
  const Status bad = renderMapPng(map, scene, dir.file("bad.png"), options);
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().message.find("max_picture_px") != std::string::npos);
  CHECK_FALSE(fs::exists(dir.file("bad.png")));
}

TEST_CASE("Render: truth legs are dark, fused edges blue, empty arena white", "[render]") {
  TempDir dir;
  const SimpleCase c = makeSimpleCase();
  const std::string path = dir.file("simple.png");
  REQUIRE(renderMapPng(c.map, c.scene, path).ok());
  SurfacePtr image = loadPng(path);
  REQUIRE(cairo_surface_status(image.get()) == CAIRO_STATUS_SUCCESS);
  const MapCanvas canvas(c.scene.width, c.scene.depth, RenderOptions{}.pixels_per_metre);

  const TableSpec& table = c.scene.tables[0];
  const Vec2 leg_centre = table.legs()[0].pose.position();
  const Rgb8 leg = pixelAt(image.get(), canvas, leg_centre);
  INFO("leg centre " << describe(leg));
  CHECK(isDark(leg));

  // Midpoint of the fused table's +y edge (the table is axis-aligned).
  const Vec2 edge = c.map.tables[0].pose.position() + Vec2{0.0, 0.5 * kStandardTableDepth};
  const Rgb8 fused = pixelAt(image.get(), canvas, edge);
  INFO("fused edge " << describe(fused));
  CHECK(isBlueish(fused));

  // Between grid lines, far from the table, the poses and the walls.
  const Rgb8 empty = pixelAt(image.get(), canvas, {3.2, 2.2});
  INFO("empty arena " << describe(empty));
  CHECK(isWhite(empty));

  // The origin is the arena's bottom-left: a point low in the arena is low in the picture.
  CHECK(canvas.toPixel({0.0, 0.0}).y() > canvas.toPixel({0.0, 1.0}).y());
}

TEST_CASE("Render: overlapping per-pose tables build up darker red", "[render]") {
  TempDir dir;
  SimpleCase c = makeSimpleCase();
  c.map.tables.clear();
  c.map.per_pose.clear();
  // One pose sees a table at A; five poses agree on a table at B. Both in empty arena.
  const Vec2 a{3.1, 0.9}, b{3.1, 2.1};
  PoseMap one;
  one.tables = {makeMapTable(a.x(), a.y(), 0.0)};
  c.map.per_pose.push_back(one);
  for (int k = 0; k < 5; ++k) {
    PoseMap agree;
    agree.tables = {makeMapTable(b.x(), b.y(), 0.0)};
    c.map.per_pose.push_back(agree);
  }
  const std::string path = dir.file("red.png");
  REQUIRE(renderMapPng(c.map, c.scene, path).ok());
  SurfacePtr image = loadPng(path);
  REQUIRE(cairo_surface_status(image.get()) == CAIRO_STATUS_SUCCESS);
  const MapCanvas canvas(c.scene.width, c.scene.depth, RenderOptions{}.pixels_per_metre);

  // Probe the -x edge midpoints, off the grid lines.
  const Vec2 to_edge{-0.5 * kStandardTableWidth, 0.0};
  const Rgb8 faint = pixelAt(image.get(), canvas, a + to_edge);
  const Rgb8 strong = pixelAt(image.get(), canvas, b + to_edge);
  INFO("one pose " << describe(faint) << ", five poses " << describe(strong));
  CHECK(faint.r > faint.g);  // reddish
  CHECK(faint.g < 255);
  CHECK(strong.r > strong.g + 80);
  CHECK(strong.g < faint.g);  // agreement is darker
}

TEST_CASE("Render: SVG is a complete svg document", "[render]") {
  TempDir dir;
  const Scene scene = makeScene();
  const Map map = makeMap(scene);
  const std::string path = dir.file("map.svg");
  RenderOptions options;
  options.title = "svg test";
  REQUIRE(renderMapSvg(map, scene, path, options).ok());
  CHECK_FALSE(fs::exists(path + ".tmp"));
  const std::string text = readFile(path);
  CHECK(text.find("<svg") != std::string::npos);
  CHECK(text.find("</svg>") != std::string::npos);
}

TEST_CASE("Render: a missing directory is an Error naming the path and leaves no file",
          "[render]") {
  TempDir dir;
  const Scene scene = makeScene();
  const Map map = makeMap(scene);
  const std::string png = dir.file("no_such_dir/map.png");
  const std::string svg = dir.file("no_such_dir/map.svg");

  const Status png_status = renderMapPng(map, scene, png);
  REQUIRE_FALSE(png_status.ok());
  CHECK_THAT(png_status.error().message, Catch::Contains(png));
  CHECK_THAT(png_status.error().message, Catch::Contains("error while writing"));
  CHECK_FALSE(fs::exists(png));
  CHECK_FALSE(fs::exists(png + ".tmp"));

  const Status svg_status = renderMapSvg(map, scene, svg);
  REQUIRE_FALSE(svg_status.ok());
  CHECK_THAT(svg_status.error().message, Catch::Contains(svg));
  CHECK_FALSE(fs::exists(svg));
  CHECK_FALSE(fs::exists(svg + ".tmp"));
}

TEST_CASE("Render: a failed render leaves an existing picture untouched", "[render]") {
  TempDir dir;
  const SimpleCase c = makeSimpleCase();
  const std::string path = dir.file("keep.png");
  REQUIRE(renderMapPng(c.map, c.scene, path).ok());
  const std::string before = readFile(path);

  RenderOptions bad;
  bad.max_picture_px = 40000;  // past cairo's 32767 px limit (a large scale is fitted, not refused)
  const Status st = renderMapPng(c.map, c.scene, path, bad);
  REQUIRE_FALSE(st.ok());
  CHECK_THAT(st.error().message, Catch::Contains(path));
  CHECK(readFile(path) == before);
  CHECK_FALSE(fs::exists(path + ".tmp"));

  bad.pixels_per_metre = 0.0;
  CHECK_FALSE(renderMapSvg(c.map, c.scene, path, bad).ok());
  CHECK(readFile(path) == before);
}

// Not run by default: `render_test "[.sample]"` writes a sample montage to look at.
TEST_CASE("Render: sample montage for eyeballing", "[.sample]") {
  const Scene scene = makeScene();
  const Map map = makeMap(scene);
  RenderOptions options;
  options.title = "render_test sample";
  const std::string base = (fs::temp_directory_path() / "render_sample").string();
  REQUIRE(renderMapPng(map, scene, base + ".png", options).ok());
  REQUIRE(renderMapSvg(map, scene, base + ".svg", options).ok());
}
