#include "crunch/session/sensing_chain.h"

#include <string>
#include <utility>

#include "crunch/core/range_check.h"

namespace crunch::session {

Status SensingChainOptions::validate() const {
  if (mounts.size() != static_cast<std::size_t>(signal::kWhiskers)) {
    return Error{"mounts: the whisker array must have " + std::to_string(signal::kWhiskers) +
                 " whiskers, has " + std::to_string(mounts.size())};
  }
  if (auto s = within("pipeline", pipeline.validate()); !s) return s;
  if (pipeline.max_episode_samples >= static_cast<std::int64_t>(kPoseHistory)) {
    return Error{"pipeline: max_episode_samples: must be below the pose history of " +
                 std::to_string(kPoseHistory) + " samples"};
  }
  return okStatus();
}

Result<std::unique_ptr<SensingChain>> SensingChain::create(const SensingChainOptions& options) {
  if (auto s = options.validate(); !s) return s.error();
  auto pipeline = signal::SignalPipeline::create(options.pipeline);
  if (!pipeline) return pipeline.error();
  return std::unique_ptr<SensingChain>(new SensingChain(options, std::move(pipeline).value()));
}

SensingChain::SensingChain(const SensingChainOptions& options, signal::SignalPipeline pipeline)
    : pipeline_(std::move(pipeline)),
      evidence_(options.mounts, options.beam),
      pose_history_(kPoseHistory, options.start),
      queue_(kQueueSamples),
      live_{signal::ContactDetector(options.pipeline.detector),
            signal::ContactDetector(options.pipeline.detector),
            signal::ContactDetector(options.pipeline.detector),
            signal::ContactDetector(options.pipeline.detector)},
      free_pose_(options.start),
      negative_evidence_(options.negative_evidence) {
  static_assert(signal::kWhiskers == 4, "live_ is initialised for four whiskers");
  evidence_.begin();
}

std::uint32_t SensingChain::contactMask() const {
  std::uint32_t mask = 0;
  for (int w = 0; w < signal::kWhiskers; ++w) {
    if (pipeline_.detector(w).inContact()) mask |= 1u << w;
  }
  return mask;
}

std::uint32_t SensingChain::liveContactMask() const {
  std::uint32_t mask = 0;
  for (int w = 0; w < signal::kWhiskers; ++w) {
    if (live_[static_cast<std::size_t>(w)].inContact()) mask |= 1u << w;
  }
  return mask;
}

bool SensingChain::liveCalibrated() const {
  for (const signal::ContactDetector& d : live_) {
    const signal::DetectorState s = d.state();
    if (s != signal::DetectorState::kQuiet && s != signal::DetectorState::kContact) return false;
  }
  return true;
}

std::uint32_t SensingChain::unreadyMask() const {
  std::uint32_t mask = 0;
  for (int w = 0; w < signal::kWhiskers; ++w) {
    if (!pipeline_.detector(w).ready()) mask |= 1u << w;
  }
  return mask;
}

Status SensingChain::setModels(const signal::SignalModels& models) {
  if (auto s = pipeline_.setModels(models); !s) return s;
  evidence_.setModels(models);
  return okStatus();
}

bool SensingChain::calibrated() const {
  for (int w = 0; w < signal::kWhiskers; ++w) {
    const signal::DetectorState s = pipeline_.detector(w).state();
    if (s != signal::DetectorState::kQuiet && s != signal::DetectorState::kContact) return false;
  }
  return true;
}

std::uint32_t SensingChain::reportedMask() const {
  std::uint32_t mask = 0;
  for (int w = 0; w < signal::kWhiskers; ++w) {
    if (evidence_.entry(w).have) mask |= 1u << w;
  }
  return mask;
}

const signal::ContactEpisode* SensingChain::onSample(const signal::SampleFrame& frame,
                                                     const Pose2& pose) {
  const std::uint64_t index = pipeline_.counts().samples;  // this sample's pipeline index
  pose_history_[index % kPoseHistory] = pose;
  ++counts_.samples;
  const signal::ContactEpisode* ep = pipeline_.push(frame, pose);
  if (ep != nullptr) takeEpisode(*ep);
  // Negative evidence: one sample of pose and contacts every kFreeEvery pipeline samples.
  if (index % WhiskEvidence::kFreeEvery == 0) {
    if (index > 0 && negative_evidence_) evidence_.sample(free_pose_, free_mask_);
    free_pose_ = pose;
    free_mask_ = 0;
  }
  free_mask_ |= contactMask() | unreadyMask();
  return ep;
}

void SensingChain::takeEpisode(const signal::ContactEpisode& episode) {
  if (!in_whisk_) {
    ++counts_.roaming_episodes;
    return;
  }
  ++counts_.episodes;
  evidence_.take(episode, [this](std::uint64_t i) { return poseAtSample(i); });
}

void SensingChain::beginWhisk() {
  // The episode of the contact that started this whisk is still open (the robot stops on it
  // without reversing) and becomes the whisk's first: its f1 is the peak over the sweep.
  evidence_.discardReports();
  in_whisk_ = true;
}

const signal::ContactEpisode* SensingChain::endEpisode() {
  if (!pipeline_.inEpisode()) return nullptr;
  const signal::ContactEpisode* ep = pipeline_.finish();
  if (ep != nullptr) takeEpisode(*ep);
  return ep;
}

void SensingChain::endWhisk(std::vector<ContactReport>& reports, std::vector<FreeRay>& free_rays) {
  // An episode still open at the end of the whisk (a whisker still pressed) ends here: a
  // recording holds the whisk-end mark, so a replay ends it at the same sample.
  (void)endEpisode();
  const std::size_t first = reports.size();
  evidence_.end(reports, free_rays);
  counts_.reports += static_cast<int>(reports.size() - first);
  ++counts_.whisks;
  evidence_.begin();
  in_whisk_ = false;
}

void SensingChain::reconnect() {
  decoder_.resync();
  assembler_.reset();
}

}  // namespace crunch::session
