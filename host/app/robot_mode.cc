#include "robot_mode.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cmath>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>

#include "crunch/behaviour/body_whisk.h"
#include "crunch/core/atomic_file.h"
#include "crunch/io/create_base.h"
#include "crunch/io/recording.h"
#include "crunch/io/spsc_ring.h"
#include "crunch/io/usb_bridge.h"
#include "crunch/mapping/map_io.h"
#include "crunch/mapping/sensor_model.h"
#include "crunch/render/map_render.h"
#include "crunch/scene/scene.h"
#include "crunch/signal/models_io.h"
#include "crunch/session/robot_session.h"

namespace crunch::app {

using session::RobotSession;
using session::RobotSessionOptions;

namespace {

using json = nlohmann::json;

// 1024 slots: 4 MiB, 4 s of 28 boards at 2 kHz in full 4 KiB transfers; at least 0.5 s when the
// bridge completes a transfer per frame group (about 1 ms each).
constexpr std::size_t kRingSlots = 1024;
constexpr char kRecordingSchema[] = "crunch.recording/1";

// SIGINT/SIGTERM: the control loop sees this and shuts down in order.
std::atomic<int> g_signal{0};
extern "C" void onSignal(int sig) { g_signal.store(sig); }

class SignalGuard {
 public:
  SignalGuard() {
    g_signal.store(0);
    struct sigaction sa {};
    sa.sa_handler = onSignal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_int_);
    sigaction(SIGTERM, &sa, &old_term_);
  }
  ~SignalGuard() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  SignalGuard(const SignalGuard&) = delete;
  SignalGuard& operator=(const SignalGuard&) = delete;

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

const char* signalName(int sig) { return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "signal"; }

// The settings a replay needs to give the same map: everything the session's result depends on.
json settingsJson(const RobotSessionOptions& s, std::uint64_t seed) {
  const SamplerOptions& so = s.mapping.sampler;
  return {{"seed", seed},
          {"start", {s.start.x, s.start.y, s.start.theta}},
          {"area", {s.area_lo.x(), s.area_lo.y(), s.area_hi.x(), s.area_hi.y()}},
          {"checksum_includes_header", s.checksum_includes_header},
          {"onset_threshold", s.pipeline.detector.min_onset_threshold},
          {"mapping",
           {{"working_memory", s.mapping.working_memory},
            {"schedule_steps", so.schedule_steps},
            {"sweeps", so.sweeps_per_temperature},
            {"smart_proposals", so.smart_parent},
            {"smart_gain", so.smart_parent_gain},
            {"min_support", s.mapping.fuse.min_support},
            {"global_sweeps", s.mapping.global_sweeps},
            {"global_chains", s.mapping.global_chains},
            {"sigma_r_shapelet", s.mapping.model.sigma_r_shapelet},
            {"sigma_theta_shapelet", s.mapping.model.sigma_theta_shapelet}}}};
}

// The session's options for the models: the pipeline they were trained with (carried in the
// models file; docs/TRAINING.md) and eq. 12's shapelet sigmas set to the
// classifiers' measured errors (paper Table 1 all whiskers, Fig. 10), as `--sim --sensor-model
// physics` does.
RobotSessionOptions sessionOptions(const signal::SignalModels& models, const MappingOptions& m,
                                   std::uint64_t seed) {
  RobotSessionOptions s;
  s.models = models;
  s.pipeline = models.pipeline;  // the settings the models were trained with
  s.mounts = defaultWhiskerArray();
  s.mapping = m;
  s.mapping.seed = seed;
  s.mapping.progress = nullptr;
  s.mapping.model = withSensorNoise(s.mapping.model, NoiseRegime::classifiers());
  return s;
}

Result<RobotSessionOptions> sessionFromMetadata(const std::string& text, const std::string& src) {
  try {
    const json meta = json::parse(text);
    if (meta.value("schema", "") != kRecordingSchema) {
      return Error{src + ": metadata schema is not " + std::string(kRecordingSchema)};
    }
    auto models = signal::parseModelsJson(meta.at("models").dump(), src + " (models)");
    if (!models) return models.error();
    const json& st = meta.at("settings");
    const std::uint64_t seed = st.at("seed").get<std::uint64_t>();
    RobotSessionOptions s = sessionOptions(models.value(), MappingOptions{}, seed);
    const auto start = st.at("start").get<std::vector<double>>();
    const auto area = st.at("area").get<std::vector<double>>();
    if (start.size() != 3 || area.size() != 4) return Error{src + ": settings.start/area malformed"};
    s.start = {start[0], start[1], start[2]};
    s.area_lo = {area[0], area[1]};
    s.area_hi = {area[2], area[3]};
    s.checksum_includes_header = st.at("checksum_includes_header").get<bool>();
    s.pipeline.detector.min_onset_threshold = st.at("onset_threshold").get<double>();
    const json& mp = st.at("mapping");
    s.mapping.working_memory = mp.at("working_memory").get<int>();
    s.mapping.sampler.schedule_steps = mp.at("schedule_steps").get<int>();
    s.mapping.sampler.sweeps_per_temperature = mp.at("sweeps").get<int>();
    s.mapping.sampler.smart_parent = mp.at("smart_proposals").get<bool>();
    s.mapping.sampler.smart_parent_gain = mp.at("smart_gain").get<double>();
    s.mapping.fuse.min_support = mp.at("min_support").get<int>();
    s.mapping.global_sweeps = mp.at("global_sweeps").get<int>();
    s.mapping.global_chains = mp.at("global_chains").get<int>();
    s.mapping.model.sigma_r_shapelet = mp.at("sigma_r_shapelet").get<double>();
    s.mapping.model.sigma_theta_shapelet = mp.at("sigma_theta_shapelet").get<double>();
    return s;
  } catch (const json::exception& e) {
    return Error{src + ": metadata: " + e.what()};
  }
}

// The map files, each complete or not at all. The "truth" drawn is only the mapped area.
Status writeMapFiles(const Map& map, const RobotSessionOptions& s, const std::string& out_dir,
                     const std::string& title) {
  if (auto st = ensureDirectory(out_dir); !st) return st;
  Scene area;
  area.width = s.area_hi.x();
  area.depth = s.area_hi.y();
  area.source = "robot";
  RenderOptions ropt;
  ropt.title = title;
  if (auto st = writeFileAtomic(out_dir + "/map.json", mapToJson(map)); !st) return st;
  return renderMapPng(map, area, out_dir + "/map.png", ropt);
}

json sessionReport(const RobotSession& session, const Map& map) {
  const auto& d = session.decoderCounters();
  const auto& a = session.assemblerCounters();
  const auto& c = session.counts();
  const auto& e = session.evidenceCounts();
  const auto t = session.tracker().counters();
  std::uint64_t lost = 0, dropped = 0;
  for (const auto& b : d.boards) {
    lost += b.lost_frames;
    dropped += b.dropped_samples;
  }
  const Pose2 p = session.pose();
  json shapelets = json::array();
  for (const Shapelet& sh : map.shapelets) {
    shapelets.push_back({{"x", sh.x}, {"y", sh.y}, {"phi", sh.phi}, {"whisker", sh.whisker},
                         {"pose", sh.pose_index}, {"from", {sh.ox, sh.oy}}});
  }
  return {{"bridge",
           {{"chunks", c.bridge_chunks},
            {"bytes", d.bytes},
            {"frames", d.frames},
            {"crc_failures", d.crc_failures},
            {"bad_version", d.bad_version},
            {"bad_board", d.bad_board},
            {"skipped_bytes", d.skipped_bytes},
            {"lost_frames", lost},
            {"dropped_samples", dropped}}},
          {"samples",
           {{"assembled", a.samples},
            {"gap_placeholders", a.placeholders},
            {"silent_fills", a.silent_fills},
            {"unmapped_frames", a.unmapped_frames}}},
          {"create",
           {{"chunks", c.create_chunks},
            {"packets", t.stream.packets},
            {"checksum_failures", t.stream.checksum_failures},
            {"bad_length_or_id", t.stream.bad_length_or_id},
            {"skipped_bytes", t.stream.skipped_bytes}}},
          {"contacts",
           {{"episodes", c.episodes},
            {"roaming_episodes", c.roaming_episodes},
            {"whisks", c.whisks},
            {"reports", c.reports},
            {"no_radial", e.no_radial},
            {"no_orientation", e.no_orientation}}},
          {"final_pose", {p.x, p.y, p.theta}},
          {"map", {{"tables", map.tables.size()}, {"shapelets", map.stats.shapelets}}},
          {"shapelets", shapelets}};
}

// map.json, map.png, then report.json; stops at the first failure. 0, or 1 with the error said.
int writeOutputs(const Map& map, const RobotSessionOptions& s, const std::string& out_dir,
                 const std::string& title, const json& report, std::ostream& err) {
  Status st = writeMapFiles(map, s, out_dir, title);
  if (st) st = writeFileAtomic(out_dir + "/report.json", report.dump(2) + "\n");
  if (!st) {
    err << "crunchhost: " << st.error().message << "\n";
    return 1;
  }
  return 0;
}

// Writes the running map off the control loop: rendering and the atomic write's fsync can take
// longer than the Create's watchdog allows the loop to stall (measured: a 0.5 s stall under disk
// load stopped the motors and overflowed the ring). post() hands over the newest snapshot; one
// still waiting is replaced (only the newest map matters).
class MapWriter {
 public:
  MapWriter(const RobotSessionOptions& s, std::string out_dir, std::ostream& err)
      : s_(s), out_dir_(std::move(out_dir)), err_(err), thread_([this] { loop(); }) {}
  ~MapWriter() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    cv_.notify_one();
    thread_.join();
  }
  MapWriter(const MapWriter&) = delete;
  MapWriter& operator=(const MapWriter&) = delete;

  void post(Map map) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      pending_ = std::move(map);
    }
    cv_.notify_one();
  }

 private:
  void loop() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
      cv_.wait(lock, [this] { return stop_ || pending_.has_value(); });
      if (stop_) return;
      Map map = std::move(*pending_);
      pending_.reset();
      lock.unlock();
      if (auto st = writeMapFiles(map, s_, out_dir_, "crunchhost --robot (running)"); !st) {
        err_ << "crunchhost: " << st.error().message << "\n";
      }
      lock.lock();
    }
  }

  const RobotSessionOptions& s_;
  std::string out_dir_;
  std::ostream& err_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::optional<Map> pending_;
  bool stop_ = false;
  std::thread thread_;  // last: started once the rest is built
};

}  // namespace

// ------------------------------------------------------------------------------------------
// --robot
// ------------------------------------------------------------------------------------------

int runRobot(const RobotOptions& opt, std::ostream& out, std::ostream& err) {
  const auto t0 = std::chrono::steady_clock::now();
  // ---- Options and models: exit 2, nothing opened, nothing written.
  auto usb_id = io::parseUsbId(opt.usb);
  if (!usb_id) {
    err << "crunchhost: --usb: " << usb_id.error().message << "\n";
    return 2;
  }
  if (!(opt.area_width > 0.5 && opt.area_depth > 0.5 && opt.map_every_s > 0.0 &&
        opt.duration_s >= 0.0 && std::isfinite(opt.start_theta))) {
    err << "crunchhost: --area must be at least 0.5 m each way, --map-every and --duration "
           "positive\n";
    return 2;
  }
  const std::string models_path =
      opt.models_path.empty() ? std::string(CRUNCH_DEFAULT_MODELS) : opt.models_path;
  auto models = signal::loadModels(models_path);
  if (!models) {
    err << "crunchhost: --robot: " << models.error().message << "\n";
    return 2;
  }
  if (auto st = opt.mapping.validate(); !st) {
    err << "crunchhost: mapping options: " << st.error().message << "\n";
    return 2;
  }
  RobotSessionOptions sopt = sessionOptions(models.value(), opt.mapping, opt.seed);
  sopt.area_hi = {opt.area_width, opt.area_depth};
  sopt.start = {opt.start_x < 0.0 ? opt.area_width / 2 : opt.start_x,
                opt.start_y < 0.0 ? opt.area_depth / 2 : opt.start_y, opt.start_theta};
  sopt.checksum_includes_header = opt.checksum_includes_header;
  auto created = RobotSession::create(sopt);
  if (!created) {
    err << "crunchhost: --robot: " << created.error().message << "\n";
    return 2;
  }
  RobotSession& session = *created.value();

  // ---- Devices: both are tried, every missing one is named; exit 3.
  io::SpscRing<io::Chunk> ring(kRingSlots);
  std::mutex state_mutex;
  std::string state_message;
  std::atomic<int> link_events{0};  // bumped by the USB thread on every state change
  std::atomic<bool> link_up{true};
  io::UsbBridge::Options bopt;
  bopt.id = usb_id.value();
  auto on_chunk = [&ring](std::span<const std::uint8_t> bytes, std::uint64_t t_ns) {
    thread_local io::Chunk chunk;  // the USB thread's staging slot: no allocation per chunk
    while (!bytes.empty()) {
      const std::size_t n = chunk.assign(io::StreamId::kBridge, t_ns, bytes);
      (void)ring.tryPush(chunk);  // full: dropped and counted (spsc_ring.h)
      bytes = bytes.subspan(n);
    }
  };
  auto on_state = [&](io::UsbBridge::LinkState s, const std::string& message) {
    {
      std::lock_guard<std::mutex> lock(state_mutex);
      state_message = message;
    }
    link_up.store(s == io::UsbBridge::LinkState::kConnected);
    link_events.fetch_add(1);
  };
  io::CreateBase::Options copt;
  copt.full_mode = opt.create_full_mode;
  copt.checksum_includes_header = opt.checksum_includes_header;
  auto create = io::CreateBase::open(opt.create, copt);
  auto bridge = io::UsbBridge::open(bopt, on_chunk, on_state);
  if (!create || !bridge) {
    if (!bridge) err << "crunchhost: --robot: USB whisker bridge: " << bridge.error().message << "\n";
    if (!create) err << "crunchhost: --robot: Create: " << create.error().message << "\n";
    err << "crunchhost: --robot: nothing was moved. If a device is plugged in but cannot be "
           "opened, install the udev rule tools/udev/99-crunchbot.rules and join the plugdev "
           "and dialout groups (docs/USB.md, docs/CREATE.md)\n";
    return 3;
  }
  io::CreateBase& base = *create.value();
  io::UsbBridge& usb = *bridge.value();

  // ---- Output directory and recording.
  if (auto s = ensureDirectory(opt.out_dir); !s) {
    err << "crunchhost: " << s.error().message << "\n";
    return 1;
  }
  std::unique_ptr<io::RecordingWriter> recorder;
  if (opt.record) {
    json meta = {{"schema", kRecordingSchema},
                 {"crunchhost", "0.1.0"},
                 {"usb", opt.usb},
                 {"create", opt.create},
                 {"models_path", models_path},
                 {"models", json::parse(signal::modelsToJson(models.value()))},
                 {"settings", settingsJson(sopt, opt.seed)}};
    const std::string path =
        opt.record_path.empty() ? opt.out_dir + "/recording.crec" : opt.record_path;
    auto w = io::RecordingWriter::create(path, meta.dump());
    if (!w) {
      err << "crunchhost: " << w.error().message << "\n";
      return 1;
    }
    recorder = std::move(w).value();
    session.setRecorder(recorder.get());
  }

  SignalGuard signals;
  Status failure = okStatus();
  auto fail = [&](const Error& e) {
    if (failure) failure = e;
  };
  base.setByteTap([&](std::span<const std::uint8_t> bytes) {
    io::Chunk chunk;
    const std::uint64_t t = io::monotonicNs();
    while (!bytes.empty()) {
      const std::size_t n = chunk.assign(io::StreamId::kCreate, t, bytes);
      if (auto s = session.handle(chunk); !s) fail(s.error());
      bytes = bytes.subspan(n);
    }
  });
  auto drain = [&] {
    ring.drain([&](const io::Chunk& c) {
      if (auto s = session.handle(c); !s) fail(s.error());
    });
  };
  auto progress = [&](const char* event, const std::string& text) {
    if (opt.json_progress) {
      out << json{{"event", event}, {"t", base.now()}, {"message", text}}.dump() << "\n";
    } else {
      out << "[" << static_cast<int>(base.now()) << " s] " << text << "\n";
    }
    out.flush();
  };

  BodyWhisk::Options wopt;
  wopt.seed = opt.seed;
  // No reverse before the sweep: a whisker meets an object with its tip, at the edge of its
  // reach, and turning in place keeps every point's distance from the robot's centre, so after
  // any reverse the sweep could not touch it again (measured: 0 contacts in 9 whisks with the
  // 3 cm default). Stopping on the contact (~2 mm of push at 0.1 m/s) and sweeping from there
  // is the "pressed start" the orientation models were trained with (docs/TRAINING.md).
  wopt.reverse_distance = 0.0;
  wopt.whisker_bearings.clear();
  for (const WhiskerMount& m : sopt.mounts) wopt.whisker_bearings.push_back(m.bearing);
  BodyWhisk whisk(base, wopt);

  progress("start", "whisker bridge " + opt.usb + " at " + usb.devicePath() + ", Create on " +
                        opt.create + "; calibrating the whiskers at rest");
  enum class Stage { kCalibrating, kRoaming, kPaused } stage = Stage::kCalibrating;
  const double start_s = base.now();
  double next_map_s = start_s + opt.map_every_s;
  double calibrate_since = start_s;
  int seen_events = 0;
  std::uint64_t watchdog_seen = 0;
  std::string stop_reason = "done";
  auto map_writer = std::make_unique<MapWriter>(sopt, opt.out_dir, err);
  while (true) {
    if (const int sig = g_signal.load(); sig != 0) {
      stop_reason = std::string("stopped by ") + signalName(sig);
      break;
    }
    if (opt.duration_s > 0.0 && base.now() - start_s >= opt.duration_s) {
      stop_reason = "--duration reached";
      break;
    }
    if (auto s = base.poll(0.002); !s) {
      fail(s.error());
      stop_reason = "the Create failed";
      break;
    }
    drain();
    if (!failure) {
      stop_reason = "the recording failed";
      break;
    }

    // The bridge's link state, as the USB thread reported it.
    if (const int ev = link_events.load(); ev != seen_events) {
      seen_events = ev;
      std::string message;
      {
        std::lock_guard<std::mutex> lock(state_mutex);
        message = state_message;
      }
      if (!link_up.load()) {
        (void)whisk.halt();
        stage = Stage::kPaused;
        progress("bridge_lost", message + "; robot stopped, keeping " +
                                    std::to_string(session.counts().whisks) +
                                    " whisks; waiting for the bridge to return");
      } else {
        if (auto s = session.bridgeReconnected(io::monotonicNs()); !s) fail(s.error());
        stage = Stage::kCalibrating;  // the detectors need their rest again only if lost
        calibrate_since = base.now();
        progress("bridge_back", message + "; resuming");
      }
    }

    if (stage == Stage::kCalibrating) {
      if (session.calibrated()) {
        stage = Stage::kRoaming;
        if (auto s = whisk.startRoaming(); !s) {
          fail(s.error());
          break;
        }
        progress("roaming", "whiskers calibrated; roaming");
      } else if (base.now() - calibrate_since > opt.calibrate_timeout_s) {
        const std::string within = std::to_string(opt.calibrate_timeout_s) + " s";
        fail(Error{session.counts().samples == 0
                       ? "the whisker bridge " + opt.usb + " sent no whisker samples within " +
                             within + ": are the whisker boards powered and connected to it?"
                       : "the whiskers did not calibrate at rest within " + within +
                             " (a whisker touching something, or a noisy sensor): start the "
                             "robot clear of objects"});
        stop_reason = "whiskers not calibrated";
        break;
      }
    } else if (stage == Stage::kRoaming) {
      const BodyWhisk::Phase before = whisk.phase();
      if (auto s = whisk.update(session.contactMask()); !s) {
        fail(s.error());
        stop_reason = "the Create refused a command";
        break;
      }
      // The sweep's contacts are the whisk's own (robot_session.h), from the toward leg on;
      // they form one group once the robot has backed clear of the object.
      if (before == BodyWhisk::Phase::kForward && whisk.phase() != BodyWhisk::Phase::kForward) {
        const Pose2 q = session.pose();
        const std::string at = "at (" + std::to_string(q.x) + ", " + std::to_string(q.y) + ", " +
                               std::to_string(q.theta) + ")";
        if (whisk.phase() == BodyWhisk::Phase::kBumpBackOff) {
          progress("bump", "bumper " + at + ": backing off and turning");
        } else {
          progress("contact", "contact (whiskers " + std::to_string(session.contactMask()) +
                                  ") " + at + ": whisking");
        }
      }
      if (whisk.phase() == BodyWhisk::Phase::kToward && before != BodyWhisk::Phase::kToward) {
        if (auto s = session.beginWhisk(io::monotonicNs()); !s) fail(s.error());
      }
      if (whisk.phase() == BodyWhisk::Phase::kTurn && before != BodyWhisk::Phase::kTurn) {
        if (auto s = session.endWhisk(io::monotonicNs()); !s) fail(s.error());
        progress("whisk", "whisk " + std::to_string(session.counts().whisks) + ": " +
                              std::to_string(session.counts().reports) + " reports so far");
      }
    }

    if (base.now() >= next_map_s) {
      next_map_s += opt.map_every_s;
      map_writer->post(session.snapshot());
    }
    // The driver's watchdog stopped the motors (this loop stalled): say so and drive again.
    if (const std::uint64_t stops = base.watchdogStops(); stops != watchdog_seen) {
      watchdog_seen = stops;
      whisk.commandLost();
      progress("watchdog", "the control loop stalled; the Create's watchdog stopped the motors; "
                           "resuming");
    }
  }

  // ---- Shut down in order: motors, USB, the last chunks, the recording, the map.
  (void)whisk.halt();
  map_writer.reset();  // waits for a write in progress; the final map is written below
  (void)base.stop();
  usb.stop();
  drain();
  const Map map = session.finish();
  if (recorder) {
    if (auto s = recorder->close(); !s) fail(s.error());
  }
  json report = sessionReport(session, map);
  report["mode"] = "robot";
  report["stop"] = stop_reason;
  report["wall_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  report["ring"] = {{"capacity", ring.capacity()},
                    {"pushed", ring.pushed()},
                    {"dropped", ring.dropped()},
                    {"high_water", ring.highWater()}};
  report["usb"] = {{"transfers", usb.transfersCompleted()},
                   {"bytes", usb.bytes()},
                   {"transfer_errors", usb.transferErrors()},
                   {"disconnects", usb.disconnects()},
                   {"reconnects", usb.reconnects()}};
  report["create_watchdog_stops"] = base.watchdogStops();
  if (recorder) report["recording"] = recorder->path();
  if (!failure) report["error"] = failure.error().message;
  if (writeOutputs(map, sopt, opt.out_dir, "crunchhost --robot, seed " + std::to_string(opt.seed),
                   report, err) != 0) {
    return 1;
  }
  progress("done", stop_reason + ": " + std::to_string(session.counts().whisks) + " whisks, " +
                       std::to_string(map.stats.shapelets) + " shapelets, " +
                       std::to_string(map.tables.size()) + " tables; wrote " + opt.out_dir +
                       "/{map.json,map.png,report.json}" +
                       (recorder ? " and " + recorder->path() : std::string()));
  if (!failure) {
    err << "crunchhost: --robot: " << failure.error().message << "\n";
    return 3;
  }
  return 0;
}

// ------------------------------------------------------------------------------------------
// --replay
// ------------------------------------------------------------------------------------------

int runReplay(const ReplayOptions& opt, std::ostream& out, std::ostream& err) {
  const auto t0 = std::chrono::steady_clock::now();
  auto reader = io::RecordingReader::open(opt.recording);
  if (!reader) {
    err << "crunchhost: --replay: " << reader.error().message << "\n";
    return 2;
  }
  auto sopt = sessionFromMetadata(reader.value()->metadata(), "recording " + opt.recording);
  if (!sopt) {
    err << "crunchhost: --replay: " << sopt.error().message << "\n";
    return 2;
  }
  auto created = RobotSession::create(sopt.value());
  if (!created) {
    err << "crunchhost: --replay: " << created.error().message << "\n";
    return 2;
  }
  RobotSession& session = *created.value();
  io::Chunk chunk;
  io::RecordingReader::Next next;
  while ((next = reader.value()->next(chunk)) == io::RecordingReader::Next::kRecord) {
    (void)session.handle(chunk);  // no recorder: cannot fail
  }
  const bool damaged = next == io::RecordingReader::Next::kDamaged;
  const Map map = session.finish();
  json report = sessionReport(session, map);
  report["mode"] = "replay";
  report["recording"] = opt.recording;
  report["records"] = reader.value()->records();
  report["wall_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (damaged) report["damage"] = reader.value()->damage();
  if (writeOutputs(map, sopt.value(), opt.out_dir, "crunchhost --replay " + opt.recording, report,
                   err) != 0) {
    return 1;
  }
  if (opt.json_progress) {
    out << json{{"event", "done"},
                {"records", reader.value()->records()},
                {"tables", map.tables.size()},
                {"damaged", damaged}}
               .dump()
        << "\n";
  } else {
    out << "replayed " << reader.value()->records() << " records of " << opt.recording << ": "
        << session.counts().whisks << " whisks, " << map.stats.shapelets << " shapelets, "
        << map.tables.size() << " tables; wrote " << opt.out_dir
        << "/{map.json,map.png,report.json}\n";
  }
  if (damaged) {
    err << "crunchhost: --replay: " << reader.value()->damage()
        << "; replayed up to the damage\n";
    return 3;
  }
  return 0;
}

}  // namespace crunch::app
