// `crunchhost --robot` / `--replay` (host/app/robot_mode.h): a bad setting on either road in —
// the command line, a recording's metadata — is exit 2 with a message naming it, and nothing is
// opened or written (ARCHITECTURE.md §3 "One road in", §4 exit codes). No device is needed: the
// settings are checked before any is opened.
#include "robot_mode.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "crunch/io/recording.h"
#include "crunch/session/session_settings.h"
#include "crunch/signal/models_io.h"
#include "support/temp_dir.h"

namespace {

using namespace crunch;
using json = nlohmann::json;

// A recording whose metadata has settings.mapping.working_memory = `working_memory`, and one
// bridge chunk.
std::string recordingWithWorkingMemory(const TempDir& dir, const json& working_memory) {
  auto models = signal::loadModels(std::string(CRUNCH_SOURCE_DIR) + "/models/sim_models.json");
  REQUIRE(models);
  session::RobotSessionOptions s = session::sessionOptions(models.value(), MappingOptions{}, 1);
  json meta = json::parse(session::recordingMetadata(s, {"1209:0001", "/dev/ttyUSB0", "test"}));
  meta["settings"]["mapping"]["working_memory"] = working_memory;
  const std::string path = dir.file("bad.crec");
  auto w = io::RecordingWriter::create(path, meta.dump());
  REQUIRE(w);
  const std::uint8_t bytes[4] = {0xA5, 0x5A, 0, 0};
  REQUIRE(w.value()->write(io::StreamId::kBridge, 1, bytes));
  REQUIRE(w.value()->close());
  return path;
}

}  // namespace

TEST_CASE("Robot mode: --replay: working_memory 0 in the recording's metadata is exit 2 naming it",
          "[app]") {
  TempDir dir;
  app::ReplayOptions o;
  o.recording = recordingWithWorkingMemory(dir, 0);
  o.out_dir = dir.file("out");
  std::ostringstream out, err;
  CHECK(app::runReplay(o, out, err) == 2);
  CHECK(err.str().find("working_memory") != std::string::npos);
  CHECK(err.str().find(o.recording) != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(dir.file("out/map.json")));
  CHECK_FALSE(std::filesystem::exists(dir.file("out")));
}

TEST_CASE("Robot mode: --replay --threads out of range is exit 2 naming it, nothing written",
          "[app]") {
  TempDir dir;
  app::ReplayOptions o;
  o.recording = recordingWithWorkingMemory(dir, 7);  // good metadata: the flag is what fails
  o.out_dir = dir.file("out");
  o.threads = 257;
  std::ostringstream out, err;
  CHECK(app::runReplay(o, out, err) == 2);
  CHECK(err.str().find("threads") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(dir.file("out")));
}

TEST_CASE("Robot mode: --replay: a working_memory that is not a number is exit 2 naming it",
          "[app]") {
  TempDir dir;
  app::ReplayOptions o;
  o.recording = recordingWithWorkingMemory(dir, "seven");
  o.out_dir = dir.file("out");
  std::ostringstream out, err;
  CHECK(app::runReplay(o, out, err) == 2);
  CHECK(err.str().find("settings.mapping.working_memory") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(dir.file("out")));
}

TEST_CASE(
    "Robot mode: --robot: a bad setting on the command line is exit 2 naming it, nothing opened",
    "[app]") {
  TempDir dir;
  app::RobotOptions o;
  o.out_dir = dir.file("out");
  o.create = dir.file("no-such-port");  // never reached: the settings fail first
  std::string field;
  SECTION("working memory 0") {
    o.mapping.working_memory = 0;
    field = "working_memory";
  }
  SECTION("an area of 1e308 m") {
    o.start_x = 1.0;
    o.start_y = 1.0;
    o.area_width = 1e308;
    field = "area width";
  }
  SECTION("a NaN start heading") {
    o.start_theta = std::nan("");
    field = "start.theta";
  }
  SECTION("a negative thread count") {
    o.mapping.threads = -1;
    field = "threads";
  }
  SECTION("map every 0 s") {
    o.map_every_s = 0.0;
    field = "map_every_s";
  }
  SECTION("--explore with a negative travel budget") {
    exploration::ExploreOptions e;
    e.policy = exploration::ExplorePolicyKind::kFrontier;
    e.travel_budget_m = -1.0;
    o.explore = e;
    field = "--travel-budget";
  }
  SECTION("--explore with a negative whisk budget") {
    exploration::ExploreOptions e;
    e.whisk_budget = -3;
    o.explore = e;
    field = "--whisk-budget";
  }
  std::ostringstream out, err;
  CHECK(app::runRobot(o, out, err) == 2);
  CHECK(err.str().find(field) != std::string::npos);
  CHECK(err.str().find("Create") == std::string::npos);  // no device was tried
  CHECK_FALSE(std::filesystem::exists(dir.file("out")));
}

TEST_CASE("Robot mode: --replay: settings out of range in the metadata are exit 2 naming them, "
          "nothing written (issue 16)", "[app]") {
  struct Row {
    const char* pointer;  // a JSON pointer into the metadata
    json value;
    const char* named;
  };
  const Row row = GENERATE(Row{"/settings/mapping/working_memory", -5, "working_memory"},
                           Row{"/settings/mapping/schedule_steps", 100000000, "schedule_steps"},
                           Row{"/settings/mapping/global_chains", 0, "global_chains"},
                           Row{"/settings/area", json::array({0.0, 0.0, 1e308, 1e308}), "area"},
                           Row{"/settings/seed", -1, "seed"},
                           Row{"/models/radial/whiskers/1/sigma", 0.0, "sigma"});
  TempDir dir;
  auto models = signal::loadModels(std::string(CRUNCH_SOURCE_DIR) + "/models/sim_models.json");
  REQUIRE(models);
  session::RobotSessionOptions s = session::sessionOptions(models.value(), MappingOptions{}, 1);
  json meta = json::parse(session::recordingMetadata(s, {"1209:0001", "/dev/ttyUSB0", "test"}));
  meta[json::json_pointer(row.pointer)] = row.value;
  app::ReplayOptions o;
  o.recording = dir.file("bad.crec");
  {
    auto w = io::RecordingWriter::create(o.recording, meta.dump());
    REQUIRE(w);
    REQUIRE(w.value()->close());
  }
  o.out_dir = dir.file("out");
  std::ostringstream out, err;
  const int code = app::runReplay(o, out, err);
  INFO(row.pointer << ": " << err.str());
  CHECK(code == 2);
  CHECK(err.str().find(row.named) != std::string::npos);
  CHECK(err.str().find(o.recording) != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(dir.file("out")));
}
