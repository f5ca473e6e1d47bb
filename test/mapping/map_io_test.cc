#include "crunch/mapping/map_io.h"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include "support/temp_dir.h"

namespace fs = std::filesystem;
using crunch::kPi;
using crunch::Map;
using crunch::MapTable;
using crunch::Vec2;

namespace {

std::string readFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

size_t entries(const fs::path& dir) {
  return static_cast<size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

MapTable makeMapTable(double x, double y, double theta) {
  MapTable t;
  t.pose = {x, y, theta};
  return t;
}

// A map using every field the file carries, with awkward (non-round) values.
Map sampleMap() {
  Map m;
  MapTable a = makeMapTable(1.2100000000000002, 0.88, 0.41);
  a.score = 0.93;
  a.support = 17;
  MapTable b = makeMapTable(3.0, 2.5, -0.3);  // written as pi - 0.3
  b.width = 0.6;
  b.depth = 0.45;
  b.leg = 0.04;
  b.score = 1.0 / 3.0;
  b.support = 2;
  m.tables = {a, b};
  m.walls.push_back({Vec2{0.0, 2.0}, Vec2{1.5, 2.0}, 0.9});
  crunch::PoseMap p0;
  p0.pose = {0.3, 0.3, 1.5 * kPi};
  p0.shapelets = 3;
  p0.tables = {makeMapTable(1.2, 0.9, 0.4 + kPi)};  // written as 0.4
  crunch::PoseMap p1;
  p1.pose = {0.6777777777777778, 0.3, 0.0};
  m.per_pose = {p0, p1};
  m.stats.poses = 400;
  m.stats.skipped_poses = 12;
  m.stats.shapelets = 1234;
  m.stats.rejected_reports = 5;
  m.stats.proposals = 12345678901LL;
  m.stats.wall_s = 2.75;
  m.stats.peak_live_tables = 41;
  m.stats.peak_live_legs = 163;
  m.shapelets.resize(3);  // for pictures only: not written
  return m;
}

}  // namespace

TEST_CASE("MapIo: a map survives the JSON round trip", "[mapping]") {
  const Map m = sampleMap();
  const auto r = crunch::parseMapJson(crunch::mapToJson(m), "map.json");
  INFO((r.ok() ? std::string() : r.error().message));
  REQUIRE(r.ok());
  const Map& back = r.value();

  REQUIRE(back.tables.size() == 2);
  for (size_t i = 0; i < 2; ++i) {
    INFO("table " << i);
    CHECK(back.tables[i].pose.x == m.tables[i].pose.x);
    CHECK(back.tables[i].pose.y == m.tables[i].pose.y);
    CHECK(back.tables[i].width == m.tables[i].width);
    CHECK(back.tables[i].depth == m.tables[i].depth);
    CHECK(back.tables[i].leg == m.tables[i].leg);
    CHECK(back.tables[i].score == m.tables[i].score);
    CHECK(back.tables[i].support == m.tables[i].support);
  }
  CHECK(back.tables[0].pose.theta == 0.41);
  CHECK(back.tables[1].pose.theta == Approx(kPi - 0.3));

  REQUIRE(back.walls.size() == 1);
  CHECK(back.walls[0].a == Vec2(0.0, 2.0));
  CHECK(back.walls[0].b == Vec2(1.5, 2.0));
  CHECK(back.walls[0].score == 0.9);

  REQUIRE(back.per_pose.size() == 2);
  CHECK(back.per_pose[0].pose.x == 0.3);
  CHECK(back.per_pose[0].pose.theta == 1.5 * kPi);  // robot headings are not folded
  CHECK(back.per_pose[0].shapelets == 3);
  REQUIRE(back.per_pose[0].tables.size() == 1);
  CHECK(back.per_pose[0].tables[0].pose.x == 1.2);
  CHECK(back.per_pose[0].tables[0].pose.theta == Approx(0.4));
  CHECK(back.per_pose[1].pose.x == m.per_pose[1].pose.x);
  CHECK(back.per_pose[1].tables.empty());

  CHECK(back.stats.poses == 400);
  CHECK(back.stats.skipped_poses == 12);
  CHECK(back.stats.shapelets == 1234);
  CHECK(back.stats.rejected_reports == 5);
  CHECK(back.stats.proposals == 12345678901LL);
  CHECK(back.stats.wall_s == 2.75);
  CHECK(back.stats.peak_live_tables == 41);
  CHECK(back.stats.peak_live_legs == 163);
  CHECK(back.shapelets.empty());
}

TEST_CASE("MapIo: table thetas are written in 0 <= theta < pi", "[mapping]") {
  Map m;
  for (double theta : {-1e-17, -kPi, kPi, 2.5 * kPi, -0.3, 0.0, 3.0}) {
    m.tables.push_back(makeMapTable(1.0, 1.0, theta));
  }
  const auto r = crunch::parseMapJson(crunch::mapToJson(m), "map.json");
  REQUIRE(r.ok());
  for (const MapTable& t : r.value().tables) {
    INFO("theta " << t.pose.theta);
    CHECK(t.pose.theta >= 0.0);
    CHECK(t.pose.theta < kPi);
  }
}

TEST_CASE("MapIo: the file names its schema, is indented by two and omits shapelets", "[mapping]") {
  const std::string text = crunch::mapToJson(sampleMap());
  CHECK(text.rfind("{\n  \"schema\": \"crunch.map/2\",\n", 0) == 0);
  for (const char* key : {"tables", "walls", "per_pose", "stats"}) {
    CHECK(text.find("\n  \"" + std::string(key) + "\": ") != std::string::npos);
  }
  CHECK(text.find("\n  \"shapelets\"") == std::string::npos);  // no top-level shapelet list
  CHECK(text.find("\"support\": 17") != std::string::npos);
}

TEST_CASE("MapIo: a crunch.map/1 file (scores from per-pose support) is still read", "[mapping]") {
  const auto r = crunch::parseMapJson(
      R"({"schema": "crunch.map/1", "tables": [{"x": 1, "y": 2, "theta": 0.5, "score": 0.25}]})",
      "map.json");
  INFO((r.ok() ? std::string() : r.error().message));
  REQUIRE(r.ok());
  REQUIRE(r.value().tables.size() == 1);
  CHECK(r.value().tables[0].score == 0.25);
}

TEST_CASE("MapIo: an empty map round-trips", "[mapping]") {
  const auto r = crunch::parseMapJson(crunch::mapToJson(Map{}), "map.json");
  REQUIRE(r.ok());
  CHECK(r.value().tables.empty());
  CHECK(r.value().per_pose.empty());
  CHECK(r.value().stats.poses == 0);
}

TEST_CASE("MapIo: extra keys are allowed, missing sections are empty", "[mapping]") {
  const auto r = crunch::parseMapJson(
      R"({"schema": "crunch.map/1", "generator": "hand", "tables": [{"x": 1, "y": 2, "theta": 0.5,
          "colour": "oak"}]})",
      "map.json");
  INFO((r.ok() ? std::string() : r.error().message));
  REQUIRE(r.ok());
  REQUIRE(r.value().tables.size() == 1);
  CHECK(r.value().tables[0].width == crunch::kStandardTableWidth);
  CHECK(r.value().walls.empty());
}

TEST_CASE("MapIo: peak_live_tables and peak_live_legs are written and optional", "[mapping]") {
  Map m;
  m.stats.peak_live_tables = 7;
  m.stats.peak_live_legs = 19;
  const std::string text = crunch::mapToJson(m);
  CHECK(text.find("\"peak_live_tables\": 7") != std::string::npos);
  CHECK(text.find("\"peak_live_legs\": 19") != std::string::npos);
  // A file from before issue 6 has neither: both read as 0.
  const auto old = crunch::parseMapJson(
      R"({"schema": "crunch.map/1", "stats": {"poses": 3, "wall_s": 0.5}})", "map.json");
  REQUIRE(old.ok());
  CHECK(old.value().stats.poses == 3);
  CHECK(old.value().stats.peak_live_tables == 0);
  CHECK(old.value().stats.peak_live_legs == 0);
  // A negative count is an error naming the field.
  const auto bad = crunch::parseMapJson(
      R"({"schema": "crunch.map/1", "stats": {"peak_live_legs": -2}})", "map.json");
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().message.find("peak_live_legs") != std::string::npos);
}

TEST_CASE("MapIo: a bad map file is an error naming the file and the field", "[mapping]") {
  auto message = [](const std::string& text) {
    const auto r = crunch::parseMapJson(text, "out/map.json");
    REQUIRE_FALSE(r.ok());
    return r.error().message;
  };
  CHECK(message(R"({"tables": []})") == "out/map.json: schema: missing (required)");
  CHECK(message(R"({"schema": "crunch.map/3"})").rfind("out/map.json: schema: expected", 0) == 0);
  CHECK(message(R"({"schema": "crunch.map/1", "tables": [{"x": 1, "y": "2", "theta": 0}]})") ==
        "out/map.json: tables[0].y: expected a number, got string");
  CHECK(message(R"({"schema": "crunch.map/1", "per_pose": [{"pose": [1, 2]}]})")
            .rfind("out/map.json: per_pose[0].pose: ", 0) == 0);
  CHECK(message(R"({"schema": "crunch.map/1", "stats": {"poses": -3}})")
            .rfind("out/map.json: stats.poses: ", 0) == 0);
  CHECK(message("{\"schema\": ").rfind("out/map.json: parse error", 0) == 0);
}

TEST_CASE("MapIo: writing into a missing directory fails, names the path and leaves nothing",
          "[mapping]") {
  TempDir tmp;
  const fs::path dir = tmp.path() / "no_such_dir";
  const std::string path = (dir / "map.json").string();
  const crunch::Status s = crunch::writeFileAtomic(path, "{}");
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().message.rfind(path + ": ", 0) == 0);
  CHECK(s.error().message.find("No such file or directory") != std::string::npos);
  CHECK_FALSE(fs::exists(dir));
  CHECK(entries(tmp.path()) == 0);
}

TEST_CASE("MapIo: a failed rename removes the temporary file and keeps the target", "[mapping]") {
  // The target is a non-empty directory: everything succeeds up to the rename, which fails.
  TempDir tmp;
  const fs::path target = tmp.path() / "map.json";
  fs::create_directories(target / "inside");
  const crunch::Status s = crunch::writeFileAtomic(target.string(), "{}");
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().message.rfind(target.string() + ": ", 0) == 0);
  CHECK(fs::is_directory(target / "inside"));
  CHECK(entries(tmp.path()) == 1);  // no map.json.tmp.<pid> left behind
}

TEST_CASE("MapIo: writing over an existing file replaces it whole", "[mapping]") {
  TempDir tmp;
  const fs::path path = tmp.path() / "map.json";
  REQUIRE(crunch::writeFileAtomic(path.string(), "first, and longer than the second\n").ok());
  CHECK(readFile(path) == "first, and longer than the second\n");
  REQUIRE(crunch::writeFileAtomic(path.string(), "second\n").ok());
  CHECK(readFile(path) == "second\n");
  CHECK(entries(tmp.path()) == 1);

  const std::string big(1 << 20, 'x');  // more than one write() may take
  REQUIRE(crunch::writeFileAtomic(path.string(), big).ok());
  CHECK(readFile(path) == big);
}

TEST_CASE("MapIo: a written map file reads back", "[mapping]") {
  TempDir tmp;
  const fs::path path = tmp.path() / "map.json";
  REQUIRE(crunch::writeFileAtomic(path.string(), crunch::mapToJson(sampleMap())).ok());
  const auto r = crunch::parseMapJson(readFile(path), path.string());
  REQUIRE(r.ok());
  CHECK(r.value().stats.shapelets == 1234);
}

TEST_CASE("MapIo: ensureDirectory creates parents and rejects a file in the way", "[mapping]") {
  TempDir tmp;
  const fs::path nested = tmp.path() / "a" / "b" / "c";
  REQUIRE(crunch::ensureDirectory(nested.string()).ok());
  CHECK(fs::is_directory(nested));
  CHECK(crunch::ensureDirectory(nested.string()).ok());  // already there

  const fs::path file = tmp.path() / "plain";
  std::ofstream(file) << "x";
  const crunch::Status s = crunch::ensureDirectory(file.string());
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().message.rfind(file.string() + ": ", 0) == 0);
  CHECK_FALSE(crunch::ensureDirectory("").ok());
}

TEST_CASE("MapIo: free_space is written as row runs and read back cell for cell", "[mapping]") {
  Map m;
  crunch::FreeSpaceLayer& f = m.free_space;
  f.origin = {-0.25, 0.5};
  f.cell = 0.01;
  f.nx = 7;
  f.ny = 3;
  // Row 0: cells 0-1 and 4; row 1: none; row 2: 6 (the last cell) only.
  f.swept = {1, 1, 0, 0, 1, 0, 0, /**/ 0, 0, 0, 0, 0, 0, 0, /**/ 0, 0, 0, 0, 0, 0, 1};
  const std::string text = crunch::mapToJson(m);
  CHECK(text.find("\"0+2 4+1\"") != std::string::npos);
  CHECK(text.find("\"6+1\"") != std::string::npos);
  const auto r = crunch::parseMapJson(text, "map.json");
  INFO((r.ok() ? std::string() : r.error().message));
  REQUIRE(r.ok());
  const crunch::FreeSpaceLayer& g = r.value().free_space;
  CHECK(g.origin == f.origin);
  CHECK(g.cell == f.cell);
  CHECK(g.nx == 7);
  CHECK(g.ny == 3);
  CHECK(g.swept == f.swept);
}

TEST_CASE("MapIo: a map without free_space reads as an empty layer and writes no key",
          "[mapping]") {
  const auto r = crunch::parseMapJson(R"({"schema": "crunch.map/1"})", "map.json");
  REQUIRE(r.ok());
  CHECK(r.value().free_space.empty());
  CHECK(crunch::mapToJson(Map{}).find("free_space") == std::string::npos);
}

TEST_CASE("MapIo: a bad free_space is an error naming the field", "[mapping]") {
  const std::string head = R"({"schema": "crunch.map/1", "free_space": )";
  const struct {
    const char* fs;
    const char* field;
  } cases[] = {
      {R"({"cell": 0, "origin": [0, 0], "size": [2, 1], "rows": [""]})", "free_space.cell"},
      {R"({"cell": 0.01, "origin": [0], "size": [2, 1], "rows": [""]})", "free_space.origin"},
      {R"({"cell": 0.01, "origin": [0, 0], "size": [2, 2], "rows": [""]})", "free_space.rows"},
      {R"({"cell": 0.01, "origin": [0, 0], "size": [4, 1], "rows": ["3+2"]})",
       "free_space.rows[0]"},
      {R"({"cell": 0.01, "origin": [0, 0], "size": [9, 1], "rows": ["3+2 4+1"]})",
       "free_space.rows[0]"},
      {R"({"cell": 0.01, "origin": [0, 0], "size": [9, 1], "rows": ["3+0"]})",
       "free_space.rows[0]"},
      {R"({"cell": 0.01, "origin": [0, 0], "size": [9, 1], "rows": ["1+1 "]})",
       "free_space.rows[0]"},
      {R"({"cell": 0.01, "origin": [0, 0], "size": [9, 1], "rows": ["x"]})", "free_space.rows[0]"},
      {R"({"cell": 0.01, "origin": [0, 0], "size": [9, 1], "rows": [3]})", "free_space.rows[0]"},
      {R"({"cell": 0.01, "origin": [0, 0], "size": [100000, 100000], "rows": []})",
       "free_space.size"},
      {R"({"cell": 0.01, "origin": [0, 0], "size": [2, 1], "rows": [""], "extra": 1})",
       "free_space.extra"},
  };
  for (const auto& c : cases) {
    const auto r = crunch::parseMapJson(head + c.fs + "}", "m.json");
    INFO(c.fs);
    REQUIRE_FALSE(r.ok());
    INFO(r.error().message);
    CHECK(r.error().message.rfind(std::string("m.json: ") + c.field, 0) == 0);
  }
}
