#include "crunch/session/robot_session.h"

#include <utility>

#include "crunch/core/range_check.h"

namespace crunch::session {

namespace {
constexpr std::size_t kPoseHistory = 1u << 16;  // 32.8 s of samples: more than an episode
}  // namespace

Status RobotSessionOptions::validate() const {
  if (mounts.size() != static_cast<std::size_t>(signal::kWhiskers)) {
    return Error{"mounts: the whisker array must have " + std::to_string(signal::kWhiskers) +
                 " whiskers, has " + std::to_string(mounts.size())};
  }
  if (auto s = within("pipeline", pipeline.validate()); !s) return s;
  if (pipeline.max_episode_samples >= static_cast<std::int64_t>(kPoseHistory)) {
    return Error{"pipeline: max_episode_samples: must be below the pose history of " +
                 std::to_string(kPoseHistory) + " samples"};
  }
  if (auto s = within("mapping", mapping.validate()); !s) return s;
  const Status checks[] = {
      checkRange("start.x", start.x, -1e3, 1e3),
      checkRange("start.y", start.y, -1e3, 1e3),
      checkRange("start.theta", start.theta, -1e3, 1e3),
      checkRange("area.lo.x", area_lo.x(), -1e3, 1e3),
      checkRange("area.lo.y", area_lo.y(), -1e3, 1e3),
      checkRange("area width (area.hi.x - area.lo.x)", area_hi.x() - area_lo.x(), 0.5, kMaxAreaSide),
      checkRange("area depth (area.hi.y - area.lo.y)", area_hi.y() - area_lo.y(), 0.5, kMaxAreaSide)};
  for (const Status& s : checks) {
    if (!s) return s;
  }
  return okStatus();
}

Result<std::unique_ptr<RobotSession>> RobotSession::create(const RobotSessionOptions& options) {
  if (auto s = options.validate(); !s) return s.error();
  auto pipeline = signal::SignalPipeline::create(options.pipeline);
  if (!pipeline) return pipeline.error();
  if (auto s = pipeline.value().setModels(options.models); !s) return s.error();
  return std::unique_ptr<RobotSession>(new RobotSession(options, std::move(pipeline).value()));
}

RobotSession::RobotSession(const RobotSessionOptions& options, signal::SignalPipeline pipeline)
    : options_(options),
      pipeline_(std::move(pipeline)),
      tracker_(io::oi::StreamParserOptions{options.checksum_includes_header, 0}),
      evidence_(options.mounts),
      mapper_(options.mounts, options.area_lo, options.area_hi, options.mapping),
      pose_history_(kPoseHistory, options.start),
      free_pose_(options.start) {
  evidence_.begin();
}

Pose2 RobotSession::pose() const { return compose(options_.start, tracker_.odometry()); }

std::uint32_t RobotSession::contactMask() const {
  std::uint32_t mask = 0;
  for (int w = 0; w < signal::kWhiskers; ++w) {
    if (pipeline_.detector(w).inContact()) mask |= 1u << w;
  }
  return mask;
}

bool RobotSession::calibrated() const {
  for (int w = 0; w < signal::kWhiskers; ++w) {
    const signal::DetectorState s = pipeline_.detector(w).state();
    if (s != signal::DetectorState::kQuiet && s != signal::DetectorState::kContact) return false;
  }
  return true;
}

Pose2 RobotSession::poseAtSample(std::uint64_t index) const {
  return pose_history_[index % kPoseHistory];
}

Status RobotSession::handle(const io::Chunk& chunk) {
  if (recorder_ != nullptr) {
    if (auto s = recorder_->write(chunk); !s) return s;
  }
  switch (chunk.stream) {
    case io::StreamId::kBridge:
      ++counts_.bridge_chunks;
      decoder_.feed(chunk.data(), [this](const io::DecodedFrame& d) {
        assembler_.push(d, [this](const signal::SampleFrame& f) { onSample(f); });
      });
      break;
    case io::StreamId::kCreate:
      ++counts_.create_chunks;
      tracker_.feed(chunk.data());
      break;
    case io::StreamId::kMark:
      ++counts_.marks;
      if (chunk.size >= 1) {
        if (chunk.bytes[0] == static_cast<std::uint8_t>(io::MarkKind::kWhiskStart)) openWhisk();
        if (chunk.bytes[0] == static_cast<std::uint8_t>(io::MarkKind::kWhiskEnd)) closeWhisk();
        if (chunk.bytes[0] == static_cast<std::uint8_t>(io::MarkKind::kBridgeReconnected)) {
          decoder_.resync();
          assembler_.reset();
        }
      }
      break;
  }
  return okStatus();
}

Status RobotSession::mark(io::MarkKind kind_id, std::uint64_t t_ns) {
  io::Chunk c;
  const std::uint8_t kind = static_cast<std::uint8_t>(kind_id);
  c.assign(io::StreamId::kMark, t_ns, {&kind, 1});
  return handle(c);
}

void RobotSession::onSample(const signal::SampleFrame& frame) {
  const std::uint64_t index = pipeline_.counts().samples;  // this sample's pipeline index
  const Pose2 now = pose();
  pose_history_[index % kPoseHistory] = now;
  ++counts_.samples;
  if (const signal::ContactEpisode* ep = pipeline_.push(frame)) takeEpisode(*ep);
  // Negative evidence: one sample of pose and contacts every kFreeEvery pipeline samples.
  if (index % WhiskEvidence::kFreeEvery == 0) {
    if (index > 0) evidence_.sample(free_pose_, free_mask_);
    free_pose_ = now;
    free_mask_ = 0;
  }
  free_mask_ |= contactMask();
}

void RobotSession::takeEpisode(const signal::ContactEpisode& episode) {
  if (!in_whisk_) {
    ++counts_.roaming_episodes;
    return;
  }
  ++counts_.episodes;
  evidence_.take(episode, [this](std::uint64_t i) { return poseAtSample(i); });
}

void RobotSession::openWhisk() {
  // The episode of the contact that started this whisk is still open (the robot stops on it
  // without reversing) and becomes the whisk's first: its f1 is the peak over the sweep.
  evidence_.discardReports();
  in_whisk_ = true;
}

void RobotSession::closeWhisk() {
  // An episode still open at the end of the whisk (a whisker still pressed) ends here: the
  // mark is in the recording, so a replay ends it at the same sample.
  if (pipeline_.inEpisode()) {
    if (const signal::ContactEpisode* ep = pipeline_.finish()) takeEpisode(*ep);
  }
  reports_.clear();
  free_rays_.clear();
  evidence_.end(reports_, free_rays_);
  mapper_.addPose(pose(), reports_, free_rays_);
  counts_.reports += static_cast<int>(reports_.size());
  ++counts_.whisks;
  evidence_.begin();
  in_whisk_ = false;
}

Status RobotSession::bridgeReconnected(std::uint64_t t_ns) {
  return mark(io::MarkKind::kBridgeReconnected, t_ns);
}

Map RobotSession::finish() {
  closeWhisk();
  return mapper_.finish();
}

}  // namespace crunch::session
