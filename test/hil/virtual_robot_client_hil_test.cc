// Hardware-in-loop test of crunch-virtual-robot with a Create client that is not crunchhost
// (issue 18): test/hil/create_oi_client.py, written from the Create Open Interface manual on
// pyserial (python3-serial), run the way docs/CREATE.md tells a user to run their own client.
// It connects, enters Full mode, streams, drives a drive-turn-drive path with Drive (137) and
// prints its odometry; the harness prints the simulator's true pose. With CRUNCH_HIL_CREATE
// naming a serial port, the client runs against that real Create instead (no truth pose there:
// connection, mode and stream are checked, the odometry is only printed).
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "support/run_command.h"

namespace {

using nlohmann::json;

constexpr double kPi = 3.14159265358979323846;

struct Run : CommandRun {
  json client;   // the client's JSON line
  json summary;  // crunch-virtual-robot's summary line
};

Run run(const std::string& command) {
  Run r;
  static_cast<CommandRun&>(r) = runCommand(command);
  if (auto line = lastLineStartingWith(r.output, "{\"client\""); !line.empty())
    r.client = json::parse(line);
  if (auto line = lastLineStartingWith(r.output, "{\"child_exit\""); !line.empty())
    r.summary = json::parse(line);
  return r;
}

const std::string kClient = std::string(CRUNCH_SOURCE_DIR) + "/test/hil/create_oi_client.py";
const std::string kScene = std::string(CRUNCH_SOURCE_DIR) + "/test/scenes/empty_arena.json";

void requirePyserial() {
  const Run r = run(std::string(CRUNCH_PYTHON3) + " -c 'import serial'");
  if (r.exit_code != 0) {
    FAIL(CRUNCH_PYTHON3 << " cannot import serial: install python3-serial (tools/install-deps.sh)\n"
                        << r.output);
  }
}

int countOf(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

}  // namespace

TEST_CASE("Virtual robot: an independent OI client on pyserial connects, streams without "
          "corruption and its odometry is within 5 mm and 1.5 deg of the truth",
          "[hil]") {
  requirePyserial();
  // The path: 0.2 m ahead at 0.2 m/s, 90 deg counter-clockwise in place at 0.5 rad/s, 0.2 m
  // ahead; from (1, 1, 0) in the empty 4 m arena nothing is touched. The Create 1 reports whole
  // degrees and keeps the remainder, so after the turn the client's heading can be up to 1 deg
  // short of the truth for the whole second leg (driving straight adds no angle to tip it over):
  // 0.2 m x sin(1 deg) = 3.5 mm sideways at worst, plus < 1 mm of unreported distance, inside
  // the 5 mm bound. (With 0.3 m legs that alone reaches 5.2 mm: seen once in four runs.)
  const std::string client = std::string(CRUNCH_PYTHON3) + " " + kClient +
                             " --leg 0.2 --speed 0.2 --turn-deg 90 --turn-rate 0.5";
  if (const char* port = std::getenv("CRUNCH_HIL_CREATE"); port != nullptr) {
    std::cout << "hil: real Create on " << port << std::endl;
    const Run r = run(client + " --port " + port);
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    CHECK(r.client["connected"] == true);
    CHECK(r.client["mode"] == 3);
    CHECK(r.client["corrupt"] == 0);
    WARN("no truth pose on the real robot; the client's odometry: " << r.client["odometry"]);
    return;
  }
  std::cout << "hil: virtual Create (crunch-virtual-robot, pty), client " << kClient << std::endl;
  // The command of docs/CREATE.md, "Your own Create client" (the preload included), with a time
  // limit put before it: `--start 1 1 0 -- client --port` exactly as documented (CLI11 alone
  // once parsed the client's --port as the harness's there).
  const Run r = run(std::string(CRUNCH_VIRTUAL_ROBOT) + " --time-limit 60 --scene " + kScene +
                    " --start 1 1 0 -- " + client + " --port {create} --probe-unsupported");
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  REQUIRE(r.client.is_object());
  REQUIRE(r.summary.is_object());
  CHECK(r.client["connected"] == true);
  CHECK(r.client["mode"] == 3);  // Full, read back with Sensors(35)
  // The stream: every frame the client got was whole and summed to zero; no stray byte before,
  // between or after them (also none for the unsupported id 100 it asked for).
  const int packets = r.client["packets"].get<int>();
  CHECK(packets >= 200);  // ~5 s of driving and stopping at one frame per 15 ms
  CHECK(r.client["corrupt"] == 0);
  CHECK(r.client["skipped_bytes"] == 0);
  CHECK(r.summary["corrupted_ticks"] == 0);
  CHECK(r.summary["create"]["packets"].get<int>() >= packets);
  // Unsupported id: answered without it (the mode's byte only), counted, said once on stderr.
  CHECK(r.client["probe_answer"] == json::array({3}));
  CHECK(r.summary["create"]["unsupported_ids"] == 1);
  CHECK(r.summary["create"]["unsupported_id_list"] == json::array({100}));
  CHECK(countOf(r.output, "does not have") == 1);

  // Odometry against the simulator's truth, in the client's frame (it started at (1, 1, 0)).
  const auto& odo = r.client["odometry"];
  const auto& truth = r.summary["truth_pose"];
  const double tx = truth[0].get<double>() - 1.0, ty = truth[1].get<double>() - 1.0;
  const double tth = truth[2].get<double>();
  const double err_m = std::hypot(odo[0].get<double>() - tx, odo[1].get<double>() - ty);
  const double err_deg =
      std::abs(std::remainder(odo[2].get<double>() - tth, 2.0 * kPi)) * 180.0 / kPi;
  std::cout << "hil: client " << packets << " packets, " << r.client["corrupt"]
            << " corrupt; odometry (" << odo[0] << ", " << odo[1] << ", " << odo[2]
            << ") truth (" << tx << ", " << ty << ", " << tth << "): error " << err_m * 1000.0
            << " mm, " << err_deg << " deg; " << r.wall_s << " s" << std::endl;
  // The path was driven: both legs and the turn are in the truth.
  CHECK(std::hypot(tx, ty) > 0.25);
  CHECK(tth > 80.0 * kPi / 180.0);
  // Issue 18's bounds: 5 mm, and 1.5 deg (the Create 1 reports whole degrees).
  CHECK(err_m < 0.005);
  CHECK(err_deg < 1.5);
}

TEST_CASE("Virtual robot: --no-usb-preload starts the child without umockdev, the default with it",
          "[hil]") {
  const std::string probe = " -- sh -c 'echo \"preload=[$LD_PRELOAD] dir=[$UMOCKDEV_DIR]\"'";
  const std::string harness =
      std::string(CRUNCH_VIRTUAL_ROBOT) + " --scene " + kScene + " --start 1 1 0 --time-limit 10";
  const Run with = run("env -u LD_PRELOAD " + harness + probe);
  INFO(with.output);
  REQUIRE(with.exit_code == 0);
  CHECK(with.output.find("preload=[libumockdev-preload.so.0] dir=[/") != std::string::npos);
  const Run without = run("env -u LD_PRELOAD " + harness + " --no-usb-preload" + probe);
  INFO(without.output);
  REQUIRE(without.exit_code == 0);
  CHECK(without.output.find("preload=[] dir=[]") != std::string::npos);
}
