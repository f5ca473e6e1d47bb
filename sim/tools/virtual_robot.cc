// crunch-virtual-robot: the whole robot, simulated behind the operating system's own device
// interfaces, for the hardware-in-loop tests (ARCHITECTURE.md §5, docs/ROBOT.md):
//
//   ODE world of --scene, WhiskeredRobot (bending whiskers, bumpers against the scene)
//     -> Hall model -> firmware core on four virtual whisker boards -> bridge bytes
//     -> VirtualUsbBridge: a umockdev USB device 1209:0001 with a live ioctl handler
//   CreateEmulator on a pseudo-terminal, driving the same WhiskeredRobot (OI v2 bytes)
//
// and runs the program given after `--` as a child that sees both: the child is started with the
// umockdev preload library and the testbed's UMOCKDEV_DIR, and "{create}" in its arguments is
// replaced by the emulator's pty path. Simulated time follows the wall clock (--rate times real
// time), so the unmodified `crunchhost --robot` runs against it as against the real robot.
// Only the USB device nodes are emulated: the Create's pty stays the kernel's tty under the
// preload, whatever serial library the child uses (VirtualUsbBridge::create, docs/CREATE.md
// "Your own Create client against the virtual robot"). --no-usb-preload starts the child
// without the preload and without UMOCKDEV_DIR, for a child that talks only to the Create (it
// then cannot see the USB bridge).
//
// Packet ids the Create 1 does not have (outside 0..42) that the child asks for are skipped by
// the emulator (CreateEmulator), said once on stderr and listed in the summary.
//
// --truth-csv FILE writes the robot's true pose every 10 ms of simulated time with the
// CLOCK_MONOTONIC time it was simulated at (t_ns,sim_s,x_m,y_m,theta_rad): the clock the child
// stamps what it reads with, so the child's own pose track (`crunchhost export --format csv`,
// odometry.csv) can be set against the truth (tools/odometry_error.py).
//
// Faults (for the tests): --unplug-at/--replug-at (seconds of simulated time), --corrupt-every N
// (one byte of every Nth tick's bridge bytes flipped), --serial-garbage-every S (garbage bytes
// on the Create's line), --create-silent (a Create that never answers), --interrupt-at (SIGINT
// to the child, as Ctrl-C).
//
// When the child exits, prints one JSON line on stdout (the robot's true final pose, counters)
// and exits with the child's status (124 if --time-limit killed it).
#include <signal.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <array>
#include <bitset>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "crunch/scene/scene.h"
#include "crunch_sim/create_emulator.h"
#include "crunch_sim/training.h"
#include "crunch_sim/virtual_usb_bridge.h"
#include "crunch_sim/whisker_rig.h"
#include "crunch_sim/world.h"

namespace {

using namespace crunch;

pid_t spawnChild(std::vector<std::string> args, const std::string& create_path,
                 bool usb_preload) {
  for (std::string& a : args) {
    const auto at = a.find("{create}");
    if (at != std::string::npos) a.replace(at, 8, create_path);
  }
  const pid_t pid = fork();
  if (pid != 0) return pid;
  if (usb_preload) {
    // The child: the umockdev preload makes libusb see the testbed's device.
    std::string preload = "libumockdev-preload.so.0";
    if (const char* old = std::getenv("LD_PRELOAD"); old != nullptr && *old != '\0') {
      preload += std::string(":") + old;
    }
    setenv("LD_PRELOAD", preload.c_str(), 1);
  } else {
    unsetenv("UMOCKDEV_DIR");  // LD_PRELOAD is left as the user set it
  }
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  execvp(argv[0], argv.data());
  std::perror(("crunch-virtual-robot: cannot run " + args[0]).c_str());
  _exit(127);
}

std::vector<int> idVector(const std::bitset<256>& ids) {
  std::vector<int> v;
  for (int id = 0; id < 256; ++id) {
    if (ids.test(static_cast<std::size_t>(id))) v.push_back(id);
  }
  return v;
}

std::string idList(const std::bitset<256>& ids) {
  std::string s;
  for (const int id : idVector(ids)) {
    if (!s.empty()) s.append(", ");
    s.append(std::to_string(id));
  }
  return s;
}

std::uint64_t monotonicNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000000ull +
         static_cast<std::uint64_t>(ts.tv_nsec);
}

void sleepFor(double seconds) {
  timespec ts{0, static_cast<long>(seconds * 1e9)};
  nanosleep(&ts, nullptr);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"crunch-virtual-robot: a simulated whiskered Create behind umockdev USB and a pty"};
  std::string scene_path;
  std::vector<double> start;
  std::uint64_t seed = 1;
  double rate = 1.0, time_limit = 300.0;
  double wheel_acceleration = 0.5;  // m/s^2, an assumption (whisker_physics.h)
  double unplug_at = -1.0, replug_at = -1.0, garbage_every = 0.0;
  int corrupt_every = 0;
  bool silent = false;
  bool log_contacts = false;
  bool no_usb_preload = false;
  double interrupt_at = -1.0;
  std::string truth_csv;
  std::vector<std::string> child;
  app.add_option("--scene", scene_path, "scene file (ARCHITECTURE.md §4)")->required();
  app.add_option("--start", start, "start pose x y theta (default: the scene's first pose)")
      ->expected(3);
  app.add_option("--seed", seed, "Hall sensor noise seed");
  app.add_option("--rate", rate, "simulated seconds per wall-clock second");
  app.add_option("--wheel-acceleration", wheel_acceleration,
                 "the base's wheel acceleration limit, m/s^2 (0: instant)");
  app.add_option("--time-limit", time_limit, "wall-clock seconds before the child is killed");
  app.add_option("--unplug-at", unplug_at, "simulated second at which the USB bridge is unplugged");
  app.add_option("--replug-at", replug_at, "simulated second at which it is plugged back");
  app.add_option("--corrupt-every", corrupt_every, "flip one byte of every Nth tick's frames");
  app.add_option("--serial-garbage-every", garbage_every, "seconds between garbage on the serial line");
  app.add_flag("--create-silent", silent, "the Create never answers");
  app.add_option("--interrupt-at", interrupt_at,
                 "simulated second at which the child gets SIGINT (Ctrl-C)");
  app.add_flag("--log-contacts", log_contacts,
               "print each true whisker contact (ODE) as it begins, on stderr");
  app.add_option("--truth-csv", truth_csv,
                 "write the true pose every 10 ms of simulated time, with its CLOCK_MONOTONIC "
                 "time, to this CSV file");
  app.add_flag("--no-usb-preload", no_usb_preload,
               "start the child without the umockdev preload (it sees the Create, not the USB "
               "bridge)");
  app.add_option("child", child, "the program to run, after --");
  // Everything after the first `--` is the child's, verbatim: split here rather than left to
  // CLI11, which ends a multi-value option such as `--start 1 1 0` at that `--` and then parses
  // the child's own options (`--port`) as the harness's.
  int own = argc;
  for (int i = 1; i < argc; ++i) {
    if (std::string_view(argv[i]) == "--") {
      own = i;
      break;
    }
  }
  try {
    app.parse(own, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  if (own < argc) {
    if (!child.empty()) {
      std::cerr << "crunch-virtual-robot: the program to run goes after --, not before it\n";
      return 2;
    }
    child.assign(argv + own + 1, argv + argc);
  }
  if (child.empty()) {
    std::cerr << "crunch-virtual-robot: no program to run: give it after --\n";
    return 2;
  }

  auto scene = loadScene(scene_path);
  if (!scene) {
    std::cerr << "crunch-virtual-robot: " << scene.error().message << "\n";
    return 2;
  }
  Pose2 start_pose;
  if (start.size() == 3) {
    start_pose = {start[0], start[1], start[2]};
  } else if (!scene.value().poses.empty()) {
    start_pose = scene.value().poses.front();
  } else {
    std::cerr << "crunch-virtual-robot: --start is needed: the scene lists no pose\n";
    return 2;
  }
  auto world = sim::World::build(scene.value());
  // The rig the shipped models were trained with, on a base whose wheels accelerate like a real
  // one's (whisker_physics.h: an instant step of the turn rate swings the whiskers past the
  // contact threshold).
  sim::WhiskerRig::Options rig_options = sim::physicsRigOptions(seed);
  rig_options.robot.max_wheel_acceleration = wheel_acceleration;
  rig_options.negative_evidence = false;  // the rig only senses; the host whisks
  auto rig = sim::WhiskerRig::create(*world, defaultWhiskerArray(), start_pose, rig_options);
  if (!rig) {
    std::cerr << "crunch-virtual-robot: " << rig.error().message << "\n";
    return 2;
  }
  sim::WhiskerRig& r = *rig.value();
  auto emulator = sim::CreateEmulator::open(r.robot(), sim::CreateEmulator::Options{});
  if (!emulator) {
    std::cerr << "crunch-virtual-robot: " << emulator.error().message << "\n";
    return 2;
  }
  sim::CreateEmulator& create = *emulator.value();
  create.setSilent(silent);
  auto usb = sim::VirtualUsbBridge::create(sim::VirtualUsbBridge::Options{});
  if (!usb) {
    std::cerr << "crunch-virtual-robot: " << usb.error().message << "\n";
    return 2;
  }
  sim::VirtualUsbBridge& bridge = *usb.value();
  std::ofstream truth;
  if (!truth_csv.empty()) {
    truth.open(truth_csv);
    if (!truth) {
      std::cerr << "crunch-virtual-robot: cannot write --truth-csv " << truth_csv << "\n";
      return 2;
    }
    truth << "t_ns,sim_s,x_m,y_m,theta_rad\n";
    truth.precision(9);
  }
  std::cerr << "crunch-virtual-robot: scene " << scene_path << ", USB bridge at "
            << bridge.devicePath() << ", Create on " << create.slavePath() << "\n";

  const pid_t pid = spawnChild(child, create.slavePath(), !no_usb_preload);
  if (pid < 0) {
    std::perror("crunch-virtual-robot: fork");
    return 2;
  }
  const auto wall0 = std::chrono::steady_clock::now();
  const double sim0 = r.robot().now();
  std::vector<std::uint8_t> batch;
  batch.reserve(1 << 16);
  std::uint64_t ticks = 0, corrupted = 0, garbage = 0;
  double next_garbage = garbage_every > 0.0 ? sim0 + garbage_every : -1.0;
  bool unplugged = false, replugged = false;
  std::array<bool, 4> touching{}, detecting{};
  std::uint64_t unsupported_said = 0;  // unsupported ids already reported on stderr
  int status = 0;
  int exit_code = -1;
  while (true) {
    const pid_t done = waitpid(pid, &status, WNOHANG);
    if (done == pid) {
      exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      break;
    }
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    if (wall > time_limit) {
      kill(pid, SIGTERM);
      waitpid(pid, &status, 0);
      exit_code = 124;
      std::cerr << "crunch-virtual-robot: --time-limit " << time_limit << " s: child killed\n";
      break;
    }
    const double target = sim0 + rate * wall;
    int steps = 0;
    while (r.robot().now() < target && steps < 400) {
      (void)r.step();
      ++ticks;
      if (truth.is_open() && ticks % 20 == 0) {  // 20 ticks of 500 us
        const Pose2 q = r.robot().odometry();
        truth << monotonicNs() << ',' << r.robot().now() - sim0 << ',' << q.x << ',' << q.y << ','
              << q.theta << '\n';
      }
      if (log_contacts) {
        for (int w = 0; w < 4; ++w) {
          const auto c = r.robot().contact(w);
          if (c.has_value() != touching[static_cast<std::size_t>(w)] && c.has_value()) {
            const Pose2 q = r.robot().odometry();
            std::cerr << "truth: t " << r.robot().now() - sim0 << " whisker " << w << " touches ("
                      << c->point.x() << ", " << c->point.y() << ") r " << c->r << " from pose ("
                      << q.x << ", " << q.y << ", " << q.theta << ")\n";
          }
          touching[static_cast<std::size_t>(w)] = c.has_value();
          const bool detected = (r.contactMask() >> w) & 1u;
          if (detected && !detecting[static_cast<std::size_t>(w)]) {
            std::cerr << "detector: t " << r.robot().now() - sim0 << " whisker " << w
                      << " onset, base angle " << r.robot().baseAngles(w).horizontal << "\n";
          }
          detecting[static_cast<std::size_t>(w)] = detected;
        }
      }
      const auto bytes = r.lastTickBytes();
      const std::size_t at = batch.size();
      batch.insert(batch.end(), bytes.begin(), bytes.end());
      if (corrupt_every > 0 && ticks % static_cast<std::uint64_t>(corrupt_every) == 0 &&
          batch.size() > at + 8) {
        batch[at + 8] ^= 0x5A;  // inside the first frame's payload: its CRC fails
        ++corrupted;
      }
      // The tick's frames go to the bridge before the Create answers for the same tick: the
      // two streams reach the host in the order the robot made them, as on the real robot,
      // also when the harness runs behind the wall clock and steps many ticks at once.
      if (bridge.plugged()) bridge.push(batch);  // unplugged: the frames are lost, as on a bus
      batch.clear();
      create.pump();
      ++steps;
    }
    const double now = r.robot().now() - sim0;
    if (unplug_at >= 0.0 && !unplugged && now >= unplug_at) {
      bridge.unplug();
      unplugged = true;
      std::cerr << "crunch-virtual-robot: unplugged the USB bridge at " << now << " s\n";
    }
    if (unplugged && !replugged && replug_at >= 0.0 && now >= replug_at) {
      bridge.replug();
      replugged = true;
      std::cerr << "crunch-virtual-robot: plugged the USB bridge back at " << now << " s\n";
    }
    if (interrupt_at >= 0.0 && now >= interrupt_at) {
      kill(pid, SIGINT);
      interrupt_at = -1.0;
      std::cerr << "crunch-virtual-robot: sent SIGINT to the child at " << now << " s\n";
    }
    if (next_garbage >= 0.0 && r.robot().now() >= next_garbage) {
      static const std::uint8_t kGarbage[] = {0x13, 0x05, 0xFF, 0x13, 0x00, 0x42, 0x13};
      create.injectGarbage(kGarbage);
      garbage += sizeof kGarbage;
      next_garbage += garbage_every;
    }
    if (unsupported_said == 0 && create.counters().unsupported_ids > 0) {
      unsupported_said = create.counters().unsupported_ids;
      std::cerr << "crunch-virtual-robot: the client asked for packet id(s) "
                << idList(create.unsupportedIds())
                << " that the Create 1 (OI v2, packet ids 0-42) does not have: they are skipped, "
                   "so the answer or stream carries only the other ids (said once; the count is "
                   "in the summary's create.unsupported_ids)\n";
    }
    if (steps == 0) sleepFor(0.0005);  // ahead of the wall clock: wait for it
  }
  const Pose2 p = r.robot().odometry();
  nlohmann::json summary = {
      {"child_exit", exit_code},
      {"truth_pose", {p.x, p.y, p.theta}},
      {"sim_s", r.robot().now() - sim0},
      {"ticks", ticks},
      {"corrupted_ticks", corrupted},
      {"garbage_bytes", garbage},
      {"usb", {{"urbs", bridge.urbsCompleted()}, {"bytes", bridge.bytesDelivered()}}},
      {"create", {{"commands", create.counters().commands},
                  {"packets", create.counters().packets_sent},
                  {"unsupported_ids", create.counters().unsupported_ids},
                  {"unsupported_id_list", idVector(create.unsupportedIds())},
                  {"last_wheels_mm_s", {create.requestedRight(), create.requestedLeft()}}}}};
  std::cout << summary.dump() << std::endl;
  return exit_code;
}
