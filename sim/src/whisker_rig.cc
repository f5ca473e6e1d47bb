#include "crunch_sim/whisker_rig.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <string>
#include <utility>

namespace crunch::sim {

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
  session::SensingChainOptions chain_options;
  chain_options.pipeline = options.pipeline;
  chain_options.mounts = mounts;
  chain_options.start = start;
  chain_options.negative_evidence = options.negative_evidence;
  auto chain = session::SensingChain::create(chain_options);
  if (!chain) return Error{"whisker rig: " + chain.error().message};
  auto robot = WhiskeredRobot::create(world, std::move(mounts), options.robot);
  if (!robot) return robot.error();
  std::unique_ptr<WhiskerRig> rig(
      new WhiskerRig(std::move(robot).value(), std::move(chain).value(), options));

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
    if (!rig->pipeline().detector(w).ready()) {
      return Error{"whisker rig: whisker " + std::to_string(w) +
                   " did not calibrate at rest (no valid samples or too noisy)"};
    }
  }
  rig->resetTruth();
  return rig;
}

WhiskerRig::WhiskerRig(std::unique_ptr<WhiskeredRobot> robot,
                       std::unique_ptr<session::SensingChain> chain, const Options& options)
    : robot_(std::move(robot)),
      chain_(std::move(chain)),
      hall_(options.hall),
      rng_(options.seed) {
  for (int w = 0; w < signal::kWhiskers; ++w) {
    boards_[static_cast<std::size_t>(w)] =
        std::make_unique<VirtualWhiskerBoard>(static_cast<std::uint8_t>(w));
  }
  stream_.reserve(static_cast<std::size_t>(signal::kWhiskers) * BRIDGE_FRAME_LEN *
                  (RING_CAPACITY + 1));
}

std::uint64_t WhiskerRig::missingFrames() const {
  const io::SampleAssembler::Counters& c = chain_->assemblerCounters();
  return c.placeholders + c.silent_fills;
}

void WhiskerRig::resetTruth() { truth_ = {}; }

void WhiskerRig::trackTruth() {
  for (int w = 0; w < signal::kWhiskers; ++w) {
    const auto contact = robot_->contact(w);
    if (!contact) continue;
    const BaseAngles a = robot_->baseAngles(w);
    const double angle = std::hypot(a.horizontal, a.vertical);
    WhiskerTruth& t = truth_[static_cast<std::size_t>(w)];
    if (!t.touched) {
      t.r_at_touch = contact->r;
      t.point_at_touch = contact->point;
      t.tangent_at_touch = std::atan2(contact->normal.y(), contact->normal.x()) + kPi / 2.0;
    }
    if (t.track.empty() ||
        (contact->point - t.track.back()).norm() >= WhiskerTruth::kTrackStep) {
      t.track.push_back(contact->point);
    }
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

const signal::ContactEpisode* WhiskerRig::step() {
  robot_->step();
  trackTruth();

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

  // Into the sensing chain with the pose of this tick (exact: §2.8). Each tick completes one
  // sample, so at most one episode ends here.
  const signal::ContactEpisode* episode = nullptr;
  chain_->feed(stream_, robot_->odometry(), [this, &episode](const signal::ContactEpisode& ep) {
    episode = &ep;
    episode_truth_ = truth_;
    resetTruth();
  });
  return episode;
}

const signal::ContactEpisode* WhiskerRig::finish() {
  const signal::ContactEpisode* episode = chain_->endEpisode();
  if (episode != nullptr) {
    episode_truth_ = truth_;
    resetTruth();
  }
  return episode;
}

}  // namespace crunch::sim
