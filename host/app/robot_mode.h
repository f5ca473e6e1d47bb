// `crunchhost --robot` and `crunchhost --replay FILE` (ARCHITECTURE.md §4 command line; paper
// §2.1-2.8 end to end on the real robot). Parsing and wiring only: the running robot is the
// library's session area (docs/ROBOT.md).
//
// --robot: the options become the library's settings (session::sessionOptions,
// session::ControllerOptions; each validated by the library, its error naming the field); then
// opens the USB whisker bridge (io/usb_bridge.h) and the Create (io/create_base.h); the USB
// thread puts the bridge's chunks into a lock-free SPSC ring (io/spsc_ring.h) and its link state
// into a session::LinkMonitor; the control loop, one thread, steps a session::RobotController
// (session/controller.h: calibrating, roaming with the body whisk, paused while the bridge is
// unplugged, whisk marks, watchdog stops) that polls the Create and drains the ring into the
// RobotSession (decoder, sample assembler, signal pipeline, odometry, mapper;
// session/robot_session.h). Every chunk is recorded (io/recording.h; the metadata is
// session/session_settings.h) before it is processed; OUT/map.json and OUT/map.png are rewritten
// every map_every_s seconds by a writer thread (session::MapWriter) and at the end.
//   SIGINT/SIGTERM, --duration: stop the motors, flush the recording, write the map, exit 0.
//
// --replay: session::replayRecording (session/replay.h): the recording's metadata holds the
// run's settings and models, so a replay needs nothing else; the records go through the same
// RobotSession in the same order, which gives the same map. A damaged recording replays up to
// the damage, which is reported; the map of what was replayed is written and the exit status
// is 3.
//
// Exit codes: 0 done; 2 bad option, models or recording header (nothing written); 3 a device
// is missing or failed (the message names it and how to fix it), the recording is damaged, or
// the --serve address cannot be listened on (nothing opened or written);
// 1 an output could not be written.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>

#include "crunch/exploration/exploration.h"
#include "crunch/mapping/run_mapping.h"

namespace crunch::app {

struct RobotOptions {
  std::string usb = "1209:0001";        // VID:PID of the whisker bridge (docs/USB.md)
  std::string create = "/dev/ttyUSB0";  // the Create's serial port
  std::string out_dir = "out";
  std::string models_path;  // empty: the shipped models/sim_models.json
  std::string record_path;  // empty: OUT/recording.crec
  bool record = true;
  std::uint64_t seed = 1;
  double duration_s = 0.0;   // 0: until SIGINT/SIGTERM
  double map_every_s = 5.0;  // map.json/map.png rewritten this often
  double calibrate_timeout_s = 5.0;
  double area_width = 6.0, area_depth = 6.0;  // the mapped region, metres
  // The robot's start pose in the map frame; a negative x or y: the centre of the area.
  double start_x = -1.0, start_y = -1.0, start_theta = 0.0;
  bool create_full_mode = false;         // OI Full instead of Safe
  bool checksum_includes_header = true;  // the Create 1's checksum quirk (docs/CREATE.md)
  bool json_progress = false;
  MappingOptions mapping;
  // --chain-fusion / --global-chains given: used as they are; not given and exploring: the
  // in-place whisk's fusion (mapping_options.h, useInPlaceWhiskFusion).
  bool chain_fusion_given = false;
  bool global_chains_given = false;
  // --explore POLICY [--travel-budget M] [--whisk-budget N]: the robot explores instead of
  // roaming (session/controller.h ControllerOptions::explore); validated by planRobot.
  std::optional<exploration::ExploreOptions> explore;
  // --serve ADDRESS: a live view of the run (serve/live_view.h, docs/LIVE_VIEW.md), listening
  // before the devices are opened. A bad address: exit 2; one that cannot be listened on: exit 3;
  // nothing opened or written either way.
  std::optional<std::string> serve;
};

struct ReplayOptions {
  std::string recording;
  std::string out_dir = "out";
  bool json_progress = false;
  int threads = 0;  // --threads: MappingOptions::threads (not in the recording: a machine's)
};

int runRobot(const RobotOptions& options, std::ostream& out, std::ostream& err);
int runReplay(const ReplayOptions& options, std::ostream& out, std::ostream& err);

}  // namespace crunch::app
