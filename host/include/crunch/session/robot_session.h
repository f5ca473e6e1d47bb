// The data path of `crunchhost --robot` and `crunchhost --replay` (paper §2.1-2.8), one input
// chunk at a time and in the order the control loop handled them:
//
//   bridge bytes --> SensingChain (decoder, assembler, signal pipeline, WhiskEvidence)
//                          ^ pose per bridge chunk                  | reports, free rays
//   Create bytes --> io::oi::SensorTracker (odometry, bumpers)      |   per whisk
//   whisk marks -----------------------------------------------------+--> Mapper (blackboard)
//
// RobotSession = SensingChain (sensing_chain.h, which the simulator's physics path runs too) +
// the odometry tracker as its pose source + the Mapper + the recorder.
//
// Live, the control loop hands each chunk to handle() as it reads it — the USB chunks out of the
// SPSC ring, the Create's bytes from the driver's byte tap, a mark when a body whisk ends — and
// handle() records it first. A replay reads the same records from the file and hands them to
// handle() in the same order, so every decoder, parser, pipeline and sampler state — and the
// map — comes out the same.
//
// Which contacts are reported: the episodes that end between a kWhiskStart mark (the toward
// leg begins: SensingChain::beginWhisk) and the kWhiskEnd mark (SensingChain::endWhisk) — the
// body whisk's own, including the episode of the contact that started it, which the sweep
// continues (the robot stops on the contact and whisks without reversing: see
// roamingWhiskOptions in session/controller.h).
// Episodes that end outside a whisk (a whisker brushing something while the robot drives or
// turns) are counted (RobotSessionCounts::roaming_episodes) and not reported: the radial model
// was trained on sweeps, not on pushes. Rays swept free count at all times (negative evidence).
//
// Poses: the map frame is the one the robot started in, placed at Options::start. Each pipeline
// sample gets the odometry of its own moment: the samples wait in the chain's queue
// (SensingChain::feedTimed) until the Create's packets after them have arrived, and take the
// pose OdometryTrack interpolates between the packets' whole-degree steps (odometry_track.h;
// the chunks' arrival times, t_ns, are the clock). A mark first releases the samples up to its
// time. The behaviour acts on the chain's live detectors (contactMask()), which do not wait.
//
// Ownership: owns every stage; the recorder, if set, is not owned. Thread-safety: none; the
// control loop (or the replay) owns a session. Allocation: handle() of bridge and Create chunks
// allocates nothing once the run is warm (the chain's pose history is allocated at create()); a
// whisk's end allocates the mapper's new shapelets and per-pose MAP.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "crunch/core/result.h"
#include "crunch/io/bridge_stream.h"
#include "crunch/io/create_oi.h"
#include "crunch/io/recording.h"
#include "crunch/io/sample_assembler.h"
#include "crunch/mapping/mapper.h"
#include "crunch/session/odometry_track.h"
#include "crunch/session/sensing_chain.h"
#include "crunch/session/whisk_evidence.h"
#include "crunch/signal/pipeline.h"

namespace crunch::session {

struct RobotSessionOptions {
  signal::SignalModels models;
  signal::PipelineOptions pipeline;
  std::vector<WhiskerMount> mounts;  // the four horizontal whiskers, whisker w on board w
  MappingOptions mapping;
  Pose2 start;             // where the robot starts, in the map frame
  Vec2 area_lo{0.0, 0.0};  // the region it maps (the negative-evidence grid's extent)
  Vec2 area_hi{6.0, 6.0};
  bool checksum_includes_header = true;  // the Create 1's checksum quirk (io/create_oi.h)
  // The area's edges are the room's walls: the mapper is told no leg stands beyond them
  // (MappingOptions::room; mapping.room itself is ignored: the area is the room). Recordings
  // from before it was recorded: false.
  bool room_bounds = true;

  // The sensing chain's options (SensingChainOptions::validate: kWhiskers mounts,
  // pipeline.validate() prefixed "pipeline: "); mapping.validate() (prefixed "mapping: "); a
  // finite start; an area with finite corners, 0.5..kMaxAreaSide m each way
  // (the negative-evidence grid has a 1 cm cell: 50 m is 50 MB). okStatus(), or an Error naming
  // the first bad field. RobotSession::create calls it.
  Status validate() const;
};

inline constexpr double kMaxAreaSide = 50.0;  // metres

struct RobotSessionCounts {
  std::uint64_t bridge_chunks = 0, create_chunks = 0, marks = 0;
  std::uint64_t samples = 0;   // SampleFrames fed to the pipeline
  std::uint64_t episodes = 0;  // contact episodes within whisks (reported from)
  std::uint64_t roaming_episodes = 0;  // contact episodes outside a whisk's sweep (not reported)
  int whisks = 0;              // groups handed to the mapper
  int reports = 0;             // contact reports handed to the mapper
};

class RobotSession {
 public:
  // Errors: the models do not fit the pipeline (signal::SignalPipeline::setModels), bad options.
  static Result<std::unique_ptr<RobotSession>> create(const RobotSessionOptions& options);
  RobotSession(const RobotSession&) = delete;
  RobotSession& operator=(const RobotSession&) = delete;

  // Records the chunk to `recorder` (if set), then processes it. An Error is the recorder's.
  Status handle(const io::Chunk& chunk);
  // Write and handle a kWhiskStart / kWhiskEnd mark now (live).
  Status beginWhisk(std::uint64_t t_ns) { return mark(io::MarkKind::kWhiskStart, t_ns); }
  Status endWhisk(std::uint64_t t_ns) { return mark(io::MarkKind::kWhiskEnd, t_ns); }
  // Every chunk handled from now on is recorded first (nullptr: none).
  void setRecorder(io::RecordingWriter* recorder) { recorder_ = recorder; }

  // Bit w set while whisker w's detector is in contact (what the behaviour acts on: the chain's
  // live detectors, not waiting for the pose).
  std::uint32_t contactMask() const { return chain_->liveContactMask(); }
  // The odometry pose in the map frame.
  Pose2 pose() const;
  bool bumped() const { return tracker_.bumped(); }
  // The pipeline's detectors have calibrated their rest (the robot may move).
  bool calibrated() const { return chain_->liveCalibrated(); }
  // The odometry pose at t_ns (CLOCK_MONOTONIC, as the chunks' t_ns), map frame, interpolated
  // between the Create's packets (odometry_track.h); the pose now before any packet.
  Pose2 poseAt(std::uint64_t t_ns) const;
  const OdometryTrack& track() const { return track_; }

  // The map so far (no random draws) and the final one (call once, after the last chunk: ends
  // an open whisk first).
  Map snapshot() const { return mapper_.snapshot(); }
  Map finish();
  // Posterior draws of the map so far, for the exploring robot (Mapper::drawSamples: its own
  // random stream, so the map does not depend on them).
  void drawSamples(int n, double beta, int sweeps_between, std::vector<MapSample>& out) {
    mapper_.drawSamples(n, beta, sweeps_between, out);
  }
  // The same a slice at a time (Mapper::continueSamples): true once the n draws are in `out`.
  bool continueSamples(int n, double beta, int sweeps_between, std::vector<MapSample>& out,
                       int max_sweeps) {
    return mapper_.continueSamples(n, beta, sweeps_between, out, max_sweeps);
  }
  // The rays the whiskers swept free during the last whisk handed to the mapper.
  const std::vector<FreeRay>& lastFreeRays() const { return free_rays_; }
  // The contact reports of the last whisk handed to the mapper (the CSV export's contacts).
  const std::vector<ContactReport>& lastReports() const { return reports_; }
  const RobotSessionOptions& options() const { return options_; }

  const RobotSessionCounts& counts() const { return counts_; }
  const io::BridgeStreamCounters& decoderCounters() const { return chain_->decoderCounters(); }
  const io::SampleAssembler::Counters& assemblerCounters() const {
    return chain_->assemblerCounters();
  }
  const io::oi::SensorTracker& tracker() const { return tracker_; }
  const WhiskEvidence::Counts& evidenceCounts() const { return chain_->evidence().counts(); }
  const SensingChain& chain() const { return *chain_; }
  // Writes and handles a kBridgeReconnected mark: forgets partial frames, per-board baselines
  // and queued readings (the bridge was replugged).
  Status bridgeReconnected(std::uint64_t t_ns);

 private:
  RobotSession(const RobotSessionOptions& options, std::unique_ptr<SensingChain> chain);
  Status mark(io::MarkKind kind, std::uint64_t t_ns);
  void closeWhisk();
  void syncCounts();
  void feedCreate(const io::Chunk& chunk);
  void sweepBody(bool to_end);
  std::uint64_t settledUntil() const;

  static constexpr std::uint64_t kStreamPeriodNs = 15000000;  // the Create's stream, 15 ms
  // The body's sweep (Mapper::addBodySweep) is added in steps of this many metres of odometry.
  static constexpr double kSweepStep = 0.05;

  RobotSessionOptions options_;
  io::RecordingWriter* recorder_ = nullptr;
  std::unique_ptr<SensingChain> chain_;
  io::oi::SensorTracker tracker_;
  OdometryTrack track_;
  std::array<std::int64_t, 64> packet_totals_{};  // one Create chunk's packets (feedCreate)
  std::array<Pose2, 64> packet_poses_{};
  Mapper mapper_;
  std::optional<Vec2> swept_to_;  // where the body's sweep has reached
  std::vector<ContactReport> reports_;
  std::vector<FreeRay> free_rays_;
  RobotSessionCounts counts_;
};

}  // namespace crunch::session
