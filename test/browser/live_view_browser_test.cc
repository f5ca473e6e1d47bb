// The live view in a real browser (issue 17; docs/LIVE_VIEW.md): `crunchhost --robot --serve`
// runs inside crunch-virtual-robot (the simulated robot behind a umockdev USB bridge and a pty
// Create, as the hil tests run it) and Debian's headless Chromium loads the page during the run.
// Chromium is driven from its command line only (--dump-dom, --screenshot; no npm, no driver):
//   - while the run goes, once the robot has touched something: the page in polling mode
//     (?poll=MS: an open event stream would hold --dump-dom until the run ends) must draw the
//     robot (#robot visible, its pose in data-x/-y) and at least one contact (.contact), and
//     list the counters (#counters); a screenshot of it is saved as
//     build/.../test/browser/live_view.png (docs/img/live_view.png is a copy);
//   - the page in its normal mode (server-sent events), loaded at the start: its DOM is dumped
//     when the run's last event ends the stream, and shows the run ended with the robot drawn.
// Label `browser` (in the default test preset, so in .ci/run). Chromium missing is a failure,
// not a skip: tools/install-deps.sh installs it.
#include <httplib.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <future>
#include <iostream>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <thread>

#include "support/free_port.h"
#include "support/run_command.h"
#include "support/temp_dir.h"

namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// How long the robot runs: its first contacts reach the map after about 25 s in
// hil_one_table (the second body whisk; the first usually yields none).
constexpr int kRunSeconds = 40;
constexpr int kContactDeadlineSeconds = 36;

// Chromium, headless, with nothing of its own on the network and a fresh profile in `profile`.
std::string chromium(const fs::path& profile) {
  return std::string("timeout 60 ") + CRUNCH_CHROMIUM +
         " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run"
         " --disable-background-networking --disable-component-update --disable-sync"
         " --disable-dev-shm-usage --hide-scrollbars --user-data-dir=" +
         profile.string();
}

// Chromium's output without its own log lines (dbus and the like on stderr).
std::string domOf(const CommandRun& r) {
  const auto at = r.output.find("<html");
  return at == std::string::npos ? std::string() : r.output.substr(at);
}

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t at = 0; (at = text.find(what, at)) != std::string::npos; at += what.size()) ++n;
  return n;
}

// The value of attribute `attr` on the element with id `id` in `dom`, or "".
std::string attribute(const std::string& dom, const std::string& id, const std::string& attr) {
  std::smatch m;
  const std::regex tag("<[a-z]+ [^>]*id=\"" + id + "\"[^>]*>");
  if (!std::regex_search(dom, m, tag)) return "";
  const std::string t = m.str();
  std::smatch v;
  if (!std::regex_search(t, v, std::regex(" " + attr + "=\"([^\"]*)\""))) return "";
  return v[1].str();
}

}  // namespace

TEST_CASE("Browser: headless Chromium draws the virtual robot's run live: the robot, its "
          "contacts and counters",
          "[browser]") {
  if (::access(CRUNCH_CHROMIUM, X_OK) != 0) {
    FAIL("Chromium not found at " << CRUNCH_CHROMIUM
                                  << ": install it (bash tools/install-deps.sh installs Debian's "
                                     "chromium package), then re-run cmake");
  }
  const auto t0 = Clock::now();
  TempDir dir;
  const int port = freeLoopbackPort();
  const std::string url = "http://127.0.0.1:" + std::to_string(port) + "/";
  const std::string out = dir.file("out");
  const std::string scene = std::string(CRUNCH_SOURCE_DIR) + "/test/scenes/hil_one_table.json";
  auto robot = std::async(std::launch::async, [&] {
    return runCommand(std::string(CRUNCH_VIRTUAL_ROBOT) + " --scene " + scene +
                      " --time-limit 90 -- " + CRUNCHHOST +
                      " --robot --create {create} --start-x 0.3 --start-y 0.775 --start-theta 0"
                      " --area-width 2 --area-depth 2 --duration " +
                      std::to_string(kRunSeconds) + " --json --serve 127.0.0.1:" +
                      std::to_string(port) + " --out " + out);
  });

  // The server answers once crunchhost runs; until the run publishes its first snapshot
  // (seq >= 1) it answers the empty "starting" document (live_view.h).
  httplib::Client cli("127.0.0.1", port);
  cli.set_read_timeout(5, 0);
  json state;
  while (since(t0) < 20 && !(state.is_object() && state.value("seq", 0) >= 1)) {
    if (auto res = cli.Get("/state.json"); res && res->status == 200) state = json::parse(res->body);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  REQUIRE((state.is_object() && state.value("seq", 0) >= 1));
  CHECK(state["mode"] == "robot");
  std::cout << "browser: live view up after " << since(t0) << " s" << std::endl;

  // The page as a user opens it (server-sent events), from the start to the run's end.
  auto followed = std::async(std::launch::async, [&] {
    return runCommand(chromium(dir.path() / "profile-sse") +
                      " --virtual-time-budget=2000 --dump-dom " + url);
  });

  // Wait for the first contact in the map.
  while (since(t0) < kContactDeadlineSeconds && state["contacts"].empty()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
    if (auto res = cli.Get("/state.json"); res && res->status == 200) state = json::parse(res->body);
  }
  INFO("last state: " << state.dump().substr(0, 2000));
  REQUIRE_FALSE(state["contacts"].empty());
  REQUIRE_FALSE(state["done"].get<bool>());
  std::cout << "browser: first contact in the live view after " << since(t0) << " s (run time "
            << state["t"] << " s)" << std::endl;

  // The page in polling mode, mid-run: the robot, the contacts, the counters.
  const auto d0 = Clock::now();
  const CommandRun live = runCommand(chromium(dir.path() / "profile-poll") +
                                     " --virtual-time-budget=1500 --dump-dom '" + url +
                                     "?poll=250'");
  const double dom_s = since(d0);
  const std::string dom = domOf(live);
  INFO(live.output.substr(0, 4000));
  REQUIRE_FALSE(dom.empty());
  CHECK(attribute(dom, "robot", "visibility") == "visible");
  CHECK_FALSE(attribute(dom, "robot", "data-x").empty());
  CHECK_FALSE(attribute(dom, "robot", "transform").empty());
  CHECK(count(dom, "class=\"contact") >= 1);
  CHECK(count(dom, "data-name=\"ring_dropped\"") == 1);
  CHECK(count(dom, "data-name=\"whisks\"") == 1);
  CHECK(attribute(dom, "status", "class") == "live");
  CHECK(dom.find("id=\"arena\"") != std::string::npos);
  std::cout << "browser: mid-run DOM in " << dom_s << " s: " << count(dom, "class=\"contact")
            << " contacts drawn, robot at (" << attribute(dom, "robot", "data-x") << ", "
            << attribute(dom, "robot", "data-y") << ")" << std::endl;

  // A screenshot of the same (docs/img/live_view.png is a copy of it).
  const fs::path png = fs::path(CRUNCH_BINARY_DIR) / "live_view.png";
  fs::remove(png);
  const CommandRun shot = runCommand(chromium(dir.path() / "profile-shot") +
                                     " --virtual-time-budget=1500 --window-size=1200,760"
                                     " --screenshot=" + png.string() + " '" + url + "?poll=250'");
  INFO(shot.output.substr(0, 2000));
  REQUIRE(fs::exists(png));
  CHECK(fs::file_size(png) > 10000);
  std::ifstream in(png, std::ios::binary);
  char magic[8] = {};
  in.read(magic, 8);
  CHECK(std::string(magic + 1, 3) == "PNG");
  std::cout << "browser: screenshot " << png << " (" << fs::file_size(png) << " bytes)"
            << std::endl;

  // The run ends; so does the event stream, and the SSE page shows the end.
  const CommandRun r = robot.get();
  INFO(r.output.substr(r.output.size() > 4000 ? r.output.size() - 4000 : 0));
  CHECK(r.exit_code == 0);
  const CommandRun end = followed.get();
  const std::string end_dom = domOf(end);
  INFO(end.output.substr(0, 4000));
  REQUIRE_FALSE(end_dom.empty());
  CHECK(attribute(end_dom, "status", "class") == "ended");
  CHECK(attribute(end_dom, "robot", "visibility") == "visible");
  CHECK(count(end_dom, "class=\"contact") >= 1);
  // The final document's map is the one written.
  std::ifstream map_in(fs::path(out) / "map.json");
  REQUIRE(map_in.good());
  const json map = json::parse(map_in);
  CHECK(count(end_dom, "class=\"contact") ==
        std::min(64, map["stats"]["shapelets"].get<int>()));
  std::cout << "browser: whole test " << since(t0) << " s" << std::endl;
}
