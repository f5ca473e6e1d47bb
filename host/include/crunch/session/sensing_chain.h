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
// first contact and at each whisker's peak (WhiskEvidence::take). A pose source that knows a
// moment's pose only later (the robot's odometry, between the Create's packets) uses
// feedTimed() / release() instead: samples wait in a queue with their time, the behaviour's
// contact mask comes from live detectors that do not wait.
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
// thread) owns a chain. Allocation: create() allocates the pose history and the timed queue; feed() allocates nothing
// once warm (the evidence's buffers have grown to a whisk's worth after the first whisks).
#pragma once

#include <algorithm>
#include <array>
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
  // Take negative-evidence samples (above). A chain whose whisks never end (a harness that only
  // senses: crunch-virtual-robot's boards, training) turns them off, or they grow, 32 bytes per
  // 60 ms, with nothing to hand them to; endWhisk() then gives no free rays.
  bool negative_evidence = true;

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

  // Timed feeding, for a pose source that knows a moment's pose only later (RobotSession: the
  // odometry between the Create's packets, session/odometry_track.h). Decodes `bytes`, which
  // arrived at t_ns, and queues each sample they complete with its time: the last one t_ns, each
  // earlier one a sample period (500 us) before the next. The samples go through the live
  // detectors at once (liveContactMask(), liveCalibrated(): what the behaviour acts on, with no
  // delay) and through the pipeline only at release(), with their pose then. A full queue
  // (kQueueSamples, 2 s) releases its oldest sample with pose_at(t) as it is.
  template <typename PoseAt>
  void feedTimed(std::span<const std::uint8_t> bytes, std::uint64_t t_ns, PoseAt&& pose_at) {
    std::size_t added = 0;
    decoder_.feed(bytes, [&](const io::DecodedFrame& d) {
      assembler_.push(d, [&](const signal::SampleFrame& f) {
        for (int w = 0; w < signal::kWhiskers; ++w) live_[static_cast<std::size_t>(w)].push(f[w]);
        if (queued_ == kQueueSamples) releaseOne(pose_at);
        queue_[(queue_first_ + queued_) % kQueueSamples] = {f, 0};
        ++queued_;
        ++added;
      });
    });
    // Stamp this chunk's samples: 500 us apart, the last one at t_ns.
    added = std::min(added, queued_);
    for (std::size_t k = 0; k < added; ++k) {
      const std::uint64_t back = static_cast<std::uint64_t>(added - 1 - k) * kSamplePeriodNs;
      queue_[(queue_first_ + queued_ - added + k) % kQueueSamples].t_ns =
          t_ns > back ? t_ns - back : 0;
    }
  }
  // Passes every queued sample stamped at or before until_ns, oldest first, to the pipeline with
  // the pose pose_at(t) (as feed() does with its pose).
  template <typename PoseAt>
  void release(std::uint64_t until_ns, PoseAt&& pose_at) {
    while (queued_ > 0 && queue_[queue_first_].t_ns <= until_ns) releaseOne(pose_at);
  }
  // Samples queued for their pose.
  std::size_t queued() const { return queued_; }
  // The live detectors (timed feeding only): bit w set while whisker w touches; all calibrated.
  std::uint32_t liveContactMask() const;
  bool liveCalibrated() const;

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
  template <typename PoseAt>
  void releaseOne(PoseAt& pose_at) {
    const Queued& q = queue_[queue_first_];
    (void)onSample(q.frame, pose_at(q.t_ns));
    queue_first_ = (queue_first_ + 1) % kQueueSamples;
    --queued_;
  }

  static constexpr std::size_t kQueueSamples = 4096;
  static constexpr std::uint64_t kSamplePeriodNs = 500000;
  struct Queued {
    signal::SampleFrame frame;
    std::uint64_t t_ns = 0;
  };

  io::BridgeStreamDecoder decoder_;
  io::SampleAssembler assembler_;
  signal::SignalPipeline pipeline_;
  WhiskEvidence evidence_;
  std::vector<Pose2> pose_history_;  // ring: the pose of pipeline sample i at i % kPoseHistory
  std::vector<Queued> queue_;        // timed feeding: samples waiting for their pose (a ring)
  std::size_t queue_first_ = 0, queued_ = 0;
  std::array<signal::ContactDetector, signal::kWhiskers> live_;  // timed feeding's own detectors
  Pose2 free_pose_;                  // the negative-evidence sample being accumulated
  std::uint32_t free_mask_ = 0;
  bool negative_evidence_;           // SensingChainOptions::negative_evidence
  bool in_whisk_ = false;
  SensingCounts counts_;
};

}  // namespace crunch::session
