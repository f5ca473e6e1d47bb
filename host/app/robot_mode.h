// `crunchhost --robot` and `crunchhost --replay FILE` (ARCHITECTURE.md §4 command line; paper
// §2.1-2.8 end to end on the real robot).
//
// --robot: opens the USB whisker bridge (io/usb_bridge.h) and the Create (io/create_base.h);
// the USB thread puts the bridge's chunks into a lock-free SPSC ring (io/spsc_ring.h); the
// control loop, one thread, polls the Create, drains the ring into the RobotSession (decoder,
// sample assembler, signal pipeline, odometry, mapper; robot_session.h), runs the roaming body
// whisk (behaviour/body_whisk.h) on the contact mask, and marks the end of each whisk. Every
// chunk is recorded (io/recording.h) before it is processed; OUT/map.json and OUT/map.png are
// rewritten every map_every_s seconds and at the end.
//   Start: the robot stands still until every whisker's detector has calibrated its rest (at
//   most calibrate_timeout_s), then roams.
//   Unplugged bridge: the robot stops and says so, keeps everything it has, and roams again
//   when the bridge is back (the decoder and assembler forget partial frames; marked in the
//   recording). A Create that stops streaming ends the run (its error names the device).
//   SIGINT/SIGTERM, --duration: stop the motors, flush the recording, write the map, exit 0.
//
// --replay: the recording's metadata holds the run's settings and models, so a replay needs
// nothing else; the records go through the same RobotSession in the same order, which gives the
// same map. A damaged recording replays up to the damage, which is reported; the map of what
// was replayed is written and the exit status is 3.
//
// Exit codes: 0 done; 2 bad option, models or recording header (nothing written); 3 a device
// is missing or failed (the message names it and how to fix it), or the recording is damaged;
// 1 an output could not be written.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>

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
  double duration_s = 0.0;      // 0: until SIGINT/SIGTERM
  double map_every_s = 5.0;     // map.json/map.png rewritten this often
  double calibrate_timeout_s = 5.0;
  double area_width = 6.0, area_depth = 6.0;  // the mapped region, metres
  // The robot's start pose in the map frame; a negative x or y: the centre of the area.
  double start_x = -1.0, start_y = -1.0, start_theta = 0.0;
  bool create_full_mode = false;         // OI Full instead of Safe
  bool checksum_includes_header = true;  // the Create 1's checksum quirk (docs/CREATE.md)
  bool json_progress = false;
  MappingOptions mapping;
};

struct ReplayOptions {
  std::string recording;
  std::string out_dir = "out";
  bool json_progress = false;
};

int runRobot(const RobotOptions& options, std::ostream& out, std::ostream& err);
int runReplay(const ReplayOptions& options, std::ostream& out, std::ostream& err);

}  // namespace crunch::app
