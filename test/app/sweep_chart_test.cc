// crunchhost sweep-chart (host/app/sweep_chart.h): the files drawn from a small synthetic
// sweep.json written here (no real sweep runs), and bad input (exit 2, a message naming the file,
// nothing written). The statistics themselves: test/mapping/sweep_statistics_test.cc.
#include "sweep_chart.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "support/synthetic_sweep.h"
#include "support/temp_dir.h"

using namespace crunch;
using Json = nlohmann::ordered_json;

namespace {

struct Run {
  int code;
  std::string out, err;
};

Run chart(const std::string& in, const std::string& out_dir) {
  std::ostringstream out, err;
  const int code = app::runSweepChart({in, out_dir}, out, err);
  return {code, out.str(), err.str()};
}

void write(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
}

using synthetic_sweep::row;
Json synthetic() { return synthetic_sweep::sweep(); }

}  // namespace

TEST_CASE("sweep-chart draws the Pareto and noise charts and a summary", "[sweep_chart]") {
  TempDir in, out;
  write(in.file("sweep.json"), synthetic().dump(1));
  const Run r = chart(in.path().string(), out.file("charts"));
  INFO(r.err);
  REQUIRE(r.code == 0);
  for (const std::string name : {"pareto_realistic", "pareto_realistic_proposals", "pareto_noisy",
                                 "pareto_noisy_proposals", "noise"}) {
    for (const std::string ext : {".png", ".svg"}) {
      const auto p = std::filesystem::path(out.file("charts")) / (name + ext);
      INFO(p);
      REQUIRE(std::filesystem::exists(p));
      // A drawn chart with axes, text and data, not an empty canvas.
      CHECK(std::filesystem::file_size(p) > 10000);
    }
  }
  // The front printed and in summary.csv: (8, 2, 14) is off it.
  CHECK(r.out.find("realistic: Pareto front (wall time): [4 T x 1 sweep, WM 7: F1 0.500, 0.20 s] "
                   "[8 T x 1 sweep, WM 7: F1 0.700, 0.40 s] [16 T x 1 sweep, WM 7: F1 0.800, "
                   "0.90 s]") != std::string::npos);
  std::ifstream csv(out.file("charts") + "/summary.csv");
  std::string line, text;
  int lines = 0;
  while (std::getline(csv, line)) {
    ++lines;
    text += line + "\n";
  }
  CHECK(lines == 9);
  CHECK(text.find("default,paper,realistic,5,8,2,14,2,0.6000,0.1414,0.6000,0.1414,0.7000,0.0000,1.2000,"
                  "300000,0,0") != std::string::npos);
  CHECK(text.find("default,paper,realistic,5,16,1,7,2,0.8000") != std::string::npos);
  // Noise: recall 0.8 at 5 mm, 0.2 at 25 mm (the paper's setting).
  CHECK(r.out.find("mean recall below 0.5 from sigma_r = 25 mm") != std::string::npos);
}

TEST_CASE("sweep-chart without --out writes beside sweep.json, one setting draws only noise",
          "[sweep_chart]") {
  TempDir in;
  Json rows = Json::array();
  for (const auto& [name, s] : {std::pair{"x0.5", 0.5}, std::pair{"x1", 1.0}, std::pair{"x2", 2.0}}) {
    rows.push_back(row(name, 0.005 * s, 16, 1, 7, 1, 0.5 / s, 0.5 / s, 0.5, 1e5));
  }
  write(in.file("sweep.json"), rows.dump());
  const Run r = chart(in.path().string(), "");
  REQUIRE(r.code == 0);
  CHECK(std::filesystem::exists(in.file("noise.png")));
  CHECK(std::filesystem::exists(in.file("noise.svg")));
  CHECK(std::filesystem::exists(in.file("summary.csv")));
  CHECK_FALSE(std::filesystem::exists(in.file("pareto_x1.png")));
  CHECK(in.entries().size() == 4);  // sweep.json, noise.png, noise.svg, summary.csv
  CHECK(r.out.find("mean recall below 0.5 from sigma_r = 10 mm") != std::string::npos);
}

TEST_CASE("sweep-chart refuses bad input: exit 2, the file named, nothing written",
          "[sweep_chart]") {
  TempDir in, out;
  const std::string path = in.file("sweep.json");
  const std::string out_dir = out.file("charts");
  auto refused = [&](const std::string& what) {
    const Run r = chart(in.path().string(), out_dir);
    INFO(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find(path) != std::string::npos);
    CHECK(r.err.find(what) != std::string::npos);
    CHECK_FALSE(std::filesystem::exists(out_dir));
  };
  SECTION("missing file") { refused("cannot read"); }
  SECTION("not JSON") {
    write(path, "[{\"f1\": ");
    refused("parse error at line 1, column 9");  // the place, from the strict reader
  }
  SECTION("not an array") {
    write(path, "{}");
    refused("not a JSON array");
  }
  SECTION("no rows") {
    write(path, "[]");
    refused("has no rows");
  }
  SECTION("a missing column") {
    Json rows = synthetic();
    rows[3].erase("wall_s");
    write(path, rows.dump());
    refused("row 3 has no column 'wall_s'");
  }
  SECTION("a column of the wrong type") {
    Json rows = synthetic();
    rows[1]["schedule_steps"] = "16";
    write(path, rows.dump());
    refused("row 1: column 'schedule_steps' must be an integer");
  }
  SECTION("two scenes") {
    Json rows = synthetic();
    rows[5]["scene"] = "test/scenes/two_tables.json";
    write(path, rows.dump());
    refused("row 5 is of scene");
  }
}
