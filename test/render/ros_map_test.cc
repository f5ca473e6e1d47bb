#include "crunch/render/ros_map.h"

#include <yaml-cpp/yaml.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "crunch/mapping/map_io.h"
#include "crunch/scene/scene.h"
#include "support/temp_dir.h"

using crunch::FreeSpaceLayer;
using crunch::kRosFree;
using crunch::kRosOccupied;
using crunch::kRosUnknown;
using crunch::Map;
using crunch::MapTable;
using crunch::MapWall;
using crunch::RosMapGrid;
using crunch::RosMapOptions;
using crunch::Vec2;

namespace {

std::string readFile(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The PGM as map_server reads it: P5, comments, width, height, maxval, then rows from the top.
struct Pgm {
  int width = 0, height = 0, maxval = 0;
  std::string pixels;  // row 0 = top
  unsigned char atImage(int col, int row) const {
    return static_cast<unsigned char>(pixels[static_cast<std::size_t>(row * width + col)]);
  }
};

Pgm readPgm(const std::string& path) {
  const std::string data = readFile(path);
  std::istringstream in(data);
  std::string magic;
  in >> magic;
  REQUIRE(magic == "P5");
  const auto skipComments = [&in] {
    in >> std::ws;
    while (in.peek() == '#') {
      std::string line;
      std::getline(in, line);
      in >> std::ws;
    }
  };
  Pgm p;
  skipComments();
  in >> p.width;
  skipComments();
  in >> p.height;
  skipComments();
  in >> p.maxval;
  in.get();  // the single whitespace before the raster
  p.pixels = data.substr(static_cast<std::size_t>(in.tellg()));
  return p;
}

// A map: one standard table at (1.5, 1.0) turned by 0.3, one wall, and a swept region that
// covers the table's area (the free space under and around it, as a body whisk leaves it).
Map sampleMap() {
  Map m;
  MapTable t;
  t.pose = {1.5, 1.0, 0.3};
  m.tables.push_back(t);
  m.walls.push_back(MapWall{{0.5, 2.0}, {2.5, 2.0}, 0.9});
  FreeSpaceLayer& f = m.free_space;
  f.origin = {0.8, 0.4};
  f.cell = 0.01;
  f.nx = 140;  // x 0.8 .. 2.2
  f.ny = 120;  // y 0.4 .. 1.6
  f.swept.assign(static_cast<std::size_t>(f.nx * f.ny), 1);
  return m;
}

// The world point `p` in image coordinates of the exported files (column, row from the top).
void imageCell(const YAML::Node& yaml, const Pgm& pgm, const Vec2& p, int& col, int& row) {
  const double res = yaml["resolution"].as<double>();
  const double ox = yaml["origin"][0].as<double>();
  const double oy = yaml["origin"][1].as<double>();
  col = static_cast<int>(std::floor((p.x() - ox) / res));
  const int iy = static_cast<int>(std::floor((p.y() - oy) / res));
  row = pgm.height - 1 - iy;
}

}  // namespace

TEST_CASE("RosMap: files read back give occupied legs and walls, free swept floor, unknown rest",
          "[render]") {
  TempDir dir;
  const Map map = sampleMap();
  REQUIRE(crunch::writeFileAtomic(dir.file("map.json"), crunch::mapToJson(map)).ok());
  RosMapOptions opt;
  opt.resolution = 0.02;
  const auto r = crunch::exportRosMap(dir.file("map.json"), dir.file("ros"), opt);
  REQUIRE(r.ok());
  CHECK(r.value().had_free_space);

  const YAML::Node yaml = YAML::LoadFile(dir.file("ros/map.yaml"));
  CHECK(yaml["image"].as<std::string>() == "map.pgm");
  CHECK(yaml["resolution"].as<double>() == 0.02);
  CHECK(yaml["negate"].as<int>() == 0);
  CHECK(yaml["mode"].as<std::string>() == "trinary");
  REQUIRE(yaml["origin"].size() == 3);
  CHECK(yaml["origin"][2].as<double>() == 0.0);
  const double occupied_thresh = yaml["occupied_thresh"].as<double>();
  const double free_thresh = yaml["free_thresh"].as<double>();
  const Pgm pgm = readPgm(dir.file("ros/map.pgm"));
  REQUIRE(pgm.maxval == 255);
  REQUIRE(pgm.pixels.size() == static_cast<std::size_t>(pgm.width * pgm.height));
  CHECK(pgm.width == r.value().width);
  CHECK(pgm.height == r.value().height);

  // map_server's trinary reading of a pixel (negate 0): occupancy (255 - v) / 255.
  const auto classify = [&](unsigned char v) {
    const double occ = (255.0 - v) / 255.0;
    if (occ > occupied_thresh) return 'o';
    if (occ < free_thresh) return 'f';
    return 'u';
  };
  const auto at = [&](const Vec2& p) {
    int col, row;
    imageCell(yaml, pgm, p, col, row);
    REQUIRE(col >= 0);
    REQUIRE(row >= 0);
    REQUIRE(col < pgm.width);
    REQUIRE(row < pgm.height);
    return classify(pgm.atImage(col, row));
  };

  // Every leg's centre and its four inner corners (2 mm in) are occupied.
  crunch::TableSpec spec;
  spec.pose = map.tables[0].pose;
  int leg_points = 0;
  for (const auto& leg : spec.legs()) {
    CHECK(at(leg.pose.position()) == 'o');
    for (const Vec2& c : leg.corners()) {
      CHECK(at(c + 0.1 * (leg.pose.position() - c)) == 'o');
      ++leg_points;
    }
  }
  CHECK(leg_points == 16);
  // The table's centre is under its top: swept, so free (the Create drives under tops).
  CHECK(at(spec.pose.position()) == 'f');
  // Along the wall every 5 cm: occupied; 5 cm below it (outside the swept region): unknown.
  for (int i = 0; i <= 40; ++i) {
    const double x = 0.5 + 0.05 * i;
    CHECK(at({x, 2.0}) == 'o');
    CHECK(at({x, 1.95}) == 'u');
  }
  // Swept cells away from every leg are free; cells outside the swept region and off the wall
  // are unknown. Checked cell by cell over the whole grid.
  long long free_checked = 0, unknown_checked = 0;
  const double res = 0.02;
  const double ox = yaml["origin"][0].as<double>(), oy = yaml["origin"][1].as<double>();
  for (int row = 0; row < pgm.height; ++row) {
    for (int col = 0; col < pgm.width; ++col) {
      const Vec2 c{ox + (col + 0.5) * res, oy + (pgm.height - 1 - row + 0.5) * res};
      double leg_distance = 1e9;
      for (const auto& leg : spec.legs()) {
        leg_distance = std::min(leg_distance, (c - leg.pose.position()).norm());
      }
      const bool near_object = leg_distance < 0.06 || std::abs(c.y() - 2.0) < 0.03;
      if (near_object) continue;
      const bool swept = c.x() > 0.8 && c.x() < 2.2 && c.y() > 0.4 && c.y() < 1.6;
      const char got = classify(pgm.atImage(col, row));
      if (swept) {
        CHECK(got == 'f');
        ++free_checked;
      } else {
        CHECK(got == 'u');
        ++unknown_checked;
      }
    }
  }
  CHECK(free_checked > 3500);
  CHECK(unknown_checked > 1000);
  CHECK(r.value().occupied > 0);
  CHECK(r.value().free + r.value().occupied + r.value().unknown ==
        static_cast<long long>(pgm.width) * pgm.height);
}

TEST_CASE("RosMap: --tops-occupied fills the table top", "[render]") {
  Map map = sampleMap();
  RosMapOptions opt;
  const auto plain = crunch::rasteriseRosMap(map, opt);
  opt.tops_occupied = true;
  const auto tops = crunch::rasteriseRosMap(map, opt);
  REQUIRE(plain.ok());
  REQUIRE(tops.ok());
  const RosMapGrid& g = tops.value();
  const auto cellOf = [&g](const Vec2& p, int& ix, int& iy) {
    ix = static_cast<int>(std::floor((p.x() - g.origin.x()) / g.resolution));
    iy = static_cast<int>(std::floor((p.y() - g.origin.y()) / g.resolution));
  };
  int ix, iy;
  cellOf(map.tables[0].pose.position(), ix, iy);
  CHECK(plain.value().at(ix, iy) == kRosFree);
  CHECK(g.at(ix, iy) == kRosOccupied);
  // A point of the top 30 cm along its long side from the centre.
  const Vec2 p = map.tables[0].pose.toWorld({0.3, 0.1});
  cellOf(p, ix, iy);
  CHECK(plain.value().at(ix, iy) == kRosFree);
  CHECK(g.at(ix, iy) == kRosOccupied);
}

TEST_CASE("RosMap: a map file without free_space has no free cell", "[render]") {
  Map map = sampleMap();
  map.free_space = FreeSpaceLayer{};
  const auto g = crunch::rasteriseRosMap(map, RosMapOptions{});
  REQUIRE(g.ok());
  int occupied = 0;
  for (std::uint8_t c : g.value().cells) {
    CHECK(c != kRosFree);
    if (c == kRosOccupied) ++occupied;
  }
  CHECK(occupied > 50);  // the legs and the 2 m wall
  // The grid still covers every object with a cell to spare.
  CHECK(g.value().origin.x() < 0.5);
  CHECK(g.value().origin.x() + g.value().width * 0.02 > 2.5);
}

TEST_CASE("RosMap: a grid finer than the free-space layer is free where its centre is swept",
          "[render]") {
  Map map;
  FreeSpaceLayer& f = map.free_space;
  f.origin = {0.0, 0.0};
  f.cell = 0.01;
  f.nx = 10;
  f.ny = 10;
  f.swept.assign(100, 0);
  f.swept[5 * 10 + 5] = 1;  // the cell [0.05, 0.06) x [0.05, 0.06)
  RosMapOptions opt;
  opt.resolution = 0.005;
  const auto g = crunch::rasteriseRosMap(map, opt);
  REQUIRE(g.ok());
  int free = 0;
  for (int iy = 0; iy < g.value().height; ++iy) {
    for (int ix = 0; ix < g.value().width; ++ix) {
      if (g.value().at(ix, iy) != kRosFree) continue;
      ++free;
      const Vec2 c = g.value().centre(ix, iy);
      CHECK(c.x() > 0.05);
      CHECK(c.x() < 0.06);
      CHECK(c.y() > 0.05);
      CHECK(c.y() < 0.06);
    }
  }
  CHECK(free == 4);  // the 1 cm cell is 2 x 2 half-centimetre cells
}

TEST_CASE("RosMap: a bad resolution is an error naming --resolution and nothing is written",
          "[render]") {
  TempDir dir;
  REQUIRE(crunch::writeFileAtomic(dir.file("map.json"), crunch::mapToJson(sampleMap())).ok());
  for (double bad : {0.0, -0.02, 0.0005, 1.5, std::nan(""), HUGE_VAL}) {
    RosMapOptions opt;
    opt.resolution = bad;
    INFO(bad);
    const auto r = crunch::exportRosMap(dir.file("map.json"), dir.file("out"), opt);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message.find("--resolution") != std::string::npos);
    CHECK_FALSE(std::filesystem::exists(dir.file("out")));
  }
  // A grid over 10^8 cells: a 50 x 50 m free-space layer at 1 mm.
  Map big;
  big.free_space.origin = {0.0, 0.0};
  big.free_space.cell = 0.5;
  big.free_space.nx = 100;
  big.free_space.ny = 100;
  big.free_space.swept.assign(10000, 0);
  RosMapOptions fine;
  fine.resolution = 0.001;
  const auto r = crunch::rasteriseRosMap(big, fine);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("10^8") != std::string::npos);
}

TEST_CASE("RosMap: a bad or missing map file is an error naming it and nothing is written",
          "[render]") {
  TempDir dir;
  const auto missing = crunch::exportRosMap(dir.file("nope.json"), dir.file("out"), {});
  REQUIRE_FALSE(missing.ok());
  CHECK(missing.error().message.find("nope.json") != std::string::npos);
  REQUIRE(crunch::writeFileAtomic(dir.file("bad.json"),
                                  R"({"schema": "crunch.map/1", "free_space": {"cell": 0.01, )"
                                  R"("origin": [0, 0], "size": [4, 1], "rows": ["2+5"]}})")
              .ok());
  const auto bad = crunch::exportRosMap(dir.file("bad.json"), dir.file("out"), {});
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().message.find("bad.json") != std::string::npos);
  CHECK(bad.error().message.find("free_space.rows[0]") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(dir.file("out")));
}
