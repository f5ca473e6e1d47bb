#include "robot_mode.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>

#include "crunch/core/atomic_file.h"
#include "crunch/io/create_base.h"
#include "crunch/io/recording.h"
#include "crunch/io/spsc_ring.h"
#include "crunch/io/usb_bridge.h"
#include "crunch/serve/live_view.h"
#include "crunch/session/controller.h"
#include "crunch/session/map_output.h"
#include "crunch/session/replay.h"
#include "crunch/session/robot_session.h"
#include "crunch/session/session_settings.h"
#include "crunch/signal/models_io.h"
#include "stop_signals.h"

namespace crunch::app {

using session::RobotSession;
using session::RobotSessionOptions;

namespace {

using json = nlohmann::json;

// 1024 slots: 4 MiB, 4 s of 28 boards at 2 kHz in full 4 KiB transfers; at least 0.5 s when the
// bridge completes a transfer per frame group (about 1 ms each).
constexpr std::size_t kRingSlots = 1024;

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Everything --robot runs with, checked before a device is opened (exit 2 otherwise).
struct RobotPlan {
  io::UsbId usb_id;
  std::string models_path;
  RobotSessionOptions session;
  session::ControllerOptions control;
  std::optional<serve::ServeAddress> serve;  // --serve
};

// The options onto the library's settings, each validated by the library (its errors name the
// field). An Error: exit 2, nothing opened or written.
Result<RobotPlan> planRobot(const RobotOptions& opt) {
  RobotPlan plan;
  auto usb_id = io::parseUsbId(opt.usb);
  if (!usb_id) return Error{"--usb: " + usb_id.error().message};
  plan.usb_id = usb_id.value();
  plan.models_path = opt.models_path.empty() ? signal::shippedModelsPath(CRUNCH_DEFAULT_MODELS) : opt.models_path;
  auto models = signal::loadModels(plan.models_path);
  if (!models) return Error{"--robot: " + models.error().message};
  RobotSessionOptions& s = plan.session;
  s = session::sessionOptions(models.value(), opt.mapping, opt.seed);
  // Exploring, the robot whisks in place at its goals and touches, as the physics sensor does.
  if (opt.explore) {
    useInPlaceWhiskFusion(s.mapping, opt.chain_fusion_given, opt.global_chains_given);
  }
  s.area_hi = {opt.area_width, opt.area_depth};
  s.start = {opt.start_x < 0.0 ? opt.area_width / 2 : opt.start_x,
             opt.start_y < 0.0 ? opt.area_depth / 2 : opt.start_y, opt.start_theta};
  s.checksum_includes_header = opt.checksum_includes_header;
  if (auto st = s.validate(); !st) return Error{"--robot: " + st.error().message};
  session::ControllerOptions& c = plan.control;
  c.duration_s = opt.duration_s;
  c.map_every_s = opt.map_every_s;
  c.calibrate_timeout_s = opt.calibrate_timeout_s;
  c.bridge = "the whisker bridge " + opt.usb;
  c.whisk = session::roamingWhiskOptions(opt.seed, s.mounts);
  if (opt.explore) {
    session::ExploreLoop::Options e;
    e.explore = *opt.explore;
    e.seed = opt.seed;
    c.explore = e;
  }
  if (auto st = c.validate(); !st) return Error{"--robot: " + st.error().message};
  if (opt.serve) {
    auto at = serve::parseServeAddress(*opt.serve);
    if (!at) return at.error();
    plan.serve = at.value();
  }
  return plan;
}

// The devices of a run. The USB thread pushes the bridge's chunks into the ring and reports its
// link state to `link`; the control loop drains both.
struct Devices {
  io::SpscRing<io::Chunk> ring{kRingSlots};
  session::LinkMonitor link;
  std::unique_ptr<io::CreateBase> create;
  std::unique_ptr<io::UsbBridge> usb;
};

// Opens both devices; each one missing is named with the fix. false: exit 3, nothing moved.
bool openDevices(const RobotOptions& opt, const RobotPlan& plan, Devices& d, std::ostream& err) {
  auto on_chunk = [&ring = d.ring](std::span<const std::uint8_t> bytes, std::uint64_t t_ns) {
    thread_local io::Chunk chunk;  // the USB thread's staging slot: no allocation per chunk
    while (!bytes.empty()) {
      const std::size_t n = chunk.assign(io::StreamId::kBridge, t_ns, bytes);
      (void)ring.tryPush(chunk);  // full: dropped and counted (spsc_ring.h)
      bytes = bytes.subspan(n);
    }
  };
  auto on_state = [&link = d.link](io::UsbBridge::LinkState s, const std::string& message) {
    link.report(s == io::UsbBridge::LinkState::kConnected, message);
  };
  io::CreateBase::Options copt;
  copt.full_mode = opt.create_full_mode;
  copt.checksum_includes_header = opt.checksum_includes_header;
  io::UsbBridge::Options bopt;
  bopt.id = plan.usb_id;
  auto create = io::CreateBase::open(opt.create, copt);
  auto bridge = io::UsbBridge::open(bopt, on_chunk, on_state);
  if (create && bridge) {
    d.create = std::move(create).value();
    d.usb = std::move(bridge).value();
    return true;
  }
  if (!bridge) err << "crunchhost: --robot: USB whisker bridge: " << bridge.error().message << "\n";
  if (!create) err << "crunchhost: --robot: Create: " << create.error().message << "\n";
  err << "crunchhost: --robot: nothing was moved. If a device is plugged in but cannot be "
         "opened, install the udev rule tools/udev/99-crunchbot.rules and join the plugdev "
         "and dialout groups (docs/USB.md, docs/CREATE.md)\n";
  return false;
}

// The output directory, then the recording (nullptr with --no-record). An Error: exit 1.
Result<std::unique_ptr<io::RecordingWriter>> openRecording(const RobotOptions& opt,
                                                           const RobotPlan& plan) {
  if (auto s = ensureDirectory(opt.out_dir); !s) return s.error();
  if (!opt.record) return std::unique_ptr<io::RecordingWriter>();
  const std::string meta =
      session::recordingMetadata(plan.session, {opt.usb, opt.create, plan.models_path});
  return io::RecordingWriter::create(
      opt.record_path.empty() ? opt.out_dir + "/recording.crec" : opt.record_path, meta);
}

// Progress lines: "[t s] text", or one JSON object per event with --json.
session::EventSink progressPrinter(bool json_progress, std::ostream& out) {
  return [json_progress, &out](const session::ControllerEvent& e) {
    if (json_progress) {
      json line{{"event", e.name}, {"t", e.t}, {"message", e.message}};
      if (e.pose) line["pose"] = {e.pose->x, e.pose->y, e.pose->theta};
      out << line.dump() << "\n";
    } else {
      out << "[" << static_cast<int>(e.t) << " s] " << e.message << "\n";
    }
    out.flush();
  };
}

// The control loop: steps the controller until it ends or a signal comes; after_step (may be
// empty) after each step.
void runLoop(session::RobotController& controller, const StopSignals& signals,
             const std::function<void()>& after_step) {
  while (true) {
    if (const int sig = signals.received(); sig != 0) {
      controller.stop(std::string("stopped by ") + StopSignals::name(sig));
      return;
    }
    if (!controller.step()) return;
    if (after_step) after_step();
  }
}

const char* stageName(session::RobotController::Stage stage) {
  using Stage = session::RobotController::Stage;
  switch (stage) {
    case Stage::kIdle: return "idle";
    case Stage::kCalibrating: return "calibrating";
    case Stage::kRoaming: return "roaming";
    case Stage::kExploring: return "exploring";
    case Stage::kPaused: return "paused (bridge lost)";
    case Stage::kStopped: break;
  }
  return "stopped";
}

// --serve: the run as the live view shows it. The pose joins the path every step; a snapshot is
// published at most every kPeriod (the pose, the stage, the --json status line's counters) and
// the map is taken again after each whisk (RobotSession::snapshot(): no random draws, so the
// map is the same with or without the view). The control loop only copies the state: the view's
// threads serve it (serve/live_view.h).
class RobotLiveFeed {
 public:
  static constexpr std::chrono::milliseconds kPeriod{200};

  RobotLiveFeed(serve::LiveView& view, const RobotSessionOptions& s,
                std::chrono::steady_clock::time_point t0)
      : view_(view), t0_(t0) {
    state_.mode = "robot";
    state_.stage = "starting";
    state_.area_lo = s.area_lo;
    state_.area_hi = s.area_hi;
    state_.moveTo(s.start);
  }

  // Every step of the loop; `status` makes the counters (statusLine) when a snapshot is due.
  void step(const RobotSession& session, const session::RobotController& c,
            const std::function<json()>& status) {
    state_.moveTo(session.pose());
    const auto now = std::chrono::steady_clock::now();
    if (now - last_ < kPeriod) return;
    last_ = now;
    publish(session, c, status());
  }

  // The final map, after the outputs are written: the last snapshot (done).
  void finish(const RobotSession& session, const session::RobotController& c, const Map& map,
              const json& status) {
    state_.moveTo(session.pose());
    state_.setMap(map);
    whisks_ = session.counts().whisks;
    state_.done = true;
    publish(session, c, status);
  }

 private:
  void publish(const RobotSession& session, const session::RobotController& c,
               const json& status) {
    if (session.counts().whisks != whisks_) {
      whisks_ = session.counts().whisks;
      state_.setMap(session.snapshot());
    }
    state_.stage = stageName(c.stage());
    state_.t = secondsSince(t0_);
    for (const auto& [name, value] : status.items()) {
      if (value.is_number() && name != "t") state_.setCounter(name, value.get<double>());
    }
    state_.setCounter("whisks", session.counts().whisks);
    state_.setCounter("contact_reports", session.counts().reports);
    state_.setCounter("bridge_frames", double(session.decoderCounters().frames));
    state_.setCounter("create_packets", double(session.tracker().counters().stream.packets));
    view_.publish(state_);
  }

  serve::LiveView& view_;
  serve::LiveState state_;
  std::chrono::steady_clock::time_point t0_, last_{};
  int whisks_ = -1;
};

// The process's resident memory now (KiB, /proc/self/statm), -1 if unreadable.
long residentKib() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (f == nullptr) return -1;
  long pages_total = 0, pages_resident = -1;
  const int n = std::fscanf(f, "%ld %ld", &pages_total, &pages_resident);
  std::fclose(f);
  return n == 2 ? pages_resident * (::sysconf(_SC_PAGESIZE) / 1024) : -1;
}

// The --json "status" line, at each running-map post: what a soak charts over time
// (tools/soak.sh): memory, the ring's high water and drops, frames lost before the host, the
// Create's watchdog stops, and the map writer's latency.
json statusLine(const RobotSession& session, const Devices& d, const session::MapWriter& writer,
                double t) {
  const session::MapWriter::Stats w = writer.stats();
  return {{"event", "status"},
          {"t", t},
          {"rss_kib", residentKib()},
          {"ring_high_water", d.ring.highWater()},
          {"ring_dropped", d.ring.dropped()},
          {"lost_frames", session.decoderCounters().lostFrames()},
          {"watchdog_stops", d.create->watchdogStops()},
          {"map_writes", w.writes},
          {"map_write_failures", w.failures},
          {"map_write_last_s", w.last_s},
          {"map_write_max_s", w.max_s}};
}

json robotReport(const RobotSession& session, const Map& map, const session::RobotController& c,
                 const Devices& d, const io::RecordingWriter* recorder) {
  json report = json::parse(session::sessionReportJson(session, map));
  report["mode"] = "robot";
  report["stop"] = c.stopReason();
  report["ring"] = {{"capacity", d.ring.capacity()},
                    {"pushed", d.ring.pushed()},
                    {"dropped", d.ring.dropped()},
                    {"high_water", d.ring.highWater()}};
  report["usb"] = {{"transfers", d.usb->transfersCompleted()},
                   {"bytes", d.usb->bytes()},
                   {"transfer_errors", d.usb->transferErrors()},
                   {"disconnects", d.usb->disconnects()},
                   {"reconnects", d.usb->reconnects()}};
  report["create_watchdog_stops"] = d.create->watchdogStops();
  if (recorder) report["recording"] = recorder->path();
  // Exploring: the loop's report (no curve: the robot has no ground truth).
  if (const session::ExploreLoop* x = c.explore()) {
    report["exploration"] = json::parse(exploration::explorationJson(x->report()).dump());
  }
  return report;
}

// map.json, map.png and report.json, published together (OutputSet) or not at all. 0, or 1
// with the error said.
int writeOutputs(const Map& map, const RobotSessionOptions& s, const std::string& out_dir,
                 const std::string& title, const json& report, std::ostream& err,
                 const exploration::ExplorationReport* exploration = nullptr) {
  OutputSet outputs;
  Status st = session::stageMapFiles(outputs, map, s.area_hi, out_dir, title, exploration);
  if (st) st = outputs.stage(out_dir + "/report.json", report.dump(2) + "\n");
  if (st) st = outputs.publish();
  if (!st) {
    err << "crunchhost: " << st.error().message << "\n";
    return 1;
  }
  return 0;
}

// The run on open devices: the controller, the loop, the shut-down in order, the outputs.
int driveRobot(const RobotOptions& opt, const RobotPlan& p, RobotSession& session, Devices& d,
               io::RecordingWriter* recorder, std::chrono::steady_clock::time_point t0,
               serve::LiveView* view, std::ostream& out, std::ostream& err) {
  // The running map goes to a writer thread (session/map_output.h says why).
  auto writer = std::make_unique<session::MapWriter>(
      p.session.area_hi, opt.out_dir, "crunchhost --robot (running)",
      [&err](const Error& e) { err << "crunchhost: " << e.message << "\n"; });
  session::ControllerSources sources;
  sources.poll_base = [&d](double timeout_s) { return d.create->poll(timeout_s); };
  sources.drain_bridge = [&d](const auto& sink) { d.ring.drain(sink); };
  sources.link = &d.link;
  sources.watchdog_stops = [&d] { return d.create->watchdogStops(); };
  sources.map = [&writer, &opt, &out, &session, &d](Map map) {
    writer->post(std::move(map));
    if (opt.json_progress) out << statusLine(session, d, *writer, d.create->now()).dump() << std::endl;
  };
  const session::EventSink progress = progressPrinter(opt.json_progress, out);
  auto made =
      session::RobotController::create(*d.create, session, p.control, std::move(sources), progress);
  if (!made) {  // planRobot validated the options: not expected
    err << "crunchhost: --robot: " << made.error().message << "\n";
    return 2;
  }
  session::RobotController& controller = *made.value();
  d.create->setByteTap(
      [&controller](std::span<const std::uint8_t> b) { controller.handleBaseBytes(b); });
  const StopSignals signals;  // from here to the end: SIGINT/SIGTERM stop the loop, not the process
  controller.start("whisker bridge " + opt.usb + " at " + d.usb->devicePath() + ", Create on " +
                   opt.create);
  std::optional<RobotLiveFeed> feed;
  if (view) feed.emplace(*view, p.session, t0);
  const auto status_now = [&] { return statusLine(session, d, *writer, d.create->now()); };
  runLoop(controller, signals, [&] {
    if (feed) feed->step(session, controller, status_now);
  });

  // ---- Shut down in order: motors, USB, the last chunks, the recording, the map.
  controller.stopMotion();
  (void)d.create->stopAndDisarm();  // stopped: the final inference below polls nothing
  const json last_status = view ? status_now() : json();  // for the view's last snapshot
  writer.reset();  // waits for a write in progress; the final map is written below
  d.usb->stop();
  controller.drainBridge();
  const Map map = session.finish();
  const Status closed = recorder ? recorder->close() : okStatus();
  const Status& failure = controller.failure() ? closed : controller.failure();
  json report = robotReport(session, map, controller, d, recorder);
  if (!failure) report["error"] = failure.error().message;
  report["wall_s"] = secondsSince(t0);
  const int written =
      writeOutputs(map, p.session, opt.out_dir, "crunchhost --robot, seed " + std::to_string(opt.seed),
                   report, err, controller.explore() ? &controller.explore()->report() : nullptr);
  if (feed) feed->finish(session, controller, map, last_status);
  if (written != 0) return 1;
  progress({"done", d.create->now(),
            controller.stopReason() + ": " + std::to_string(session.counts().whisks) + " whisks, " +
                std::to_string(map.stats.shapelets) + " shapelets, " +
                std::to_string(map.tables.size()) + " tables; wrote " + opt.out_dir +
                "/{map.json,map.png,report.json}" +
                (recorder ? " and " + recorder->path() : std::string())});
  if (!failure) {
    err << "crunchhost: --robot: " << failure.error().message << "\n";
    return 3;
  }
  return 0;
}

}  // namespace

// ------------------------------------------------------------------------------------------
// --robot
// ------------------------------------------------------------------------------------------

int runRobot(const RobotOptions& opt, std::ostream& out, std::ostream& err) {
  const auto t0 = std::chrono::steady_clock::now();
  // ---- Options, models, session: exit 2, nothing opened, nothing written.
  auto plan = planRobot(opt);
  if (!plan) {
    err << "crunchhost: " << plan.error().message << "\n";
    return 2;
  }
  auto session = RobotSession::create(plan.value().session);
  if (!session) {
    err << "crunchhost: --robot: " << session.error().message << "\n";
    return 2;
  }
  // A --out that cannot take the outputs is refused before the devices are opened.
  if (Status s = checkOutputTargets(opt.out_dir, {"map.json", "map.png", "report.json"}); !s) {
    err << "crunchhost: --robot: --out " << s.error().message << "\n";
    return 2;
  }
  // --serve: listening before a device is opened; an address that cannot be is exit 3.
  std::unique_ptr<serve::LiveView> view;
  if (plan.value().serve) {
    auto started = serve::LiveView::start({.address = *plan.value().serve});
    if (!started) {
      err << "crunchhost: --robot: " << started.error().message << "\n";
      return 3;
    }
    view = std::move(started).value();
    serve::LiveState opening;  // until the run's own snapshots come
    opening.mode = "robot";
    opening.stage = "opening the devices";
    opening.area_lo = plan.value().session.area_lo;
    opening.area_hi = plan.value().session.area_hi;
    view->publish(opening);
    (opt.json_progress ? out : err) << serve::servingLine(view->address(), opt.json_progress)
                                    << std::endl;
  }
  removeStaleTemps(opt.out_dir, {"map.json", "map.png", "report.json"});
  Devices d;  // ---- both devices are tried, every missing one named: exit 3
  if (!openDevices(opt, plan.value(), d, err)) return 3;
  auto recorder = openRecording(opt, plan.value());
  if (!recorder) {
    err << "crunchhost: " << recorder.error().message << "\n";
    return 1;
  }
  session.value()->setRecorder(recorder.value().get());
  return driveRobot(opt, plan.value(), *session.value(), d, recorder.value().get(), t0, view.get(),
                    out, err);
}

// ------------------------------------------------------------------------------------------
// --replay
// ------------------------------------------------------------------------------------------

int runReplay(const ReplayOptions& opt, std::ostream& out, std::ostream& err) {
  const auto t0 = std::chrono::steady_clock::now();
  // A --out that cannot take the outputs is refused before the replay, not after it.
  if (Status s = checkOutputTargets(opt.out_dir, {"map.json", "map.png", "report.json"}); !s) {
    err << "crunchhost: --replay: --out " << s.error().message << "\n";
    return 2;
  }
  removeStaleTemps(opt.out_dir, {"map.json", "map.png", "report.json"});
  auto replayed = session::replayRecording(opt.recording, opt.threads);
  if (!replayed) {  // the header or the settings: nothing written
    err << "crunchhost: --replay: " << replayed.error().message << "\n";
    return 2;
  }
  const session::Replay& r = replayed.value();
  if (!r.metadata_protected) {
    err << "crunchhost: --replay: " << opt.recording
        << " is a version-1 recording: its settings have no CRC of their own, so damage there "
           "cannot be detected (recordings made now carry one)\n";
  }
  json report = json::parse(session::sessionReportJson(*r.session, r.map));
  report["mode"] = "replay";
  report["recording"] = opt.recording;
  report["records"] = r.records;
  report["metadata_crc"] = r.metadata_protected;
  report["wall_s"] = secondsSince(t0);
  if (!r.damage.empty()) report["damage"] = r.damage;
  if (writeOutputs(r.map, r.options, opt.out_dir, "crunchhost --replay " + opt.recording, report,
                   err) != 0) {
    return 1;
  }
  if (opt.json_progress) {
    out << json{{"event", "done"},
                {"records", r.records},
                {"tables", r.map.tables.size()},
                {"damaged", !r.damage.empty()}}
               .dump()
        << "\n";
  } else {
    out << "replayed " << r.records << " records of " << opt.recording << ": "
        << r.session->counts().whisks << " whisks, " << r.map.stats.shapelets << " shapelets, "
        << r.map.tables.size() << " tables; wrote " << opt.out_dir
        << "/{map.json,map.png,report.json}\n";
  }
  if (!r.damage.empty()) {
    err << "crunchhost: --replay: " << r.damage << "; replayed up to the damage\n";
    return 3;
  }
  return 0;
}

}  // namespace crunch::app
