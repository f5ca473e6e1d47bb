// The sensing chain (paper §2.1-2.5, §2.8): whisker-bridge bytes in, what each body whisk tells
// the mapper out. One piece of code for every source of bytes (ARCHITECTURE.md §2, "One path,
// three sources"): RobotSession runs it for `--robot` and `--replay`, the simulator's physics
// path (sim::WhiskerRig, sim::PhysicsSensorModel) feeds it its virtual boards' bytes.
//
//   bridge bytes --> io::BridgeStreamDecoder --> io::SampleAssembler --> signal::SignalPipeline
//        + the pose the caller gives with them                              | episodes
//                                                                           v
//   beginWhisk() / endWhisk() ------------------------------------> WhiskEvidence: reports,
//                                                                     free rays per whisk
//
// Poses: the chain does not know where the robot is; the caller's pose source does (RobotSession:
// the odometry integrated from the Create's OI bytes; the simulator: its exact pose, §2.8). Every
// pipeline sample that a feed() completes is stamped with the pose given with those bytes, and
// kept in a ring of kPoseHistory samples, from which the reports take the pose at an episode's
// first contact and at each whisker's peak (WhiskEvidence::take).
//
// Which contacts are reported: the episodes that end while a whisk is open (beginWhisk() ..
// endWhisk()) — the body whisk's own, including the episode of the contact that started it,
// which the sweep continues (beginWhisk() forgets only the reports taken before it). Episodes that
// end outside a whisk are counted (SensingCounts::roaming_episodes), not reported: the radial
// model was trained on sweeps, not on pushes.
//
// Negative evidence, at all times, not only during whisks: every WhiskEvidence::kFreeEvery
// pipeline samples (counted from the pipeline's first sample) the pose of that sample and the
// whiskers in contact over the kFreeEvery samples that follow are one WhiskEvidence::sample();
// endWhisk() turns the samples taken since the previous endWhisk() into free rays (WhiskEvidence
// applies the +-kFreeGuard contact guard). A whisker whose detector is not ready (lost to a
// clamped sensor or a silent board, or calibrating) counts as in contact: it cannot say free. The sample being accumulated at endWhisk() goes to the
// next whisk.
//
// Ownership: owns every stage. Thread-safety: none; one control loop (or replay, or simulator
// thread) owns a chain. Allocation: create() allocates the pose history; feed() allocates nothing
// once warm (the evidence's buffers have grown to a whisk's worth after the first whisks).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/core/result.h"
#include "crunch/io/bridge_stream.h"
#include "crunch/io/sample_assembler.h"
#include "crunch/robot/shapelet.h"
#include "crunch/robot/whisker_beam.h"
#include "crunch/session/whisk_evidence.h"
#include "crunch/signal/pipeline.h"

namespace crunch::session {

// Pipeline samples of pose history: 32.8 s at 2 kHz, more than any episode may last.
inline constexpr std::size_t kPoseHistory = std::size_t{1} << 16;

struct SensingChainOptions {
  signal::PipelineOptions pipeline;
  std::vector<WhiskerMount> mounts;  // the four horizontal whiskers, whisker w on board w
  WhiskerBeam beam;                  // their mechanics (contacts are located with it)
  Pose2 start;                       // the pose of every sample before the first feed()

  // kWhiskers mounts; pipeline.validate() (errors prefixed "pipeline: "); max_episode_samples
  // below kPoseHistory. okStatus(), or an Error naming the first bad field.
  Status validate() const;
};

struct SensingCounts {
  std::uint64_t samples = 0;           // SampleFrames fed to the pipeline
  std::uint64_t episodes = 0;          // contact episodes that ended within a whisk
  std::uint64_t roaming_episodes = 0;  // contact episodes that ended outside a whisk
  int whisks = 0;                      // endWhisk() calls
  int reports = 0;                     // contact reports handed out by endWhisk()
};

class SensingChain {
 public:
  // Errors: bad options (validate()), the pipeline's own.
  static Result<std::unique_ptr<SensingChain>> create(const SensingChainOptions& options);
  SensingChain(const SensingChain&) = delete;
  SensingChain& operator=(const SensingChain&) = delete;

  // The radial and orientation models (signal::SignalPipeline::setModels). Without them the
  // chain detects episodes but gives no reports (training collects its data so).
  Status setModels(const signal::SignalModels& models);

  // Decodes `bytes` (the next part of the bridge stream) handled with the robot at `pose`. Every
  // episode that ends is first taken (whisk open) or counted (roaming), then passed to
  // on_episode(const signal::ContactEpisode&); the reference is valid during that call only.
  template <typename OnEpisode>
  void feed(std::span<const std::uint8_t> bytes, const Pose2& pose, OnEpisode&& on_episode) {
    decoder_.feed(bytes, [&](const io::DecodedFrame& d) {
      assembler_.push(d, [&](const signal::SampleFrame& f) {
        if (const signal::ContactEpisode* ep = onSample(f, pose)) on_episode(*ep);
      });
    });
  }
  void feed(std::span<const std::uint8_t> bytes, const Pose2& pose) {
    feed(bytes, pose, [](const signal::ContactEpisode&) {});
  }

  // Opens a whisk: forgets the reports taken so far (contacts that were not this whisk's), keeps
  // the negative-evidence samples and the episode in progress.
  void beginWhisk();
  // Ends the episode in progress now, if any (signal::SignalPipeline::finish()), and takes or
  // counts it as feed() does. Returns it (valid until the next feed()), or nullptr.
  const signal::ContactEpisode* endEpisode();
  // Ends the whisk (also when none is open): endEpisode(), then appends the whisk's reports to
  // `reports` and its free rays to `free_rays`, and starts collecting the next whisk's.
  void endWhisk(std::vector<ContactReport>& reports, std::vector<FreeRay>& free_rays);
  // The bridge was replugged: forgets partial frames, per-board baselines and queued readings.
  void reconnect();

  bool inWhisk() const { return in_whisk_; }
  // Bit w set while whisker w's detector is in contact (what the behaviour acts on).
  std::uint32_t contactMask() const;
  // Bit w set while whisker w's detector is not ready (lost, calibrating): it cannot say free.
  std::uint32_t unreadyMask() const;
  // The pipeline's detectors have calibrated their rest (the robot may move).
  bool calibrated() const;
  // Bit w set when whisker w has a report (maybe without r or phi) in the open whisk.
  std::uint32_t reportedMask() const;
  // The pose stamped on pipeline sample `index`; meaningful for the last kPoseHistory samples.
  Pose2 poseAtSample(std::uint64_t index) const { return pose_history_[index % kPoseHistory]; }

  const signal::SignalPipeline& pipeline() const { return pipeline_; }
  const WhiskEvidence& evidence() const { return evidence_; }
  const SensingCounts& counts() const { return counts_; }
  const io::BridgeStreamCounters& decoderCounters() const { return decoder_.counters(); }
  const io::SampleAssembler::Counters& assemblerCounters() const { return assembler_.counters(); }
  const std::vector<WhiskerMount>& mounts() const { return evidence_.mounts(); }
  // The models' tip zone, metres from the tip (WhiskEvidence: a report within it is a tip contact).
  double tipZone() const { return evidence_.tipZone(); }

 private:
  SensingChain(const SensingChainOptions& options, signal::SignalPipeline pipeline);
  // One assembled sample: pose history, pipeline, negative-evidence sampling. Returns the
  // episode it ended (already taken or counted), or nullptr.
  const signal::ContactEpisode* onSample(const signal::SampleFrame& frame, const Pose2& pose);
  void takeEpisode(const signal::ContactEpisode& episode);

  io::BridgeStreamDecoder decoder_;
  io::SampleAssembler assembler_;
  signal::SignalPipeline pipeline_;
  WhiskEvidence evidence_;
  std::vector<Pose2> pose_history_;  // ring: the pose of pipeline sample i at i % kPoseHistory
  Pose2 free_pose_;                  // the negative-evidence sample being accumulated
  std::uint32_t free_mask_ = 0;
  bool in_whisk_ = false;
  SensingCounts counts_;
};

}  // namespace crunch::session
