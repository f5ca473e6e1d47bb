// What a robot session writes besides its recording (docs/ROBOT.md): OUT/map.json and
// OUT/map.png (the map so far, or the final one), and the report's session part. Used by
// `crunchhost --robot` while it runs and at the end, and by `crunchhost --replay`.
//
// MapWriter writes the running map off the control loop: rendering and the atomic write's fsync
// can take longer than the Create's watchdog allows the loop to stall (measured: a 0.5 s stall
// under disk load stopped the motors and overflowed the ring; docs/ROBOT.md "nothing slow on the
// control loop"). post() hands over the newest snapshot; one still waiting is replaced (only the
// newest map matters).
//
// Thread-safety: writeMapFiles and sessionReportJson are plain functions (the session must not
// change during sessionReportJson). MapWriter: post() from one thread (the control loop); the
// writer thread is its own; on_error is called on the writer thread. Ownership: MapWriter owns
// its thread (joined by the destructor, after a write in progress) and copies what it needs.
// Allocation: post() moves the map in; the writer allocates while rendering.
#pragma once

#include <condition_variable>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "crunch/core/atomic_file.h"  // OutputSet
#include "crunch/core/result.h"
#include "crunch/exploration/exploration.h"
#include "crunch/mapping/fused_map.h"
#include "crunch/session/robot_session.h"

namespace crunch::session {

// OUT/map.json and OUT/map.png (the mapped area [0, area_hi] — RobotSessionOptions::area_hi
// — drawn as the "truth", titled `title`), written into `outputs` (atomic_file.h) to be
// published with the caller's other files; creates `out_dir` if needed. The first Error.
Status stageMapFiles(OutputSet& outputs, const Map& map, const Vec2& area_hi,
                     const std::string& out_dir, const std::string& title,
                     const exploration::ExplorationReport* exploration = nullptr);

// The same two files published together: both new, or (on an Error) both as they were.
Status writeMapFiles(const Map& map, const Vec2& area_hi, const std::string& out_dir,
                     const std::string& title,
                     const exploration::ExplorationReport* exploration = nullptr);

// The report's session part as JSON text (an object): every counter of the data path ("bridge",
// "samples", "create", "contacts"), "final_pose", "map" (tables, shapelets), "global_inference"
// (wall_s, threads: report_json.h) and "shapelets" (x, y, phi, whisker, pose, from). The caller adds its own keys (mode, stop reason, devices).
std::string sessionReportJson(const RobotSession& session, const Map& map);

class MapWriter {
 public:
  // Starts the writer thread. Each posted map goes through writeMapFiles(map, area_hi, out_dir,
  // title); a failed write is handed to on_error (may be empty: ignored), and the next post is
  // tried all the same.
  MapWriter(const Vec2& area_hi, std::string out_dir, std::string title,
            std::function<void(const Error&)> on_error);
  // Waits for a write in progress; a map still waiting is not written.
  ~MapWriter();
  MapWriter(const MapWriter&) = delete;
  MapWriter& operator=(const MapWriter&) = delete;

  void post(Map map);

  // The writes so far and how long they took (wall seconds, render + fsync + rename): what a
  // soak run charts (tools/soak.sh). Safe to call from any thread.
  struct Stats {
    int writes = 0;
    int failures = 0;
    double last_s = 0.0;
    double max_s = 0.0;
  };
  Stats stats() const;

 private:
  void loop();

  Vec2 area_hi_;
  std::string out_dir_;
  std::string title_;
  std::function<void(const Error&)> on_error_;
  mutable std::mutex mutex_;
  Stats stats_;  // under mutex_
  std::condition_variable cv_;
  std::optional<Map> pending_;
  bool stop_ = false;
  std::thread thread_;  // last: started once the rest is built
};

}  // namespace crunch::session
