// crunchhost --sim --snapshot K (sim/app/sim_mode.h, render/blackboard_snapshot.h,
// map_render.h): the blackboard picture of paper Figs. 3-4 after pose K's annealing, on the small two_tables scene.
#include <cairo.h>

#include <catch2/catch.hpp>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <memory>
#include <sstream>

#include "sim_mode.h"

using namespace crunch;
namespace fs = std::filesystem;

namespace {

struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
using SurfacePtr = std::unique_ptr<cairo_surface_t, SurfaceDeleter>;

// Pixels within +-6 per channel of (r, g, b) left of column `w` (the legend's column is not
// counted, so only the drawn layers are).
int countColour(cairo_surface_t* image, int w, int r, int g, int b) {
  cairo_surface_flush(image);
  const int h = cairo_image_surface_get_height(image);
  const int stride = cairo_image_surface_get_stride(image);
  const unsigned char* data = cairo_image_surface_get_data(image);
  int n = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      uint32_t v;
      std::memcpy(&v, data + y * stride + 4 * x, sizeof v);  // native-endian xRGB
      const int pr = (v >> 16) & 0xff, pg = (v >> 8) & 0xff, pb = v & 0xff;
      n += std::abs(pr - r) <= 6 && std::abs(pg - g) <= 6 && std::abs(pb - b) <= 6;
    }
  }
  return n;
}

app::SimOptions twoTables(const fs::path& dir) {
  app::SimOptions opt;
  opt.scene_path = std::string(CRUNCH_SOURCE_DIR) + "/test/scenes/two_tables.json";
  opt.out_dir = dir.string();
  return opt;
}

}  // namespace

TEST_CASE("crunchhost --sim --snapshot K: the blackboard after pose K", "[app][snapshot]") {
  const fs::path dir = fs::temp_directory_path() / "crunch_app_test_snapshot";
  fs::remove_all(dir);
  app::SimOptions opt = twoTables(dir);
  // two_tables.json has 20 reachable poses; after the last (seed 1) the paper's model's
  // blackboard holds one table hypothesis (a MAP table) with legs in it and a full working
  // memory (the walls model's holds none: the contacts there are the arena's corners).
  opt.mapping.model.objects = ObjectModel::kPaper;
  opt.snapshot_pose = 19;
  std::ostringstream out, err;
  REQUIRE(app::runSim(opt, out, err) == 0);
  INFO(err.str());
  const fs::path png = dir / "snapshot_19.png";
  REQUIRE(fs::exists(png));
  REQUIRE(fs::exists(dir / "snapshot_19.svg"));
  CHECK(fs::file_size(png) > 5000);
  CHECK(fs::file_size(png) < 2000000);
  SurfacePtr image(cairo_image_surface_create_from_png(png.string().c_str()));
  REQUIRE(cairo_surface_status(image.get()) == CAIRO_STATUS_SUCCESS);
  // The 3.0 x 2.5 m arena at 200 px/m plus margins (map_render.h MapCanvas).
  CHECK(cairo_image_surface_get_width(image.get()) == 56 + 600 + 190);
  CHECK(cairo_image_surface_get_height(image.get()) == 44 + 500 + 48);
  // Inside the arena only (x < the legend column): the layers' colours (map_render.cc).
  const int arena_right = 56 + 600;
  const int tables = countColour(image.get(), arena_right, 204, 0, 153);  // kSnapTable
  const int legs = countColour(image.get(), arena_right, 0, 140, 38);     // kSnapLeg
  const int whiskers = countColour(image.get(), arena_right, 0, 115, 140);
  const int shapelets = countColour(image.get(), arena_right, 255, 158, 0);
  INFO("tables " << tables << ", legs " << legs << ", whiskers " << whiskers << ", shapelets "
                 << shapelets);
  // Measured (seed 1): 741, 126, 60, 97; about half of each, and 0 if a layer is missing.
  CHECK(tables > 350);
  CHECK(legs > 60);
  CHECK(whiskers > 30);
  CHECK(shapelets > 45);
  CHECK(out.str().find("snapshot_19.{png,svg}") != std::string::npos);

  SECTION("off by default: no snapshot file") {
    const fs::path plain = fs::temp_directory_path() / "crunch_app_test_snapshot_off";
    fs::remove_all(plain);
    std::ostringstream o2, e2;
    REQUIRE(app::runSim(twoTables(plain), o2, e2) == 0);
    for (const auto& entry : fs::directory_iterator(plain))
      CHECK(entry.path().filename().string().rfind("snapshot_", 0) == std::string::npos);
  }
}

TEST_CASE("crunchhost --sim --snapshot K beyond the poses is exit 2, nothing written",
          "[app][snapshot]") {
  for (int k : {20, 999, -1}) {
    const fs::path dir = fs::temp_directory_path() / "crunch_app_test_snapshot_bad";
    fs::remove_all(dir);
    app::SimOptions opt = twoTables(dir);
    opt.snapshot_pose = k;
    std::ostringstream out, err;
    CHECK(app::runSim(opt, out, err) == 2);
    CHECK(err.str().find("--snapshot " + std::to_string(k) + ": no such pose") !=
          std::string::npos);
    CHECK(err.str().find("20 reachable poses") != std::string::npos);
    CHECK_FALSE(fs::exists(dir));
  }
}

TEST_CASE("crunchhost --sim --snapshot K --snapshot-temperature I: part-way through pose K's "
          "annealing, and the map is unchanged",
          "[app][snapshot]") {
  const fs::path dir = fs::temp_directory_path() / "crunch_app_test_snapshot_hot";
  const fs::path plain = fs::temp_directory_path() / "crunch_app_test_snapshot_hot_plain";
  fs::remove_all(dir);
  fs::remove_all(plain);
  app::SimOptions opt = twoTables(dir);
  opt.snapshot_pose = 17;        // the last pose of two_tables.json that senses new shapelets
  opt.snapshot_temperature = 0;  // the hottest, beta = 1
  std::ostringstream out, err;
  REQUIRE(app::runSim(opt, out, err) == 0);
  INFO(err.str());
  REQUIRE(fs::exists(dir / "snapshot_17.png"));
  CHECK(fs::file_size(dir / "snapshot_17.png") > 5000);
  // Taking the picture draws no random number and changes nothing: the same map.
  std::ostringstream o2, e2;
  REQUIRE(app::runSim(twoTables(plain), o2, e2) == 0);
  auto tablesOf = [](const fs::path& p) {
    std::ifstream in(p / "map.json");
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string text = ss.str();
    return text.substr(0, text.find("\"stats\""));  // tables, walls, per_pose (not wall time)
  };
  CHECK(tablesOf(dir) == tablesOf(plain));
}

TEST_CASE("crunchhost --sim --snapshot-temperature at a pose that did not anneal writes none, "
          "and says why",
          "[app][snapshot]") {
  const fs::path dir = fs::temp_directory_path() / "crunch_app_test_snapshot_cold";
  fs::remove_all(dir);
  app::SimOptions opt = twoTables(dir);
  opt.snapshot_pose = 19;  // senses nothing new (measured): no annealing at pose 19
  opt.snapshot_temperature = 3;
  std::ostringstream out, err;
  REQUIRE(app::runSim(opt, out, err) == 0);
  CHECK_FALSE(fs::exists(dir / "snapshot_19.png"));
  CHECK(err.str().find("did not anneal") != std::string::npos);
}

TEST_CASE("crunchhost --sim --snapshot-temperature out of range or without --snapshot is exit 2",
          "[app][snapshot]") {
  for (const std::optional<int> k : {std::optional<int>(19), std::optional<int>()}) {
    for (int i : {16, -1}) {
      if (!k && i == -1) continue;
      const fs::path dir = fs::temp_directory_path() / "crunch_app_test_snapshot_badT";
      fs::remove_all(dir);
      app::SimOptions opt = twoTables(dir);
      opt.snapshot_pose = k;
      opt.snapshot_temperature = i;
      std::ostringstream out, err;
      CHECK(app::runSim(opt, out, err) == 2);
      CHECK(err.str().find("--snapshot-temperature") != std::string::npos);
      CHECK_FALSE(fs::exists(dir));
    }
  }
}
