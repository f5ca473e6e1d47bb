#include "crunch_sim/whisker_rig.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <string>
#include <utility>

namespace crunch::sim {

namespace {
// Samples of pose history kept while no episode runs; more is dropped at once.
constexpr std::size_t kIdleHistory = 4000;
}  // namespace

Status WhiskerRig::Options::validate() const {
  if (auto s = robot.validate(); !s) return Error{"robot options: " + s.error().message};
  if (auto s = hall.validate(); !s) return Error{"Hall model options: " + s.error().message};
  if (auto s = pipeline.validate(); !s) return Error{"pipeline options: " + s.error().message};
  return okStatus();
}

Result<std::unique_ptr<WhiskerRig>> WhiskerRig::create(const World& world,
                                                       std::vector<WhiskerMount> mounts,
                                                       const Pose2& start,
                                                       const Options& options) {
  if (auto s = options.validate(); !s) return s.error();
  if (mounts.size() != static_cast<std::size_t>(signal::kWhiskers)) {
    return Error{"whisker rig: " + std::to_string(mounts.size()) + " whisker mounts given, the "
                 "signal pipeline takes exactly " + std::to_string(signal::kWhiskers)};
  }
  auto robot = WhiskeredRobot::create(world, std::move(mounts), options.robot);
  if (!robot) return robot.error();
  auto pipeline = signal::SignalPipeline::create(options.pipeline);
  if (!pipeline) return pipeline.error();
  std::unique_ptr<WhiskerRig> rig(
      new WhiskerRig(std::move(robot).value(), std::move(pipeline).value(), options));

  // Power-up and calibration at rest, as a real robot does before it moves.
  rig->robot_->place(start);
  const int settle = static_cast<int>(SAMPLER_POWERUP_TICKS) +
                     options.pipeline.detector.settle_samples +
                     options.pipeline.detector.calibration_samples + 64;
  for (int i = 0; i < settle; ++i) {
    rig->step();
    for (int w = 0; w < signal::kWhiskers; ++w) {
      if (rig->robot_->contact(w)) {
        return Error{"whisker rig: whisker " + std::to_string(w) +
                     " touches something at the start pose; start it clear of walls and legs"};
      }
    }
  }
  for (int w = 0; w < signal::kWhiskers; ++w) {
    if (!rig->pipeline_.detector(w).ready()) {
      return Error{"whisker rig: whisker " + std::to_string(w) +
                   " did not calibrate at rest (no valid samples or too noisy)"};
    }
  }
  rig->resetTruth();
  return rig;
}

WhiskerRig::WhiskerRig(std::unique_ptr<WhiskeredRobot> robot, signal::SignalPipeline pipeline,
                       const Options& options)
    : robot_(std::move(robot)),
      pipeline_(std::move(pipeline)),
      hall_(options.hall),
      rng_(options.seed) {
  for (int w = 0; w < signal::kWhiskers; ++w) {
    boards_[static_cast<std::size_t>(w)] =
        std::make_unique<VirtualWhiskerBoard>(static_cast<std::uint8_t>(w));
  }
  stream_.reserve(static_cast<std::size_t>(signal::kWhiskers) * BRIDGE_FRAME_LEN *
                  (RING_CAPACITY + 1));
  poses_.reserve(static_cast<std::size_t>(options.pipeline.max_episode_samples) + kIdleHistory +
                 64);
}

void WhiskerRig::resetTruth() { truth_ = {}; }

void WhiskerRig::trackTruth() {
  for (int w = 0; w < signal::kWhiskers; ++w) {
    const auto contact = robot_->contact(w);
    if (!contact) continue;
    const BaseAngles a = robot_->baseAngles(w);
    const double angle = std::hypot(a.horizontal, a.vertical);
    WhiskerTruth& t = truth_[static_cast<std::size_t>(w)];
    if (!t.touched || angle > t.peak_angle) {
      t.touched = true;
      t.peak_angle = angle;
      t.r_at_peak = contact->r;
      t.point_at_peak = contact->point;
      t.surface_tangent = std::atan2(contact->normal.y(), contact->normal.x()) + kPi / 2.0;
      t.pose_at_peak = robot_->odometry();
    }
  }
}

void WhiskerRig::recordPose() {
  if (!pipeline_.inEpisode() && poses_.size() >= kIdleHistory) {
    poses_.clear();
    poses_start_ = samples_;
  }
  if (poses_.size() < poses_.capacity()) poses_.push_back(robot_->odometry());
}

Pose2 WhiskerRig::poseAtSample(std::uint64_t index) const {
  if (poses_.empty()) return robot_->odometry();
  if (index < poses_start_) return poses_.front();
  const std::uint64_t i = index - poses_start_;
  return i < poses_.size() ? poses_[static_cast<std::size_t>(i)] : poses_.back();
}

std::uint32_t WhiskerRig::contactMask() const {
  std::uint32_t mask = 0;
  for (int w = 0; w < signal::kWhiskers; ++w) {
    if (pipeline_.detector(w).inContact()) mask |= 1u << w;
  }
  return mask;
}

const signal::ContactEpisode* WhiskerRig::step() {
  robot_->step();
  trackTruth();
  recordPose();

  // Hall sensors -> boards -> one multiplexed stream, as the FPGA bridge forwards it.
  stream_.clear();
  for (int w = 0; w < signal::kWhiskers; ++w) {
    const BaseAngles a = robot_->baseAngles(w);
    const HallCodes codes = hall_.sample(a.horizontal, a.vertical, rng_);
    // A clamped output is what the MLX90333 flags as out of its field range.
    const std::uint16_t diag = (codes.alpha_clamped || codes.beta_clamped) ? 0x0002u : 0u;
    VirtualWhiskerBoard& board = *boards_[static_cast<std::size_t>(w)];
    board.sensor().setReading(codes.alpha, codes.beta, diag);
    const auto bytes = board.tick();
    stream_.insert(stream_.end(), bytes.begin(), bytes.end());
  }

  // Decode and assemble this tick's frame of the four whiskers.
  got_.fill(false);
  decoder_.feed(stream_, [this](const io::DecodedFrame& d) {
    const int w = d.frame.board;
    if (w < 0 || w >= signal::kWhiskers) return;
    frame_[static_cast<std::size_t>(w)] = {d.frame.alpha, d.frame.beta, d.frame.status};
    got_[static_cast<std::size_t>(w)] = true;
  });
  for (int w = 0; w < signal::kWhiskers; ++w) {
    if (!got_[static_cast<std::size_t>(w)]) {
      frame_[static_cast<std::size_t>(w)] = {0, 0, signal::status::kBusy};
      ++missing_frames_;
    }
  }
  ++samples_;
  const signal::ContactEpisode* episode = pipeline_.push(frame_);
  if (episode != nullptr) {
    episode_truth_ = truth_;
    resetTruth();
  }
  return episode;
}

const signal::ContactEpisode* WhiskerRig::finish() {
  const signal::ContactEpisode* episode = pipeline_.finish();
  if (episode != nullptr) {
    episode_truth_ = truth_;
    resetTruth();
  }
  return episode;
}

}  // namespace crunch::sim
