// The physics sensor path end to end (ARCHITECTURE.md §2), one 500 us sample at a time:
//
//   WhiskeredRobot (ODE bending whiskers) --base angles--> HallSensorModel (MLX90333 codes)
//     --> VirtualWhiskerBoard x N (the firmware core: sampler, ring, bridge frames)
//     --> one byte stream, the boards' frames interleaved as the FPGA bridge multiplexes them
//     --> session::SensingChain, the one `--robot` runs (session/sensing_chain.h):
//         io::BridgeStreamDecoder --> io::SampleAssembler --> signal::SignalPipeline
//         --> WhiskEvidence (reports, free rays per whisk), each sample stamped with the
//         simulator's exact pose (§2.8)
//
// Nothing on this path knows it is simulated past the Hall model: the bytes of each tick go into
// the same chain as a live robot's USB chunks. Every board sends one frame per tick (power-up
// frames included), so the assembler completes exactly one sample per step(): pipeline sample k
// is step k since create(). The rig also keeps the ground truth the simulator knows, so reports
// can be scored: per whisker, the true contact distance along the whisker (from ODE's contact
// points) at the sample of its largest base deflection.
//
// Start-up: create() powers the boards up (SAMPLER_POWERUP_TICKS) and lets the pipeline's
// detectors calibrate their rest and noise (ContactDetectorOptions::calibration_samples) with
// the robot standing still at `start`, away from everything (create() fails if a whisker
// touches anything there).
//
// Ownership: owns the robot, boards and sensing chain; holds a reference to the World, which
// must outlive it. Thread-safety: none (ODE and the host HAL are single-threaded).
// Allocation: step() allocates nothing after warm-up (the chain's pose history is allocated at
// create()), except that the chain's negative-evidence samples (32 bytes per 60 ms) grow until a
// whisk ends on it; a user that never calls chain().endWhisk() (training, crunch-virtual-robot)
// sets Options::negative_evidence false, or that buffer grows by about 1.9 MB a simulated hour.
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
#include "crunch/session/sensing_chain.h"
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
  // The first step of the contact: where the straight whisker first touched (what a located
  // report places; for a face the tip then slides along it, for an edge the point stays).
  double r_at_touch = 0.0;
  Vec2 point_at_touch = Vec2::Zero();
  double tangent_at_touch = 0.0;
  // Every true contact point from the first touch on, each kTrackStep from the last kept: a tip
  // pressed on a face or a leg slides along it as the whisker bends, so the whole track was
  // touched (what a ramp measured after the slide lies on it).
  static constexpr double kTrackStep = 0.001;  // metres
  std::vector<Vec2> track;
};

class WhiskerRig {
 public:
  struct Options {
    WhiskeredRobot::Options robot;
    HallSensorModel::Options hall;
    signal::PipelineOptions pipeline;
    std::uint64_t seed = 1;  // the Hall sensors' noise
    // The chain's negative evidence (session::SensingChainOptions::negative_evidence): on for a
    // user that whisks through chain() (the physics sensor), off for one that only senses.
    bool negative_evidence = true;
    Status validate() const;
  };

  // The four whiskers of `mounts` (signal::kWhiskers of them), board ids 0..3, at `start`.
  static Result<std::unique_ptr<WhiskerRig>> create(const World& world,
                                                    std::vector<WhiskerMount> mounts,
                                                    const Pose2& start, const Options& options);
  WhiskerRig(const WhiskerRig&) = delete;
  WhiskerRig& operator=(const WhiskerRig&) = delete;

  // One 500 us sample through the whole path: the tick's bridge bytes are fed to the chain with
  // the robot's pose. Returns the episode this sample completed (already taken by the chain if a
  // whisk is open), or nullptr; the pointer is valid until the next step() or finish().
  const signal::ContactEpisode* step();
  // Ends the episode in progress (session::SensingChain::endEpisode()).
  const signal::ContactEpisode* finish();

  // Ground truth since the last episode ended (or the last resetTruth()): index w = whisker w.
  const std::array<WhiskerTruth, signal::kWhiskers>& truth() const { return truth_; }
  // The truth as it was when the last returned episode ended.
  const std::array<WhiskerTruth, signal::kWhiskers>& episodeTruth() const {
    return episode_truth_;
  }
  void resetTruth();
  // The robot's pose at pipeline sample `index` (the chain's pose history: the last
  // session::kPoseHistory samples).
  Pose2 poseAtSample(std::uint64_t index) const { return chain_->poseAtSample(index); }

  // Bit w set while the pipeline's detector for whisker w is in contact: what the behaviour
  // layer sees (it never reads the simulator's truth).
  std::uint32_t contactMask() const { return chain_->contactMask(); }

  WhiskeredRobot& robot() { return *robot_; }
  const WhiskeredRobot& robot() const { return *robot_; }
  // The host side: whisks are opened and closed on it (beginWhisk / endWhisk), models set.
  session::SensingChain& chain() { return *chain_; }
  const session::SensingChain& chain() const { return *chain_; }
  const signal::SignalPipeline& pipeline() const { return chain_->pipeline(); }
  const io::BridgeStreamCounters& decoderCounters() const { return chain_->decoderCounters(); }
  // The bridge bytes of the last step(): every board's frame of that tick, as the FPGA bridge
  // forwards them to USB (the virtual robot serves these over a umockdev USB device).
  std::span<const std::uint8_t> lastTickBytes() const { return stream_; }
  VirtualWhiskerBoard& board(int w) { return *boards_[static_cast<std::size_t>(w)]; }
  // Readings the assembler had to fill in because a board's frame did not arrive (gaps and
  // silent boards: io::SampleAssembler::Counters placeholders + silent_fills).
  std::uint64_t missingFrames() const;

 private:
  WhiskerRig(std::unique_ptr<WhiskeredRobot> robot, std::unique_ptr<session::SensingChain> chain,
             const Options& options);
  void trackTruth();

  std::unique_ptr<WhiskeredRobot> robot_;
  std::unique_ptr<session::SensingChain> chain_;
  HallSensorModel hall_;
  Rng rng_;
  std::array<std::unique_ptr<VirtualWhiskerBoard>, signal::kWhiskers> boards_;
  std::vector<std::uint8_t> stream_;  // one tick's bytes of all boards, reserved
  std::array<WhiskerTruth, signal::kWhiskers> truth_{};
  std::array<WhiskerTruth, signal::kWhiskers> episode_truth_{};
};

}  // namespace crunch::sim
