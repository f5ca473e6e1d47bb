// `crunchhost export` end to end (session/export.h, docs/EXPORT.md): the binary's ROS map of a
// --sim run read back against that run's map and scene, the CSV files of a real recording (the
// golden one, test/golden/README.md) against its replay's report, and bad input: exit 2, the flag
// or file named, nothing written; a damaged recording exports what it holds and exits 3.
#include <yaml-cpp/yaml.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "crunch/scene/scene.h"
#include "support/run_command.h"
#include "support/temp_dir.h"

namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;

const std::string kSource = CRUNCH_SOURCE_DIR;
const std::string kHost = CRUNCHHOST;

// `command` in the project's root: its exit status, its output in `out` (support/run_command.h).
int run(const std::string& command, std::string* out = nullptr) {
  return exitStatusIn(kSource, command, out);
}

std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  INFO(path);
  REQUIRE(in.good());
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

json readJson(const std::string& path) { return json::parse(readText(path)); }

std::vector<std::string> splitLines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> out(1);
  for (char c : line) {
    if (c == ',') {
      out.emplace_back();
    } else {
      out.back() += c;
    }
  }
  return out;
}

}  // namespace

TEST_CASE("Export: the ROS map of a --sim run has the run's legs occupied and its swept floor free",
          "[export]") {
  TempDir dir;
  const std::string out = dir.file("run");
  REQUIRE(run(kHost + " --sim --model walls --seed 1 --out " + out) == 0);
  const json map = readJson(out + "/map.json");
  REQUIRE(map.contains("free_space"));
  REQUIRE(map["tables"].size() >= 3);
  std::string said;
  REQUIRE(run(kHost + " export --format ros-map --in " + out + "/map.json --out " +
                  dir.file("ros"),
              &said) == 0);
  CHECK(said.find("free") != std::string::npos);

  const YAML::Node yaml = YAML::LoadFile(dir.file("ros/map.yaml"));
  const double res = yaml["resolution"].as<double>();
  CHECK(res == 0.02);
  const double ox = yaml["origin"][0].as<double>(), oy = yaml["origin"][1].as<double>();
  const std::string pgm = readText(dir.file("ros/" + yaml["image"].as<std::string>()));
  // This writer's header: P5, one comment line, "W H", "255".
  std::istringstream head(pgm);
  std::string magic, comment;
  int w = 0, h = 0, maxval = 0;
  head >> magic;
  head.get();
  std::getline(head, comment);
  head >> w >> h >> maxval;
  head.get();
  REQUIRE(magic == "P5");
  REQUIRE(comment.rfind("#", 0) == 0);
  REQUIRE(maxval == 255);
  const std::size_t raster = static_cast<std::size_t>(head.tellg());
  REQUIRE(pgm.size() == raster + static_cast<std::size_t>(w) * h);
  const auto pixel = [&](double x, double y) {
    const int col = static_cast<int>(std::floor((x - ox) / res));
    const int iy = static_cast<int>(std::floor((y - oy) / res));
    REQUIRE(col >= 0);
    REQUIRE(col < w);
    REQUIRE(iy >= 0);
    REQUIRE(iy < h);
    return static_cast<unsigned char>(pgm[raster + static_cast<std::size_t>((h - 1 - iy) * w + col)]);
  };

  // Every leg of every mapped table is occupied (0) at its centre.
  int legs = 0;
  for (const json& t : map["tables"]) {
    crunch::TableSpec spec;
    spec.pose = {t["x"].get<double>(), t["y"].get<double>(), t["theta"].get<double>()};
    spec.width = t["width"].get<double>();
    spec.depth = t["depth"].get<double>();
    spec.leg = t["leg"].get<double>();
    for (const auto& leg : spec.legs()) {
      CHECK(pixel(leg.pose.x, leg.pose.y) == 0);
      ++legs;
    }
  }
  CHECK(legs == 4 * static_cast<int>(map["tables"].size()));
  // Every swept free-space cell's centre is free (254) in the export unless it lies within a
  // cell of a mapped leg or wall (occupied wins).
  const json& f = map["free_space"];
  const double cell = f["cell"].get<double>();
  long long swept = 0, free_cells = 0;
  for (std::size_t iy = 0; iy < f["rows"].size(); ++iy) {
    std::istringstream runs(f["rows"][iy].get<std::string>());
    for (std::string run_text; runs >> run_text;) {
      const auto plus = run_text.find('+');
      const int start = std::stoi(run_text.substr(0, plus));
      const int length = std::stoi(run_text.substr(plus + 1));
      for (int ix = start; ix < start + length; ++ix) {
        ++swept;
        const double x = f["origin"][0].get<double>() + (ix + 0.5) * cell;
        const double y = f["origin"][1].get<double>() + (iy + 0.5) * cell;
        const unsigned char v = pixel(x, y);
        if (v == 254) ++free_cells;
        else CHECK(v == 0);
      }
    }
  }
  CHECK(swept > 10000);
  CHECK(free_cells > 0.95 * static_cast<double>(swept));
}

TEST_CASE("Export: the CSV files of a recording hold its frames, its contacts and its odometry",
          "[export]") {
  TempDir dir;
  REQUIRE(run("tar -xJf test/golden/replay/recording.tar.xz -C " + dir.path().string()) == 0);
  std::string said;
  REQUIRE(run(kHost + " export --format csv --in " + dir.file("recording.crec") + " --out " +
                  dir.file("csv"),
              &said) == 0);
  INFO(said);
  const auto samples = splitLines(readText(dir.file("csv/samples.csv")));
  const auto contacts = splitLines(readText(dir.file("csv/contacts.csv")));
  const auto odometry = splitLines(readText(dir.file("csv/odometry.csv")));
  REQUIRE(samples[0] == "t_s,t_ns,board,seq,tick,alpha,beta,status,frames_lost,samples_dropped");
  REQUIRE(contacts[0] ==
          "t_s,t_ns,whisk,whisker,r_m,phi_rad,oriented,face_span_m,robot_x_m,robot_y_m,"
          "robot_theta_rad,contact_x_m,contact_y_m");
  REQUIRE(odometry[0] == "t_s,t_ns,x_m,y_m,theta_rad,bumped,packets");
  // 45 s at 2 kHz from four boards: about 360 000 frames; each board's sequence numbers follow,
  // and their times (seconds from the recording's earliest record) never go back.
  CHECK(samples.size() > 300000);
  std::vector<long> last_seq(4, -1);
  double last_t = 0.0;
  for (std::size_t i = 1; i < samples.size(); ++i) {
    const auto c = splitCsv(samples[i]);
    REQUIRE(c.size() == 10);
    const int board = std::stoi(c[2]);
    REQUIRE(board >= 0);
    REQUIRE(board < 4);
    const long seq = std::stol(c[3]);
    if (last_seq[board] >= 0 && c[8] == "0") CHECK(seq == (last_seq[board] + 1) % 65536);
    last_seq[board] = seq;
    CHECK(std::stod(c[0]) >= last_t);
    last_t = std::stod(c[0]);
  }
  // The contacts' located points are the replay's shapelets, number for number.
  const json subset = readJson(kSource + "/test/golden/replay/report_subset.json");
  std::vector<std::vector<std::string>> located;
  for (std::size_t i = 1; i < contacts.size(); ++i) {
    const auto c = splitCsv(contacts[i]);
    REQUIRE(c.size() == 13);
    if (!c[11].empty()) located.push_back(c);
  }
  REQUIRE(located.size() == subset["shapelets"].size());
  for (std::size_t i = 0; i < located.size(); ++i) {
    const json& s = subset["shapelets"][i];
    CHECK(std::stoi(located[i][3]) == s["whisker"].get<int>());
    CHECK(std::stod(located[i][11]) == s["x"].get<double>());
    CHECK(std::stod(located[i][12]) == s["y"].get<double>());
    CHECK((located[i][6] == "1") == s["oriented"].get<bool>());
  }
  // The last odometry row is the replay's final pose.
  REQUIRE(odometry.size() > 100);
  const auto last = splitCsv(odometry.back());
  REQUIRE(last.size() == 7);
  const json& fp = subset["final_pose"];
  CHECK(std::stod(last[2]) == Approx(fp[0].get<double>()).margin(1e-9));
  CHECK(std::stod(last[3]) == Approx(fp[1].get<double>()).margin(1e-9));
}

TEST_CASE("Export: bad input is exit 2 naming the flag or file, with nothing written",
          "[export]") {
  TempDir dir;
  REQUIRE(run(kHost + " --sim --out " + dir.file("run")) == 0);
  const std::string map = dir.file("run/map.json");
  const std::string out = dir.file("out");
  const struct {
    std::string args;
    const char* named;
  } cases[] = {
      {"--format png --in " + map, "--format"},
      {"--format ros-map --resolution 0 --in " + map, "--resolution"},
      {"--format ros-map --resolution nan --in " + map, "--resolution"},
      {"--format ros-map --resolution 2 --in " + map, "--resolution"},
      {"--format ros-map --in " + dir.file("missing.json"), "missing.json"},
      {"--format ros-map --in " + dir.path().string(), dir.path().c_str()},
      {"--format csv --resolution 0.05 --in " + map, "--resolution"},
      {"--format csv --tops-occupied --in " + map, "--tops-occupied"},
      {"--format csv --in " + map, "map.json"},  // not a recording
  };
  for (const auto& c : cases) {
    std::string said;
    INFO(c.args);
    CHECK(run(kHost + " export " + c.args + " --out " + out, &said) == 2);
    INFO(said);
    CHECK(said.find(c.named) != std::string::npos);
    CHECK_FALSE(fs::exists(out));
  }
  // An --out that is a file, or a directory where an output goes: refused before writing.
  std::ofstream(dir.file("a_file")) << "x";
  fs::create_directories(dir.file("taken/map.yaml"));
  for (const std::string& bad_out : {dir.file("a_file"), dir.file("taken")}) {
    std::string said;
    INFO(bad_out);
    CHECK(run(kHost + " export --format ros-map --in " + map + " --out " + bad_out, &said) == 2);
    INFO(said);
    CHECK(said.find("--out") != std::string::npos);
    CHECK_FALSE(fs::exists(dir.file("taken/map.pgm")));
  }
}

TEST_CASE("Export: a damaged recording is exported up to the damage, said, exit 3", "[export]") {
  TempDir dir;
  REQUIRE(run("tar -xJf test/golden/replay/recording.tar.xz -C " + dir.path().string()) == 0);
  const std::string rec = dir.file("recording.crec");
  fs::resize_file(rec, fs::file_size(rec) / 2);  // a run killed while writing
  std::string said;
  CHECK(run(kHost + " export --format csv --in " + rec + " --out " + dir.file("csv"), &said) == 3);
  CHECK(said.find("truncated") != std::string::npos);
  const auto samples = splitLines(readText(dir.file("csv/samples.csv")));
  CHECK(samples.size() > 100000);
  CHECK(fs::exists(dir.file("csv/odometry.csv")));
  CHECK(fs::exists(dir.file("csv/contacts.csv")));
}
