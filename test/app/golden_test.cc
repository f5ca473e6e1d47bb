// Behaviour kept across restructuring (issue 11): outputs of the `crunchhost` binary compared
// with files made by the binary of commit 1e043c6, before the sensing chain and the control loop
// moved into the library (test/golden/README.md says how each was made).
//   - `--sim --model paper` (gaussian sensor, realistic noise, seed 1) on the default arena and
//     on the test scenes: map.json equal in every value but the measured wall time.
//   - `sweep`: every column of every row equal but wall_s and the process's peak RSS.
//   - `--replay` of a `--robot` recording made inside crunch-virtual-robot before the move:
//     the same map and the same shapelets, counts and final pose in report.json.
// "Equal" is exact: the same numbers bit for bit (JSON text round-trips doubles exactly).
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "support/run_command.h"
#include "support/temp_dir.h"

namespace {

using json = nlohmann::json;

const std::string kSource = CRUNCH_SOURCE_DIR;

// `command` in the project's root: its exit status, its output in `out` (support/run_command.h).
int run(const std::string& command, std::string* out = nullptr) {
  return exitStatusIn(kSource, command, out);
}

json readJson(const std::string& path) {
  std::ifstream in(path);
  INFO(path);
  REQUIRE(in.good());
  return json::parse(in);
}

std::string readText(const std::string& path) {
  std::ifstream in(path);
  INFO(path);
  REQUIRE(in.good());
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// map.json without the one measured value in it, and without "free_space": the golden maps
// predate that extra key (issue 17; its content is checked by test/render/ros_map_test.cc and
// test/mapping/map_io_test.cc), and nothing else in the file changed with it.
json mapWithoutTime(json map) {
  map["stats"]["wall_s"] = 0.0;
  map.erase("free_space");
  return map;
}

std::vector<std::string> splitLines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> fields;
  std::istringstream in(line);
  for (std::string f; std::getline(in, f, ',');) fields.push_back(f);
  return fields;
}

}  // namespace

TEST_CASE("Golden: --sim maps the test scenes exactly as before the restructuring",
          "[golden]") {
  const std::string scene = GENERATE(as<std::string>{}, "default", "adjacent_tables", "dense_room",
                                     "empty_arena", "interior_walls", "sparse_poses",
                                     "table_at_wall", "two_tables", "hil_one_table",
                                     "physics_one_table");
  TempDir dir;
  const std::string arg = scene == "default" ? "" : " --scene test/scenes/" + scene + ".json";
  // The paper's model: the goldens were made with it (the default then).
  REQUIRE(run(std::string(CRUNCHHOST) + " --sim --model paper" + arg + " --json --out " +
              dir.path().string()) == 0);
  const json got = mapWithoutTime(readJson(dir.file("map.json")));
  const json want = readJson(kSource + "/test/golden/maps/" + scene + ".json");
  INFO(scene << ": " << json::diff(want, got).dump().substr(0, 2000));
  CHECK(got == want);
}

TEST_CASE("Golden: --threads 1, 2 and 3 give the same map.json", "[golden]") {
  // The global inference's chains run in parallel, each on its own stream, combined in chain
  // order (mapping/global_chain.h): the thread count must not change one bit of the map. The
  // default arena under the vote, and under the walls model with the posterior marginals.
  const std::string args = GENERATE(as<std::string>{}, "",
                                    " --model walls"
                                    " --chain-fusion marginal --seed 4");
  INFO("args:" << args);
  json first, first_moves;
  for (const int threads : {1, 2, 3}) {
    TempDir dir;
    REQUIRE(run(std::string(CRUNCHHOST) + " --sim" + args + " --threads " +
                std::to_string(threads) + " --out " + dir.path().string()) == 0);
    const json got = mapWithoutTime(readJson(dir.file("map.json")));
    const json report = readJson(dir.file("report.json"));
    CHECK(report["global_inference"]["threads"] == threads);
    // The chains' proposals by move family add up to the run's global proposals, each family's
    // accepted within its proposals, and the same counts for every thread count.
    const json& moves = report["global_inference"]["moves"];
    long long proposals = 0;
    for (const auto& [name, c] : moves.items()) {
      CHECK(c["accepted"].get<long long>() <= c["proposals"].get<long long>());
      proposals += c["proposals"].get<long long>();
    }
    CHECK(moves.contains("prime"));
    CHECK(proposals > 0);
    CHECK(proposals <= got["stats"]["proposals"].get<long long>());  // plus the per-pose ones
    if (threads == 1) first_moves = moves;
    else CHECK(moves == first_moves);
    if (threads == 1) {
      first = got;
      CHECK(got["tables"].size() >= 2);  // a map worth comparing
      // The marginals fuse the chains' walls too (the arena's four sides are touched).
      if (args.find("walls") != std::string::npos) CHECK(got["walls"].size() >= 3);
      continue;
    }
    INFO("threads " << threads << ": " << json::diff(first, got).dump().substr(0, 2000));
    CHECK(got == first);
  }
}

TEST_CASE("Golden: sweep rows are the same as before the restructuring", "[golden]") {
  TempDir dir;
  REQUIRE(run(std::string(CRUNCHHOST) +
              " sweep --model paper --scene test/scenes/two_tables.json --scene default"
              " --noise-scale 1,3"
              " --schedule-steps 4,8 --seeds 2 --jobs 2 --out " + dir.path().string()) == 0);
  const auto got = splitLines(readText(dir.file("sweep.csv")));
  const auto want = splitLines(readText(kSource + "/test/golden/sweep_before_refactor.csv"));
  REQUIRE(got.size() == want.size());
  REQUIRE(got[0] == want[0]);  // the header
  const auto columns = splitCsv(want[0]);
  for (std::size_t i = 1; i < want.size(); ++i) {
    const auto g = splitCsv(got[i]);
    const auto w = splitCsv(want[i]);
    REQUIRE(g.size() == columns.size());
    REQUIRE(w.size() == columns.size());
    for (std::size_t c = 0; c < columns.size(); ++c) {
      if (columns[c] == "wall_s" || columns[c] == "process_peak_rss_kib") continue;
      INFO("row " << i << " column " << columns[c]);
      CHECK(g[c] == w[c]);
    }
  }
}

TEST_CASE("Golden: --replay of a recording made before the restructuring gives the same map",
          "[golden]") {
  TempDir dir;
  REQUIRE(run("tar -xJf test/golden/replay/recording.tar.xz -C " + dir.path().string()) == 0);
  const std::string out = dir.file("out");
  REQUIRE(run(std::string(CRUNCHHOST) + " --replay " + dir.file("recording.crec") + " --out " +
              out) == 0);
  const json got = mapWithoutTime(readJson(out + "/map.json"));
  const json want = readJson(kSource + "/test/golden/replay/map.json");
  INFO(json::diff(want, got).dump());
  CHECK(got == want);
  CHECK(got["per_pose"].size() >= 2);  // the recording holds whisks that sensed something
  const json report = readJson(out + "/report.json");
  const json subset = readJson(kSource + "/test/golden/replay/report_subset.json");
  CHECK(report["shapelets"] == subset["shapelets"]);
  CHECK(report["contacts"] == subset["contacts"]);
  CHECK(report["final_pose"] == subset["final_pose"]);
}
