// The physics sensor path end to end (ARCHITECTURE.md §2), one 500 us sample at a time:
//
//   WhiskeredRobot (ODE bending whiskers) --base angles--> HallSensorModel (MLX90333 codes)
//     --> VirtualWhiskerBoard x N (the firmware core: sampler, ring, bridge frames)
//     --> one byte stream, the boards' frames interleaved as the FPGA bridge multiplexes them
//     --> io::BridgeStreamDecoder (resync, CRC, counters) --> SampleFrame per tick
//     --> signal::SignalPipeline (detection, filters, eqs. 1-3) --> ContactEpisode
//
// Nothing on this path knows it is simulated past the Hall model: the decoder and the pipeline
// are the ones `--robot` runs. The rig also keeps the ground truth the simulator knows, so
// reports can be scored: per whisker, the true contact distance along the whisker (from ODE's
// contact points) at the sample of its largest base deflection, and the robot's pose at every
// sample of the current episode.
//
// Start-up: create() powers the boards up (SAMPLER_POWERUP_TICKS) and lets the pipeline's
// detectors calibrate their rest and noise (ContactDetectorOptions::calibration_samples) with
// the robot standing still at `start`, away from everything (create() fails if a whisker
// touches anything there).
//
// Ownership: owns the robot, boards, decoder and pipeline; holds a reference to the World, which
// must outlive it. Thread-safety: none (ODE and the host HAL are single-threaded).
// Allocation: step() allocates nothing after warm-up (the pose history is reserved for
// PipelineOptions::max_episode_samples).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/core/result.h"
#include "crunch/core/rng.h"
#include "crunch/io/bridge_stream.h"
#include "crunch/robot/shapelet.h"
#include "crunch/signal/pipeline.h"
#include "crunch_sim/hall_model.h"
#include "crunch_sim/virtual_whisker_board.h"
#include "crunch_sim/whisker_physics.h"
#include "crunch_sim/world.h"

namespace crunch::sim {

// What the simulator knows about one whisker over the current episode.
struct WhiskerTruth {
  bool touched = false;        // ODE reported a contact on it
  double peak_angle = 0.0;     // largest |base deflection| seen, radians
  double r_at_peak = 0.0;      // true contact distance from the base at that sample, metres
  Vec2 point_at_peak = Vec2::Zero();  // true contact point, arena frame
  double surface_tangent = 0.0;  // the touched surface's direction (normal + pi/2), radians
  Pose2 pose_at_peak;          // robot pose at that sample
};

class WhiskerRig {
 public:
  struct Options {
    WhiskeredRobot::Options robot;
    HallSensorModel::Options hall;
    signal::PipelineOptions pipeline;
    std::uint64_t seed = 1;  // the Hall sensors' noise
    Status validate() const;
  };

  // The four whiskers of `mounts` (signal::kWhiskers of them), board ids 0..3, at `start`.
  static Result<std::unique_ptr<WhiskerRig>> create(const World& world,
                                                    std::vector<WhiskerMount> mounts,
                                                    const Pose2& start, const Options& options);
  WhiskerRig(const WhiskerRig&) = delete;
  WhiskerRig& operator=(const WhiskerRig&) = delete;

  // One 500 us sample through the whole path. Returns the episode this sample completed, or
  // nullptr; the pointer is valid until the next step() or finish().
  const signal::ContactEpisode* step();
  // Ends the episode in progress (signal::SignalPipeline::finish()).
  const signal::ContactEpisode* finish();

  // Ground truth since the last episode ended (or the last resetTruth()): index w = whisker w.
  const std::array<WhiskerTruth, signal::kWhiskers>& truth() const { return truth_; }
  // The truth as it was when the last returned episode ended.
  const std::array<WhiskerTruth, signal::kWhiskers>& episodeTruth() const {
    return episode_truth_;
  }
  void resetTruth();
  // The robot's pose at pipeline sample `index` of the current or just-ended episode (the
  // pipeline's own sample count); the nearest recorded pose if it is out of range.
  Pose2 poseAtSample(std::uint64_t index) const;

  // Bit w set while the pipeline's detector for whisker w is in contact: what the behaviour
  // layer sees (it never reads the simulator's truth).
  std::uint32_t contactMask() const;

  WhiskeredRobot& robot() { return *robot_; }
  const WhiskeredRobot& robot() const { return *robot_; }
  signal::SignalPipeline& pipeline() { return pipeline_; }
  const signal::SignalPipeline& pipeline() const { return pipeline_; }
  const io::BridgeStreamCounters& decoderCounters() const { return decoder_.counters(); }
  // The bridge bytes of the last step(): every board's frame of that tick, as the FPGA bridge
  // forwards them to USB (the virtual robot serves these over a umockdev USB device).
  std::span<const std::uint8_t> lastTickBytes() const { return stream_; }
  VirtualWhiskerBoard& board(int w) { return *boards_[static_cast<std::size_t>(w)]; }
  // Ticks at which some board's frame did not arrive (fed to the pipeline as kDropped).
  std::uint64_t missingFrames() const { return missing_frames_; }

 private:
  WhiskerRig(std::unique_ptr<WhiskeredRobot> robot, signal::SignalPipeline pipeline,
             const Options& options);
  void trackTruth();
  void recordPose();

  std::unique_ptr<WhiskeredRobot> robot_;
  signal::SignalPipeline pipeline_;
  HallSensorModel hall_;
  Rng rng_;
  std::array<std::unique_ptr<VirtualWhiskerBoard>, signal::kWhiskers> boards_;
  io::BridgeStreamDecoder decoder_;
  std::vector<std::uint8_t> stream_;  // one tick's bytes of all boards, reserved
  signal::SampleFrame frame_{};
  std::array<bool, signal::kWhiskers> got_{};
  std::uint64_t missing_frames_ = 0;
  std::uint64_t samples_ = 0;  // samples fed to the pipeline
  std::array<WhiskerTruth, signal::kWhiskers> truth_{};
  std::array<WhiskerTruth, signal::kWhiskers> episode_truth_{};
  std::vector<Pose2> poses_;        // robot pose per sample since poses_start_
  std::uint64_t poses_start_ = 0;   // pipeline sample index of poses_[0]
};

}  // namespace crunch::sim
