#include "crunch/session/controller.h"

#include <cstdio>

#include <utility>

#include "crunch/core/range_check.h"

namespace crunch::session {

void LinkMonitor::report(bool up, std::string message) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    latest_.up = up;
    latest_.message = std::move(message);
  }
  events_.fetch_add(1, std::memory_order_release);
}

std::optional<LinkMonitor::Event> LinkMonitor::take() {
  const int events = events_.load(std::memory_order_acquire);
  if (events == seen_) return std::nullopt;  // the loop's usual case: no lock taken
  seen_ = events;
  std::lock_guard<std::mutex> lock(mutex_);
  return latest_;
}

BodyWhisk::Options roamingWhiskOptions(std::uint64_t seed,
                                       const std::vector<WhiskerMount>& mounts) {
  BodyWhisk::Options o;
  o.seed = seed;
  o.reverse_distance = 0.0;  // no reverse before the sweep: see the header
  o.whisker_bearings.clear();
  for (const WhiskerMount& m : mounts) o.whisker_bearings.push_back(m.bearing);
  return o;
}

Status ControllerOptions::validate() const {
  const Status checks[] = {checkRange("duration_s", duration_s, 0.0, 1e7),
                           checkAbove("map_every_s", map_every_s, 0.0, 1e7),
                           checkAbove("calibrate_timeout_s", calibrate_timeout_s, 0.0, 1e7),
                           checkRange("poll_timeout_s", poll_timeout_s, 0.0, 1.0),
                           within("whisk", whisk.validate()),
                           explore ? within("explore", explore->validate()) : okStatus()};
  for (const Status& s : checks) {
    if (!s) return s;
  }
  return okStatus();
}

Result<std::unique_ptr<RobotController>> RobotController::create(MobileBase& base,
                                                                 RobotSession& session,
                                                                 const ControllerOptions& options,
                                                                 ControllerSources sources,
                                                                 EventSink events) {
  if (auto s = options.validate(); !s) return s.error();
  return std::unique_ptr<RobotController>(
      new RobotController(base, session, options, std::move(sources), std::move(events)));
}

RobotController::RobotController(MobileBase& base, RobotSession& session,
                                 const ControllerOptions& options, ControllerSources sources,
                                 EventSink events)
    : base_(base),
      session_(session),
      options_(options),
      sources_(std::move(sources)),
      events_(std::move(events)),
      whisk_(base, options.whisk),
      frame_base_(base, session),
      sink_([this](const io::Chunk& c) {
        if (auto s = session_.handle(c); !s) fail(s.error());
      }) {
  if (options_.explore) {
    const RobotSessionOptions& so = session_.options();
    known_ = std::make_unique<exploration::KnownSpace>(so.area_lo, so.area_hi,
                                                       options_.explore->explore.cell);
    policy_ = exploration::makePolicy(options_.explore->explore.policy,
                                      options_.explore->explore.policy_options);
  }
}

void RobotController::fail(const Error& error) {
  if (failure_) failure_ = error;
}

bool RobotController::end(const std::string& reason) {
  stop_reason_ = reason;
  // The exploring loop's report closes with the run's reason (its time, mean decision time);
  // a loop that ended by itself keeps its own.
  if (explore_) explore_->finish(reason);
  stage_ = Stage::kStopped;
  return false;
}

void RobotController::stop(const std::string& reason) { (void)end(reason); }

void RobotController::emit(const char* name, const std::string& message) {
  if (events_) events_(ControllerEvent{name, base_.now(), message});
}

std::uint64_t RobotController::nowNs() const {
  return sources_.clock_ns ? sources_.clock_ns() : io::monotonicNs();
}

void RobotController::start(const std::string& what) {
  emit("start", what + "; calibrating the whiskers at rest");
  stage_ = Stage::kCalibrating;
  start_s_ = base_.now();
  next_map_s_ = start_s_ + options_.map_every_s;
  calibrate_since_ = start_s_;
}

void RobotController::handleBaseBytes(std::span<const std::uint8_t> bytes) {
  const std::uint64_t t = nowNs();
  while (!bytes.empty()) {
    const std::size_t n = base_chunk_.assign(io::StreamId::kCreate, t, bytes);
    sink_(base_chunk_);
    bytes = bytes.subspan(n);
  }
}

void RobotController::drainBridge() {
  if (sources_.drain_bridge) sources_.drain_bridge(sink_);
}

void RobotController::stopMotion() {
  (void)whisk_.halt();
  (void)base_.stop();
}

bool RobotController::step() {
  if (stage_ == Stage::kStopped) return false;
  if (options_.duration_s > 0.0 && base_.now() - start_s_ >= options_.duration_s) {
    return end("--duration reached");
  }
  if (sources_.poll_base) {
    if (auto s = sources_.poll_base(options_.poll_timeout_s); !s) {
      fail(s.error());
      return end("the Create failed");
    }
  }
  drainBridge();
  // A recording write failed in the byte tap, the drain, or a mark of the last step.
  if (!failure_) return end("the recording failed");

  if (sources_.link != nullptr) {
    if (auto event = sources_.link->take()) onLinkEvent(*event);
  }
  if (stage_ == Stage::kCalibrating) {
    if (!calibrating()) return false;
  } else if (stage_ == Stage::kRoaming) {  // not in the step that ended the calibration
    if (!roaming()) return false;
  } else if (stage_ == Stage::kExploring) {
    if (!exploring()) return false;
  }

  if (base_.now() >= next_map_s_) {
    next_map_s_ += options_.map_every_s;
    if (sources_.map) sources_.map(session_.snapshot());
  }
  // The base's watchdog stopped the motors (this loop stalled): say so and drive again.
  if (sources_.watchdog_stops) {
    if (const std::uint64_t stops = sources_.watchdog_stops(); stops != watchdog_seen_) {
      watchdog_seen_ = stops;
      whisk_.commandLost();
      if (explore_) explore_->commandLost();
      emit("watchdog",
           "the control loop stalled; the Create's watchdog stopped the motors; resuming");
    }
  }
  return true;
}

void RobotController::onLinkEvent(const LinkMonitor::Event& event) {
  if (!event.up) {
    (void)whisk_.halt();
    stage_ = Stage::kPaused;
    emit("bridge_lost", event.message + "; robot stopped, keeping " +
                            std::to_string(session_.counts().whisks) +
                            " whisks; waiting for the bridge to return");
  } else {
    if (auto s = session_.bridgeReconnected(nowNs()); !s) fail(s.error());
    stage_ = Stage::kCalibrating;  // the detectors need their rest again only if lost
    calibrate_since_ = base_.now();
    emit("bridge_back", event.message + "; resuming");
  }
}

bool RobotController::calibrating() {
  if (session_.calibrated() && options_.explore) {
    stage_ = Stage::kExploring;
    if (explore_) {
      explore_->commandLost();  // the pause stopped the base: send the command again
      emit("exploring", "whiskers calibrated; exploring again");
      return true;
    }
    startExploring();
    std::string message = "whiskers calibrated; exploring with the ";
    message += exploration::explorePolicyName(options_.explore->explore.policy);
    message += " policy";
    emit("exploring", message);
  } else if (session_.calibrated()) {
    stage_ = Stage::kRoaming;
    if (auto s = whisk_.startRoaming(); !s) {
      fail(s.error());
      return end("the Create refused a command");
    }
    emit("roaming", "whiskers calibrated; roaming");
  } else if (base_.now() - calibrate_since_ > options_.calibrate_timeout_s) {
    const std::string within = std::to_string(options_.calibrate_timeout_s) + " s";
    fail(Error{session_.counts().samples == 0
                   ? options_.bridge + " sent no whisker samples within " + within +
                         ": are the whisker boards powered and connected to it?"
                   : "the whiskers did not calibrate at rest within " + within +
                         " (a whisker touching something, or a noisy sensor): start the "
                         "robot clear of objects"});
    return end("whiskers not calibrated");
  }
  return true;
}

bool RobotController::roaming() {
  const BodyWhisk::Phase before = whisk_.phase();
  if (auto s = whisk_.update(session_.contactMask()); !s) {
    fail(s.error());
    return end("the Create refused a command");
  }
  const BodyWhisk::Phase now = whisk_.phase();
  if (before == BodyWhisk::Phase::kForward && now != BodyWhisk::Phase::kForward) {
    const Pose2 q = session_.pose();
    const std::string at = "at (" + std::to_string(q.x) + ", " + std::to_string(q.y) + ", " +
                           std::to_string(q.theta) + ")";
    if (now == BodyWhisk::Phase::kBumpBackOff) {
      emit("bump", "bumper " + at + ": backing off and turning");
    } else {
      emit("contact", "contact (whiskers " + std::to_string(session_.contactMask()) + ") " + at +
                          ": whisking");
    }
  }
  // The sweep's contacts are the whisk's own (robot_session.h), from the toward leg on; they
  // form one group once the robot has backed clear of the object.
  if (now == BodyWhisk::Phase::kToward && before != BodyWhisk::Phase::kToward) {
    if (auto s = session_.beginWhisk(nowNs()); !s) fail(s.error());
  }
  if (now == BodyWhisk::Phase::kTurn && before != BodyWhisk::Phase::kTurn) {
    if (auto s = session_.endWhisk(nowNs()); !s) fail(s.error());
    emit("whisk", "whisk " + std::to_string(session_.counts().whisks) + ": " +
                      std::to_string(session_.counts().reports) + " reports so far");
  }
  return true;
}

namespace {
// Sweeps of the exploring robot's sample chain per control step while a decision's posterior
// draws are made (Mapper::continueSamples): one sweep over the whole run's hypotheses is a few
// milliseconds, well inside the Create's 0.5 s watchdog and the USB ring's slack.
constexpr int kDecisionSweepsPerStep = 1;

std::string poseText(const Pose2& q) {
  char text[96];
  std::snprintf(text, sizeof text, "(%.3f, %.3f, %.3f)", q.x, q.y, q.theta);
  return text;
}
}  // namespace

void RobotController::startExploring() {
  const ExploreLoop::Options& o = *options_.explore;
  ExploreLoop::Hooks hooks;
  hooks.whisked = [this](const Pose2& pose) { onWhisked(pose); };
  // The draws take a slice of the chain's sweeps per control step: all at once they took
  // 0.5-1 s late in a 20 m run (the Create's watchdog stopped it after every decision and the
  // USB ring overflowed, docs/ROBOT.md).
  hooks.samples = [this, beta = o.explore.sample_beta, sweeps = o.explore.sample_sweeps](
                      int n, std::vector<MapSample>& out) {
    return session_.continueSamples(n, beta, sweeps, out, kDecisionSweepsPerStep);
  };
  // No bump_point: the Create's bumper switches say only which side hit something (the loop
  // takes the expected point for those switches, robot/bumper.h).
  explore_ = std::make_unique<ExploreLoop>(frame_base_, *known_, *policy_, session_.options().mounts,
                                           session_.options().mapping.model,
                                           std::vector<Pose2>{}, o, std::move(hooks));
}

bool RobotController::exploring() {
  const int bumps = explore_->report().bumps;
  if (auto s = explore_->update(session_.contactMask()); !s) {
    fail(s.error());
    return end("the Create refused a command");
  }
  if (explore_->report().bumps != bumps) {
    emit("bump", "bumper at " + poseText(session_.pose()) + ": backing off and replanning");
  }
  const std::optional<Pose2>& goal = explore_->goal();
  if (goal && (!announced_goal_ || announced_goal_->x != goal->x || announced_goal_->y != goal->y ||
               announced_goal_->theta != goal->theta)) {
    announced_goal_ = goal;
    std::string message = "the ";
    message += exploration::explorePolicyName(options_.explore->explore.policy);
    message += " policy chose the whisk pose ";
    message += poseText(*goal);
    ControllerEvent e{"goal", base_.now(), std::move(message), *goal};
    if (events_) events_(e);
  }
  // The loop's in-place whisk (at a goal, or where a whisker touched on the way) is one group
  // for the mapper: opened here when it begins, closed by onWhisked when it ends.
  const ExploreLoop::Phase phase = explore_->phase();
  const bool whisking = phase == ExploreLoop::Phase::kWhisk ||
                        phase == ExploreLoop::Phase::kTouchWhisk;
  if (whisking && !whisk_open_) {
    whisk_open_ = true;
    if (auto s = session_.beginWhisk(nowNs()); !s) fail(s.error());
  }
  if (explore_->finished()) return end("exploration ended: " + explore_->report().stop_reason);
  return true;
}

void RobotController::onWhisked(const Pose2& pose) {
  if (!whisk_open_) return;  // a whisk the loop began in the same update: opened below it
  whisk_open_ = false;
  if (auto s = session_.endWhisk(nowNs()); !s) fail(s.error());
  for (const FreeRay& r : session_.lastFreeRays()) known_->markFreeRay(r);
  const Map snap = session_.snapshot();
  for (std::size_t i = contacts_known_; i < snap.shapelets.size(); ++i) {
    known_->markContact({snap.shapelets[i].x, snap.shapelets[i].y});
  }
  contacts_known_ = snap.shapelets.size();
  known_->setMapObstacles(snap.tables, snap.walls);
  ControllerEvent e{"whisk", base_.now(),
                    "whisk " + std::to_string(session_.counts().whisks) + " at " + poseText(pose) +
                        ": " + std::to_string(session_.counts().reports) + " reports so far",
                    pose};
  if (events_) events_(e);
}

}  // namespace crunch::session
