// session/map_output.h: the map files, the writer thread, the report's session part.
#include "crunch/session/map_output.h"

#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "crunch/core/atomic_file.h"
#include "crunch/session/session_settings.h"
#include "crunch/signal/models_io.h"
#include "support/temp_dir.h"

namespace {

using namespace crunch;

std::unique_ptr<session::RobotSession> makeSession() {
  auto models = signal::loadModels(std::string(CRUNCH_SOURCE_DIR) + "/models/sim_models.json");
  REQUIRE(models);
  session::RobotSessionOptions s = session::sessionOptions(models.value(), MappingOptions{}, 1);
  s.area_hi = {2.0, 2.0};
  s.start = {1.0, 1.0, 0.0};
  auto created = session::RobotSession::create(s);
  REQUIRE(created);
  return std::move(created).value();
}

}  // namespace

TEST_CASE("MapWriter: a posted map is written off the caller's thread", "[session]") {
  TempDir dir;
  auto session = makeSession();
  int errors = 0;
  {
    session::MapWriter writer({2.0, 2.0}, dir.file("out"), "test", [&](const Error&) { ++errors; });
    writer.post(session->snapshot());
    // The destructor waits for a write in progress; give the thread the chance to start it.
    for (int i = 0; i < 200 && !std::filesystem::exists(dir.file("out/map.png")); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  CHECK(errors == 0);
  CHECK(std::filesystem::exists(dir.file("out/map.json")));
  CHECK(std::filesystem::exists(dir.file("out/map.png")));
}

TEST_CASE("MapWriter: a failed write goes to on_error", "[session]") {
  TempDir dir;
  REQUIRE(writeFileAtomic(dir.file("blocker"), "a file where the directory should be"));
  auto session = makeSession();
  std::atomic<int> errors{0};
  {
    session::MapWriter writer({2.0, 2.0}, dir.file("blocker"), "test",
                              [&](const Error&) { ++errors; });
    writer.post(session->snapshot());
    for (int i = 0; i < 200 && errors == 0; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  CHECK(errors == 1);
}

TEST_CASE("sessionReportJson: the session's counters, pose and shapelets", "[session]") {
  auto session = makeSession();
  const Map map = session->snapshot();
  const auto report = nlohmann::json::parse(session::sessionReportJson(*session, map));
  for (const char* key :
       {"bridge", "samples", "create", "contacts", "final_pose", "map", "shapelets"}) {
    CHECK(report.contains(key));
  }
  CHECK(report["final_pose"] == nlohmann::json::array({1.0, 1.0, 0.0}));
  CHECK(report["contacts"]["whisks"] == 0);
}
