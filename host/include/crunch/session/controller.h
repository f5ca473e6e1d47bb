// The robot's control loop (paper §2.3 on §2.1-2.8's data path): drives any MobileBase — the
// Create's driver io::CreateBase on the robot, the simulator's bases in tests — with the roaming
// body whisk (behaviour/body_whisk.h) on the RobotSession's contact mask, and hands every input
// chunk to the session in the order it handled them, so a recording replays to the same map.
//
// States:
//   kCalibrating  standing still until every whisker's detector has its rest (RobotSession::
//                 calibrated()); not within calibrate_timeout_s: the run ends with an Error that
//                 says whether no samples came or the whiskers would not settle.
//   kRoaming      BodyWhisk::update(contact mask) each step. A whisk's toward leg beginning is a
//                 whisk-start mark, its random turn beginning (the robot backed clear) a
//                 whisk-end mark: the sweep's contacts form one group for the mapper.
//   kPaused       the bridge's link is lost (LinkMonitor): the robot halts, keeps everything,
//                 and waits; when the link is back the session forgets partial frames (a
//                 kBridgeReconnected mark) and the robot calibrates again, then roams.
// A watchdog stop of the base (its motors stopped because the loop stalled: Sources::
// watchdog_stops) is reported and the behaviour re-sends its command (BodyWhisk::commandLost).
//
// One step() is one pass of the loop, in this order (what the recordings so far were made with):
//   duration reached? -> poll the base's input (Sources::poll_base; the Create's bytes reach the
//   session through handleBaseBytes, its byte tap) -> drain the bridge's chunks into the
//   session (Sources::drain_bridge) -> a failure so far ends the run -> the link's state ->
//   the stage's work -> the running map every map_every_s (Sources::map) -> watchdog stops.
// Devices stay outside: the caller opens them, hands the chunk sources in as callbacks and owns
// the threads (the USB thread reports to a LinkMonitor; the ring is drained by drain_bridge).
//
// Errors: the first failure (a recording write, a refused command, the base's input failing, the
// calibration timeout) is kept (failure()) and ends the run at once or at the next step; the
// run's other outcome is its stopReason(). Progress and events go to the EventSink, with the
// base's time.
//
// Ownership: holds references to the base and the session, which must outlive it; owns the
// BodyWhisk. Thread-safety: none; one control loop calls everything, except LinkMonitor::
// report(), which any thread may call. Allocation: a step allocates only for events and marks
// (a whisk's end allocates the mapper's new shapelets); chunk handling allocates nothing.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "crunch/behaviour/body_whisk.h"
#include "crunch/core/result.h"
#include "crunch/io/recording.h"
#include "crunch/robot/mobile_base.h"
#include "crunch/robot/whiskers.h"
#include "crunch/exploration/known_space.h"
#include "crunch/exploration/policy.h"
#include "crunch/session/explore_loop.h"
#include "crunch/session/robot_session.h"

namespace crunch::session {

// The bridge's link state as the USB thread sees it, handed to the control loop.
// Thread-safety: report() from any one thread, take() from the control loop.
class LinkMonitor {
 public:
  struct Event {
    bool up = true;
    std::string message;  // the driver's words: what happened to the device
  };
  // The link is now up (connected) or down, with the driver's message.
  void report(bool up, std::string message);
  // The newest state if any report came since the last take(), else nullopt. Several reports
  // between two takes are seen as one, the newest: the loop acts on the state, not the history.
  // Allocates (the message) only when there is an event.
  std::optional<Event> take();

 private:
  std::mutex mutex_;
  Event latest_;                // under mutex_
  std::atomic<int> events_{0};  // bumped by every report()
  int seen_ = 0;                // the control loop's
};

// The body whisk as the roaming robot runs it: the whisker bearings of `mounts`, `seed` for the
// random turns, and no reverse before the sweep. A whisker meets an object with its tip, at the
// edge of its reach, and turning in place keeps every point's distance from the robot's centre,
// so after any reverse the sweep could not touch it again (measured: 0 contacts in 9 whisks with
// the 3 cm default). Stopping on the contact (~2 mm of push at 0.1 m/s) and sweeping from there
// is the "pressed start" the orientation models were trained with (docs/TRAINING.md).
BodyWhisk::Options roamingWhiskOptions(std::uint64_t seed, const std::vector<WhiskerMount>& mounts);

struct ControllerOptions {
  double duration_s = 0.0;           // the run ends this long after start(); 0: never
  double map_every_s = 5.0;          // Sources::map gets a snapshot this often; > 0
  double calibrate_timeout_s = 5.0;  // the whiskers calibrate within this; > 0
  double poll_timeout_s = 0.002;     // Sources::poll_base waits at most this per step; >= 0
  // Names the bridge in the calibration error ("the whisker bridge 1209:0001 sent no ...").
  std::string bridge = "the whisker bridge";
  BodyWhisk::Options whisk = roamingWhiskOptions(1, defaultWhiskerArray());
  // --explore (issue 14, docs/EXPLORATION.md): after calibrating, the robot explores the
  // session's area (RobotSessionOptions::area_lo/hi, the map frame) with the ExploreLoop — the
  // behaviour `--sim --explore` drives the simulator's base with — instead of roaming: each
  // whisk the loop makes is bracketed by whisk marks, so the session maps it as a roaming
  // whisk (and a recording replays to the same map); its free rays, contacts and the map's
  // legs and walls update the loop's KnownSpace. nullopt: roaming (kRoaming).
  std::optional<ExploreLoop::Options> explore;

  // okStatus(), or an Error naming the first bad field: duration_s 0..1e7, map_every_s and
  // calibrate_timeout_s above 0 and at most 1e7, poll_timeout_s 0..1, whisk.validate() (prefixed
  // "whisk: ").
  Status validate() const;
};

// Where the controller's input comes from. Every member may be empty: then there is none.
struct ControllerSources {
  // Reads the base's own input, waiting at most timeout_s (the Create: CreateBase::poll, whose
  // byte tap calls RobotController::handleBaseBytes). An Error ends the run ("the Create
  // failed": the error names the device).
  std::function<Status(double timeout_s)> poll_base;
  // Hands every bridge chunk that arrived since the last call to the sink, in arrival order
  // (the SPSC ring's drain).
  std::function<void(const std::function<void(const io::Chunk&)>& sink)> drain_bridge;
  // The bridge's link state (not owned; must outlive the controller).
  LinkMonitor* link = nullptr;
  // How many times the base's watchdog has stopped the motors (CreateBase::watchdogStops).
  std::function<std::uint64_t()> watchdog_stops;
  // The map so far, every map_every_s (MapWriter::post; map_output.h).
  std::function<void(Map)> map;
  // CLOCK_MONOTONIC in ns for the chunks and marks this controller makes; empty: io::monotonicNs.
  std::function<std::uint64_t()> clock_ns;
};

// What the controller says as it goes. name: "start", "roaming", "exploring", "goal", "bridge_lost",
// "bridge_back", "contact", "bump", "whisk", "watchdog"; t: the base's now(); message: for a
// person. An exploring robot's "goal" (the policy chose a whisk pose) has `pose` set to it, and
// its "whisk" has `pose` set to where the whisk began (map frame).
struct ControllerEvent {
  const char* name;
  double t;
  std::string message;
  std::optional<Pose2> pose = std::nullopt;
};
using EventSink = std::function<void(const ControllerEvent&)>;

class RobotController {
 public:
  enum class Stage { kIdle, kCalibrating, kRoaming, kExploring, kPaused, kStopped };

  // Errors: options.validate(). Sends nothing to the base until start() and step().
  static Result<std::unique_ptr<RobotController>> create(MobileBase& base, RobotSession& session,
                                                         const ControllerOptions& options,
                                                         ControllerSources sources,
                                                         EventSink events);
  RobotController(const RobotController&) = delete;
  RobotController& operator=(const RobotController&) = delete;

  // Begins the run: a "start" event (`what`, then "; calibrating the whiskers at rest"), the
  // duration and the map interval measured from now, kCalibrating.
  void start(const std::string& what);
  // One pass of the loop (see the top). true: call again; false: the run has ended (stage()
  // kStopped; stopReason(), failure()).
  bool step();
  // Ends the run now with `reason` (e.g. "stopped by SIGINT"); the next step() returns false.
  void stop(const std::string& reason);
  // Shut-down, in order: halt the behaviour, then stop the base. Errors are ignored (the run is
  // over; the base's own safety stops it anyway).
  void stopMotion();
  // Hands the bridge's waiting chunks to the session (step() does it; call once more after the
  // bridge's thread has stopped, so the last chunks are recorded and mapped).
  void drainBridge();
  // The base's input bytes (the Create's byte tap): to the session as kCreate chunks stamped now.
  void handleBaseBytes(std::span<const std::uint8_t> bytes);

  Stage stage() const { return stage_; }
  const std::string& stopReason() const { return stop_reason_; }
  // okStatus(), or the first failure.
  const Status& failure() const { return failure_; }
  const BodyWhisk& whisk() const { return whisk_; }
  // The exploring robot's loop (its report: path, whisk poses, bumps, travel, decisions); null
  // when roaming.
  const ExploreLoop* explore() const { return explore_.get(); }

 private:
  RobotController(MobileBase& base, RobotSession& session, const ControllerOptions& options,
                  ControllerSources sources, EventSink events);
  void fail(const Error& error);
  bool end(const std::string& reason);  // stops the run; returns false
  void emit(const char* name, const std::string& message);
  std::uint64_t nowNs() const;
  void onLinkEvent(const LinkMonitor::Event& event);
  bool calibrating();
  bool roaming();
  void startExploring();
  bool exploring();
  void onWhisked(const Pose2& pose);

  // The base as the exploring loop sees it: the session's map-frame pose (start + odometry,
  // the frame the map and the KnownSpace are in), the base's commands, bumper and clock.
  class MapFrameBase final : public MobileBase {
   public:
    MapFrameBase(MobileBase& base, const RobotSession& session) : base_(base), session_(session) {}
    Status drive(double v, double omega) override { return base_.drive(v, omega); }
    Pose2 odometry() const override { return session_.pose(); }
    bool bumped() const override { return base_.bumped(); }
    Bumper bumper() const override { return base_.bumper(); }
    double now() const override { return base_.now(); }

   private:
    MobileBase& base_;
    const RobotSession& session_;
  };

  MobileBase& base_;
  RobotSession& session_;
  ControllerOptions options_;
  ControllerSources sources_;
  EventSink events_;
  BodyWhisk whisk_;
  // Exploring (options.explore set): the loop over the map-frame base, what it knows, its policy.
  MapFrameBase frame_base_;
  std::unique_ptr<exploration::KnownSpace> known_;
  std::unique_ptr<exploration::ExplorePolicy> policy_;
  std::unique_ptr<ExploreLoop> explore_;
  std::optional<Pose2> announced_goal_;
  bool whisk_open_ = false;         // a kWhiskStart mark awaits its kWhiskEnd
  std::size_t contacts_known_ = 0;  // the session's shapelets already marked in known_
  std::function<void(const io::Chunk&)> sink_;  // into the session, failures kept
  io::Chunk base_chunk_;                        // handleBaseBytes' staging slot
  Stage stage_ = Stage::kIdle;
  double start_s_ = 0.0;
  double next_map_s_ = 0.0;
  double calibrate_since_ = 0.0;
  std::uint64_t watchdog_seen_ = 0;
  std::string stop_reason_ = "done";
  Status failure_ = okStatus();
};

}  // namespace crunch::session
