// Hardware-in-loop tests of the unmodified `crunchhost --robot` binary (issue 5, ARCHITECTURE.md
// §5). With CRUNCH_HIL_USB and CRUNCH_HIL_CREATE set they run it against the real bridge and
// Create; otherwise against crunch-virtual-robot: the ODE robot of test/scenes/hil_one_table.json
// behind a umockdev USB bridge and a pty Create emulator, with faults injected on request.
#include <sys/wait.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/mapping/evaluation.h"
#include "crunch/mapping/map_io.h"
#include "crunch/scene/scene.h"
#include "support/run_command.h"
#include "support/temp_dir.h"

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

// A hil scene and where the robot starts in it: the scene's one listed pose, clear of everything.
struct HilScene {
  std::string path;
  std::string robot_frame;  // crunchhost's --start-* and --area-* for that pose and arena
};
const HilScene kOneTable{std::string(CRUNCH_SOURCE_DIR) + "/test/scenes/hil_one_table.json",
                         "--start-x 0.3 --start-y 0.775 --start-theta 0 --area-width 2 "
                         "--area-depth 2"};
const HilScene kTwoTables{std::string(CRUNCH_SOURCE_DIR) + "/test/scenes/hil_two_tables.json",
                          "--start-x 0.35 --start-y 0.35 --start-theta 0.785 --area-width 2.5 "
                          "--area-depth 2.5"};

struct Run : CommandRun {
  json summary;  // crunch-virtual-robot's last line, if any
};

Run run(const std::string& command) {
  Run r;
  static_cast<CommandRun&>(r) = runCommand(command);
  if (auto line = lastLineStartingWith(r.output, "{\"child_exit\""); !line.empty())
    r.summary = json::parse(line);
  return r;
}

// `crunchhost --robot ARGS` inside the virtual robot, with the harness's own fault flags.
Run virtualRobot(const std::string& harness_flags, const std::string& robot_args,
                 const HilScene& scene = kOneTable, int time_limit_s = 120) {
  std::cout << "hil: virtual devices (umockdev USB bridge, pty Create emulator)" << std::endl;
  return run(std::string(CRUNCH_VIRTUAL_ROBOT) + " --scene " + scene.path + " --time-limit " +
             std::to_string(time_limit_s) + " " + harness_flags + " -- " + CRUNCHHOST +
             " --robot --create {create} " + scene.robot_frame + " " + robot_args);
}

json readJson(const fs::path& path) {
  std::ifstream in(path);
  REQUIRE(in.good());
  return json::parse(in);
}

// A length that cuts `rec` inside a record, never on a boundary (there the file would be a
// shorter but whole recording): the middle of the first record that starts past half the file
// (docs/RECORDING.md: a 32-byte header, M bytes of metadata, records of 16 + N bytes).
std::uintmax_t cutInsideARecord(const fs::path& rec) {
  std::ifstream in(rec, std::ios::binary);
  const std::vector<unsigned char> b((std::istreambuf_iterator<char>(in)),
                                     std::istreambuf_iterator<char>());
  REQUIRE(b.size() > 32);
  const auto le = [&b](std::size_t at, int bytes) {
    std::size_t v = 0;
    for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | b[at + static_cast<std::size_t>(i)];
    return v;
  };
  std::size_t at = 32 + le(12, 4);
  while (at + 16 <= b.size()) {
    const std::size_t len = 16 + le(at + 2, 2);
    if (at >= b.size() / 2) return at + len / 2;
    at += len;
  }
  FAIL("no record starts past half of " << rec);
  return 0;
}

bool realHardware() {
  const bool usb = std::getenv("CRUNCH_HIL_USB") != nullptr;
  const bool create = std::getenv("CRUNCH_HIL_CREATE") != nullptr;
  if (usb != create) {
    FAIL("set both CRUNCH_HIL_USB (VID:PID) and CRUNCH_HIL_CREATE (serial port) for the real "
         "robot, or neither for the virtual one");
  }
  return usb && create;
}

// Distance from p to the nearest surface a whisker can touch: a leg's outline or a wall.
double distanceToSurface(const crunch::Scene& scene, const crunch::Vec2& p) {
  using crunch::Vec2;
  double d = std::min({std::abs(p.x()), std::abs(p.y()), std::abs(scene.width - p.x()),
                       std::abs(scene.depth - p.y())});
  for (const crunch::TableSpec& t : scene.tables) {
    for (const crunch::OrientedRect& leg : t.legs()) {
      d = std::min(d, crunch::closestOnPerimeter(leg, p).distance);
    }
  }
  for (const crunch::WallSpec& w : scene.walls) {
    d = std::min(d, crunch::distanceToSegment(p, w.a, w.b));
  }
  return d;
}

double angleDiff(double a, double b) { return std::abs(crunch::wrapPi(a - b)); }

// What issue 12 asks of the robot's map: every table of the scene, within 5 cm and 5 degrees.
const crunch::MatchTolerance kTableTolerance{0.05, 5.0 * crunch::kPi / 180.0};

// How long the robot explores each scene (`--explore infogain --model rooms`: it chooses where
// to whisk, and its map holds walls and tables of any size) before its map must hold every
// table. The roaming body whisk (forward, whisk on contact, random turn) needed ~270 s for the
// one table and in 450 s never reached the second (docs/ROBOT.md, "Maps in the virtual
// robot"). Minutes of wall clock each on an otherwise idle machine, so hidden from ctest ([.]):
//   build/default/test/hil/robot_hil_test "[hil-map]"
// The one table: 330 s. The two tables: the travel the simulator's stand-in needed (`crunchhost
// --sim --sensor-model physics --model rooms --explore infogain --travel-budget 20` on
// hil_two_tables: recall and precision 1.0 on seeds 1-6, where 10 m gave 0.67 and 0.75;
// docs/EXPLORATION.md), about 20 minutes of the robot's time, capped at 25. Measured on
// 2026-11-28 (docs/ROBOT.md, "Maps in the virtual robot"): before the bumper's switches were
// read, 31 bumps and the small table never fused; after, 8 bumps and both tables within
// 1.2 cm and 1.1 degrees (1,160 s, 91 whisks).
constexpr int kOneTableSeconds = 330;
constexpr double kTwoTablesMetres = 20.0;
constexpr int kTwoTablesCapSeconds = 1500;

crunch::Map readMap(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  auto map = crunch::parseMapJson(ss.str(), path.string());
  REQUIRE(map);
  return map.value();
}

// Every table of `scene` is in `map` (one-to-one, within kTableTolerance); returns whether so.
bool checkEveryTableFound(const crunch::Map& map, const crunch::Scene& scene) {
  const crunch::Evaluation ev = crunch::evaluate(map, scene, kTableTolerance);
  std::cout << "hil: " << ev.true_tables << " true tables, " << ev.fused_tables
            << " fused; within 5 cm and 5 deg: " << ev.matched << " (recall " << ev.recall
            << ", precision " << ev.precision << ", mean error " << ev.mean_position_error
            << " m, " << ev.mean_angle_error * 180.0 / crunch::kPi << " deg)" << std::endl;
  for (const crunch::MapTable& t : map.tables) {
    std::cout << "hil: fused table (" << t.pose.x << ", " << t.pose.y << ", " << t.pose.theta << ") score "
              << t.score << std::endl;
  }
  CHECK(ev.matched == ev.true_tables);
  return ev.matched == ev.true_tables;
}

// --replay of the run's recording gives the same map and shapelets.
void checkReplaySameMap(const fs::path& live, const fs::path& again) {
  const Run rp = run(std::string(CRUNCHHOST) + " --replay " + (live / "recording.crec").string() +
                     " --out " + again.string());
  INFO(rp.output);
  REQUIRE(rp.exit_code == 0);
  const json a = readJson(live / "map.json"), b = readJson(again / "map.json");
  CHECK(a["tables"] == b["tables"]);
  CHECK(a["per_pose"] == b["per_pose"]);
  CHECK(a["stats"]["shapelets"] == b["stats"]["shapelets"]);
  CHECK(a["stats"]["proposals"] == b["stats"]["proposals"]);
  CHECK(readJson(again / "report.json")["shapelets"] == readJson(live / "report.json")["shapelets"]);
}

}  // namespace

TEST_CASE("Robot: the virtual robot maps by touch, --replay gives the same map, a truncated "
          "recording replays up to the damage",
          "[hil]") {
  if (realHardware()) {
    TempDir dir;
    const Run r = run(std::string(CRUNCHHOST) + " --robot --usb " + std::getenv("CRUNCH_HIL_USB") +
                      " --create " + std::getenv("CRUNCH_HIL_CREATE") + " --duration 20 --out " +
                      dir.path().string());
    std::cout << "hil: real devices\n" << r.output;
    REQUIRE(r.exit_code == 0);
    const json rep = readJson(dir.path() / "report.json");
    CHECK(rep["bridge"]["frames"].get<long>() > 20 * 2000);
    CHECK(rep["create"]["packets"].get<long>() > 20 * 50);
    return;
  }
  TempDir dir;
  const fs::path out = dir.path() / "live";
  const Run r = virtualRobot("", "--duration 40 --map-every 5 --out " + out.string());
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  REQUIRE(r.summary.is_object());
  const json rep = readJson(out / "report.json");

  // The whole stream arrived, clean: every tick the simulator made (4 frames each) but those
  // still in flight when the run stopped, no frame lost or corrupt. (Counted against the
  // harness's own ticks, so a slow machine that falls behind real time does not matter.)
  const long ticks = r.summary["ticks"].get<long>();
  CHECK(ticks > 2000L * 30);
  CHECK(rep["bridge"]["frames"].get<long>() >= 4 * (ticks - 2000));
  CHECK(rep["bridge"]["frames"].get<long>() <= 4 * ticks);
  CHECK(rep["bridge"]["crc_failures"] == 0);
  CHECK(rep["bridge"]["lost_frames"] == 0);
  CHECK(rep["ring"]["dropped"] == 0);
  CHECK(rep["create"]["checksum_failures"] == 0);
  // One OI packet per 15 ms of the simulator's clock, all parsed but the last few in flight.
  CHECK(rep["create"]["packets"].get<long>() >=
        r.summary["create"]["packets"].get<long>() - 70);
  // Odometry (OI packets 19/20) against the simulator's true pose at the end.
  const auto odo = rep["final_pose"].get<std::vector<double>>();
  const auto truth = r.summary["truth_pose"].get<std::vector<double>>();
  CHECK(std::hypot(odo[0] - truth[0], odo[1] - truth[1]) < 0.02);
  CHECK(angleDiff(odo[2], truth[2]) < 2.0 * crunch::kPi / 180.0);

  // The map: whisks were made and their shapelets lie on real surfaces. The tolerance is the
  // physics path's measured report error on legs (docs/TRAINING.md, "Through to the map":
  // sigma_r 14 mm, biased; sigma_phi 34 deg) plus the robot's own odometry drift.
  CHECK(rep["contacts"]["whisks"].get<int>() >= 2);
  const auto shapelets = rep["shapelets"];
  REQUIRE(shapelets.size() >= 4);
  auto scene = crunch::loadScene(kOneTable.path);
  REQUIRE(scene);
  std::vector<double> dist;
  for (const json& s : shapelets) {
    dist.push_back(distanceToSurface(scene.value(), {s["x"].get<double>(), s["y"].get<double>()}));
  }
  std::sort(dist.begin(), dist.end());
  const double median = dist[dist.size() / 2];
  std::cout << "hil: " << shapelets.size() << " shapelets, median distance to a true surface "
            << median << " m, worst " << dist.back() << " m" << std::endl;
  CHECK(median < 0.05);
  CHECK(dist.back() < 0.20);

  CHECK(fs::file_size(out / "map.png") > 1000);
  const crunch::Evaluation ev = crunch::evaluate(readMap(out / "map.json"), scene.value());
  std::cout << "hil: fused tables " << ev.fused_tables << ", recall " << ev.recall
            << ", precision " << ev.precision << std::endl;

  // --replay: the same records through the same path give the same map.
  const fs::path rec = out / "recording.crec";
  checkReplaySameMap(out, dir.path() / "replay");

  // A recording cut short (a run killed while writing): replayed up to the cut, reported, exit 3.
  const fs::path cut = dir.path() / "cut.crec";
  fs::copy_file(rec, cut);
  fs::resize_file(cut, cutInsideARecord(rec));
  const fs::path partial = dir.path() / "partial";
  const Run rc = run(std::string(CRUNCHHOST) + " --replay " + cut.string() + " --out " + partial.string());
  INFO(rc.output);
  CHECK(rc.exit_code == 3);
  CHECK(rc.output.find("truncated") != std::string::npos);
  CHECK(rc.output.find(cut.string()) != std::string::npos);
  const json pr = readJson(partial / "report.json");
  CHECK(pr["damage"].get<std::string>().find("truncated") != std::string::npos);
  CHECK(pr["records"].get<long>() > 1000);
  CHECK(pr["bridge"]["frames"].get<long>() < rep["bridge"]["frames"].get<long>());
  CHECK(fs::exists(partial / "map.json"));
}

// `crunchhost --robot --explore infogain --model rooms` explores `scene` for `seconds` or until
// it has driven `metres` (0: no travel budget); its map holds every table within 5 cm and 5
// degrees, and --replay of its recording gives the same map.
void mapsEveryTable(const HilScene& hil, int seconds, double metres = 0.0) {
  if (realHardware()) {  // the real room is not this scene
    WARN("hil: real devices: the scene needs the virtual robot; not run");
    return;
  }
  TempDir dir;
  const fs::path out = dir.path() / "live";
  const std::string travel =
      metres > 0.0 ? " --travel-budget " + std::to_string(metres) : std::string();
  const Run r = virtualRobot("",
                             "--explore infogain --model rooms --duration " +
                                 std::to_string(seconds) + travel + " --map-every 5 --out " +
                                 out.string(),
                             hil, 3 * seconds);
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  auto scene = crunch::loadScene(hil.path);
  REQUIRE(scene);
  REQUIRE(!scene.value().tables.empty());
  if (!checkEveryTableFound(readMap(out / "map.json"), scene.value())) {
    // Minutes of robot time: keep what the run made (recording, map, report) for a look.
    const fs::path keep = fs::temp_directory_path() /
                          ("crunch_hil_map_" + fs::path(hil.path).stem().string());
    fs::remove_all(keep);
    fs::copy(out, keep, fs::copy_options::recursive);
    std::cout << "hil: the run's outputs are kept in " << keep.string() << std::endl;
  }
  checkReplaySameMap(out, dir.path() / "replay");
}

TEST_CASE("Robot: the virtual robot maps the table of hil_one_table within 5 cm and 5 deg, "
          "--replay gives the same map",
          "[.][hil-map]") {
  mapsEveryTable(kOneTable, kOneTableSeconds);
}

TEST_CASE("Robot: the virtual robot maps both tables of hil_two_tables within 5 cm and 5 deg, "
          "--replay gives the same map",
          "[.][hil-map]") {
  mapsEveryTable(kTwoTables, kTwoTablesCapSeconds, kTwoTablesMetres);
}

// `crunchhost --robot --explore POLICY` (issue 14): the robot drives to the whisk poses the
// policy chose and whisks there. Read from the --json progress: each "goal" event carries the
// pose the policy chose, each "whisk" event the pose where a whisk began (the session's
// odometry). The whisks that followed a goal began at it: within the loop's tolerances (a
// waypoint within 5 cm, the heading within 0.03 rad) plus the odometry's resolution; at least
// one of them away from the start (the robot drove there). The report has the exploration block
// without a curve (no ground truth on a robot), and the recording replays to the same map.
void exploresToChosenPoses(const std::string& policy, int seconds) {
  if (realHardware()) {
    WARN("hil: real devices: exploring the real room is run by hand (docs/EXPLORATION.md)");
    return;
  }
  TempDir dir;
  const fs::path out = dir.path() / "live";
  const Run r = virtualRobot("", "--explore " + policy + " --duration " + std::to_string(seconds) +
                                     " --json --out " + out.string(),
                             kTwoTables, 3 * seconds);
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  crunch::Pose2 goal{};
  bool goal_open = false;  // a goal whose whisk has not come yet
  int goals = 0, at_goal = 0, away = 0;
  const crunch::Vec2 start{0.35, 0.35};
  std::istringstream lines(r.output);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("{\"event\"", 0) != 0) continue;
    const json e = json::parse(line);
    if (!e.contains("pose")) continue;
    const auto p = e["pose"].get<std::vector<double>>();
    const crunch::Pose2 pose{p[0], p[1], p[2]};
    if (e["event"] == "goal") {
      ++goals;
      goal = pose;
      goal_open = true;
    } else if (e["event"] == "whisk" && goal_open) {
      const double d = std::hypot(pose.x - goal.x, pose.y - goal.y);
      if (d < 0.06 && angleDiff(pose.theta, goal.theta) < 0.05) {
        ++at_goal;
        if (std::hypot(pose.x - start.x(), pose.y - start.y()) > 0.05) ++away;
      }
      goal_open = false;  // a whisk without a new goal in between was a touch on the way
    }
  }
  std::cout << "hil: " << policy << ": " << goals << " goals, " << at_goal
            << " whisks at the chosen pose, " << away << " of them away from the start"
            << std::endl;
  CHECK(goals >= 2);
  CHECK(at_goal >= 2);
  CHECK(away >= 1);
  const json rep = readJson(out / "report.json");
  REQUIRE(rep.contains("exploration"));
  CHECK(rep["exploration"]["policy"] == policy);
  CHECK(rep["exploration"]["whisks"].get<int>() >= at_goal);
  CHECK(rep["exploration"]["curve"].empty());
  CHECK(rep["exploration"]["stop_reason"] == "--duration reached");
  CHECK(rep["exploration"]["decision_ms"].get<double>() > 0.0);
  CHECK(rep["exploration"]["sim_time_s"].get<double>() > 0.5 * seconds);
  checkReplaySameMap(out, dir.path() / "replay");
}

TEST_CASE("Robot: --explore infogain drives the virtual robot to the whisk poses it chose",
          "[hil]") {
  exploresToChosenPoses("infogain", 90);
}

TEST_CASE("Robot: the bridge unplugged mid-run stops the robot, keeps the map and resumes",
          "[hil]") {
  if (realHardware()) {  // unplugging is done by hand on the real robot (docs/ROBOT.md)
    WARN("hil: real devices: this fault case needs the virtual ones and was not run");
    return;
  }
  TempDir dir;
  const Run r = virtualRobot("--unplug-at 8 --replug-at 13",
                             "--duration 25 --json --out " + dir.path().string());
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  CHECK(r.output.find("\"bridge_lost\"") != std::string::npos);
  CHECK(r.output.find("\"bridge_back\"") != std::string::npos);
  const json rep = readJson(dir.path() / "report.json");
  CHECK(rep["usb"]["disconnects"].get<int>() >= 1);
  CHECK(rep["usb"]["reconnects"].get<int>() >= 1);
  // About 5 s of the ~26 were missing; what came before and after arrived clean.
  const long frames = rep["bridge"]["frames"].get<long>();
  const long ticks = r.summary["ticks"].get<long>();
  CHECK(frames > 4 * (ticks - 2000 * 8));
  CHECK(frames < 4 * (ticks - 2000 * 4));
  CHECK(rep["bridge"]["crc_failures"] == 0);
  CHECK(fs::exists(dir.path() / "map.json"));
  // The roaming went on after the bridge came back: "roaming" announced twice.
  std::size_t roams = 0;
  for (std::size_t at = 0; (at = r.output.find("\"roaming\"", at)) != std::string::npos; ++at) ++roams;
  CHECK(roams >= 2);
  // A "status" line at every running-map post (--map-every 5: about five in 25 s), what
  // tools/soak.sh charts; the writes before the last line have been timed.
  std::vector<json> status;
  std::istringstream lines(r.output);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("{\"event\":\"status\"", 0) == 0) status.push_back(json::parse(line));
  }
  REQUIRE(status.size() >= 3);
  const json& last = status.back();
  CHECK(last["rss_kib"].get<long>() > 1000);
  CHECK(last["ring_high_water"].get<long>() > 0);
  CHECK(last["ring_dropped"] == 0);
  CHECK(last["map_writes"].get<int>() >= 2);
  CHECK(last["map_write_failures"] == 0);
  CHECK(last["map_write_max_s"].get<double>() > 0.0);
  CHECK(last["t"].get<double>() > status.front()["t"].get<double>());
}

TEST_CASE("Robot: corrupt frames and serial garbage are counted and never reach the pipeline",
          "[hil]") {
  if (realHardware()) {  // faults are injected by the virtual devices only
    WARN("hil: real devices: this fault case needs the virtual ones and was not run");
    return;
  }
  TempDir dir;
  const Run r = virtualRobot("--corrupt-every 97 --serial-garbage-every 0.5",
                             "--duration 20 --out " + dir.path().string());
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  const json rep = readJson(dir.path() / "report.json");
  const long corrupted = r.summary["corrupted_ticks"].get<long>();
  REQUIRE(corrupted > 100);
  // Every corrupted frame failed its CRC and was dropped (a false sync inside a rejected frame
  // can add a failure of its own); the board's sequence gap shows each loss once the board's
  // next frame arrives — all but, at most, one per board at the very end of the run.
  // The last corrupted tick's frames can still be in flight when the run stops (flaky at
  // exactly `corrupted`: 423 of 424 seen), as the lost frames below allow at the end.
  CHECK(rep["bridge"]["crc_failures"].get<long>() >= corrupted - 1);
  CHECK(rep["bridge"]["crc_failures"].get<long>() <= corrupted + corrupted / 10);
  const long lost = rep["bridge"]["lost_frames"].get<long>();
  CHECK(lost <= corrupted);
  CHECK(lost >= corrupted - 4);
  CHECK(rep["samples"]["gap_placeholders"].get<long>() == lost);
  // The garbage on the serial line was skipped; odometry stayed right.
  CHECK(rep["create"]["skipped_bytes"].get<long>() > 0);
  const auto odo = rep["final_pose"].get<std::vector<double>>();
  const auto truth = r.summary["truth_pose"].get<std::vector<double>>();
  CHECK(std::hypot(odo[0] - truth[0], odo[1] - truth[1]) < 0.02);
  CHECK(angleDiff(odo[2], truth[2]) < 2.0 * crunch::kPi / 180.0);
  for (const json& s : rep["shapelets"]) {
    CHECK(std::isfinite(s["x"].get<double>()));
    CHECK(std::isfinite(s["phi"].get<double>()));
  }
}

TEST_CASE("Robot: SIGINT stops the robot, flushes the recording and writes the map", "[hil]") {
  if (realHardware()) {  // Ctrl-C on the real robot is the same code path
    WARN("hil: real devices: this fault case needs the virtual ones and was not run");
    return;
  }
  TempDir dir;
  const fs::path out = dir.path() / "live";
  const Run r = virtualRobot("--interrupt-at 12", "--duration 0 --out " + out.string());
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  CHECK(r.output.find("stopped by SIGINT") != std::string::npos);
  CHECK(r.wall_s < 30.0);
  const json rep = readJson(out / "report.json");
  CHECK(rep["stop"] == "stopped by SIGINT");
  CHECK(rep["usb"]["bytes"].get<long>() > 0);
  // The robot was stopped: the Create's last wheel command was zero. The whole recording is
  // there: it replays cleanly to the same map.
  CHECK(r.summary["create"]["last_wheels_mm_s"] == json::array({0, 0}));
  CHECK(fs::exists(out / "map.json"));
  CHECK(fs::exists(out / "map.png"));
  const fs::path again = dir.path() / "replay";
  const Run rp = run(std::string(CRUNCHHOST) + " --replay " + (out / "recording.crec").string() +
                     " --out " + again.string());
  INFO(rp.output);
  CHECK(rp.exit_code == 0);
  CHECK(readJson(out / "map.json")["per_pose"] == readJson(again / "map.json")["per_pose"]);
  CHECK(readJson(again / "report.json")["bridge"]["frames"] == rep["bridge"]["frames"]);
}

TEST_CASE("Robot: a Create that never answers is a clear error in bounded time", "[hil]") {
  if (realHardware()) {
    WARN("hil: real devices: the silent Create needs the emulator and was not run");
    return;
  }
  TempDir dir;
  const Run r = virtualRobot("--create-silent", "--duration 20 --out " + dir.path().string());
  INFO(r.output);
  CHECK(r.exit_code == 3);
  CHECK(r.output.find("did not answer") != std::string::npos);
  CHECK(r.wall_s < 10.0);
  CHECK(!fs::exists(dir.path() / "map.json"));  // nothing moved, nothing written
}

TEST_CASE("Robot: with nothing attached, --robot names both missing devices and the fix",
          "[hil]") {
  TempDir dir;
  const Run r = run(std::string(CRUNCHHOST) + " --robot --usb 1209:0001 --create " +
                    (dir.path() / "ttyNONE").string() + " --out " + (dir.path() / "out").string());
  INFO(r.output);
  CHECK(r.exit_code == 3);
  CHECK(r.output.find("no whisker bridge with USB id 1209:0001") != std::string::npos);
  CHECK(r.output.find("ttyNONE") != std::string::npos);
  CHECK(r.output.find("tools/udev/99-crunchbot.rules") != std::string::npos);
  CHECK(!fs::exists(dir.path() / "out"));
}
