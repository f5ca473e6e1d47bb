#include "crunch/signal/pipeline.h"

#include <cmath>
#include <string>

namespace crunch::signal {

Status PipelineOptions::validate() const {
  if (Status s = detector.validate(); !s.ok()) return Error{"detector." + s.error().message};
  if (Status s = window.validate(); !s.ok()) return s;
  if (max_episode_samples < window.samples) {
    return Error{"max_episode_samples: expected at least window.samples (" +
                 std::to_string(window.samples) + "), got " + std::to_string(max_episode_samples)};
  }
  if (max_episode_samples > 1200000) {
    return Error{"max_episode_samples: expected at most 1200000 (10 minutes), got " +
                 std::to_string(max_episode_samples)};
  }
  if (!(max_held_fraction >= 0.0 && max_held_fraction <= 1.0)) {
    return Error{"max_held_fraction: expected a number in [0, 1]"};
  }
  if (Status s = ramp.validate(); !s.ok()) return Error{"ramp." + s.error().message};
  return okStatus();
}

namespace {
int delaySamples(const SmoothingFilter::Options& smoothing) {
  return static_cast<int>(std::lround(SmoothingFilter(smoothing).groupDelayAtDc() * kSampleRateHz));
}
}  // namespace

Result<SignalPipeline> SignalPipeline::create(const PipelineOptions& options) {
  if (Status s = options.validate(); !s.ok())
    return Error{"signal pipeline options: " + s.error().message};
  if (delaySamples(options.detector.smoothing) >= kPoseRing) {
    return Error{"signal pipeline options: detector.smoothing: a group delay of more than " +
                 std::to_string(kPoseRing) + " samples"};
  }
  return SignalPipeline(options);
}

SignalPipeline::SignalPipeline(const PipelineOptions& options)
    : options_(options),
      detectors_{ContactDetector(options.detector), ContactDetector(options.detector),
                 ContactDetector(options.detector), ContactDetector(options.detector)},
      recorder_(options.window),
      delay_(delaySamples(options.detector.smoothing)) {
  static_assert(kWhiskers == 4, "detectors_ is initialised for four whiskers");
  episode_.window = recorder_.window();
  for (RampFitter& r : ramps_) r = RampFitter(options.ramp);
}

Status SignalPipeline::setModels(const SignalModels& models) {
  if (Status s = validateModels(models); !s.ok()) return s;
  if (Status s = setOrientationModel(models.orientation); !s.ok()) return s;
  setRadialModel(models.radial);
  return okStatus();
}

void SignalPipeline::setRadialModel(const RadialModel& model) { radial_ = model; }

Status SignalPipeline::setOrientationModel(const OrientationModel& model) {
  const int columns = options_.window.columns();
  if (model.decimation != options_.window.decimation || model.columns != columns) {
    return Error{"orientation model: its windows have decimation " +
                 std::to_string(model.decimation) + " and " + std::to_string(model.columns) +
                 " columns, this pipeline records decimation " +
                 std::to_string(options_.window.decimation) + " and " + std::to_string(columns) +
                 " columns; retrain with the pipeline's window options"};
  }
  if (model.templates.empty()) return Error{"orientation model: no templates"};
  for (size_t k = 0; k < model.templates.size(); ++k) {
    if (model.templates[k].mean.cols() != columns || !model.templates[k].mean.allFinite()) {
      return Error{"orientation model: template " + std::to_string(k) +
                   " has the wrong size or a non-finite value"};
    }
  }
  orientation_ = model;
  episode_.orientation.errors.assign(model.templates.size(), 0.0);
  return okStatus();
}

void SignalPipeline::clearModels() {
  radial_.reset();
  orientation_.reset();
}

void SignalPipeline::startEpisode() {
  in_episode_ = true;
  episode_start_ = counts_.samples - 1;
  episode_samples_ = 0;
  recorder_.start();
  for (int w = 0; w < kWhiskers; ++w) {
    episode_.whiskers[w] = WhiskerContact{};
    ramps_[w].reset();
    // The onset sample itself belongs to the episode.
    held_at_start_[w] = detectors_[w].counts().held - (detectors_[w].lastHeld() ? 1 : 0);
  }
  // Reset field by field: `window` and `orientation.errors` keep their storage.
  episode_.start_sample = episode_start_;
  episode_.length_samples = 0;
  episode_.duration_s = 0.0;
  episode_.touched_count = 0;
  episode_.kind = ContactKind::kUnknown;
  episode_.truncated = false;
  episode_.finished_early = false;
  episode_.reliable = true;
  episode_.window_complete = false;
  episode_.has_orientation = false;
  episode_.orientation.class_index = -1;
  episode_.orientation.angle = 0.0;
}

const ContactEpisode* SignalPipeline::push(const SampleFrame& frame) {
  return step(frame, nullptr);
}

const ContactEpisode* SignalPipeline::push(const SampleFrame& frame, const Pose2& pose) {
  return step(frame, &pose);
}

const ContactEpisode* SignalPipeline::step(const SampleFrame& frame, const Pose2* pose) {
  const std::uint64_t index = counts_.samples;
  if (pose != nullptr) poses_[index % kPoseRing] = *pose;
  ++counts_.samples;
  bool onset = false;
  std::array<DetectorEvent, kWhiskers> events;
  for (int w = 0; w < kWhiskers; ++w) {
    events[w] = detectors_[w].push(frame[w]);
    onset = onset || events[w] == DetectorEvent::kOnset;
  }
  if (!in_episode_) {
    if (!onset) return nullptr;
    startEpisode();  // aligned to the first onset over all whiskers (§2.5)
  }

  std::array<double, kChannels> channels;
  for (int w = 0; w < kWhiskers; ++w) {
    channels[channelOf(w, 0)] = detectors_[w].deflection().x();
    channels[channelOf(w, 1)] = detectors_[w].deflection().y();
  }
  recorder_.push(channels);

  const std::int64_t t = episode_samples_++;
  bool touching = false;
  for (int w = 0; w < kWhiskers; ++w) {
    WhiskerContact& c = episode_.whiskers[w];
    const ContactDetector& d = detectors_[w];
    if (d.inContact()) {
      touching = true;
      if (!c.touched) {
        c.touched = true;
        c.onset_sample = t;
      }
    }
    if (events[w] == DetectorEvent::kLost) c.lost = true;
    if (c.touched && pose != nullptr && index >= static_cast<std::uint64_t>(delay_)) {
      // The first contact's ramp; a lost whisker's readings are not deflections.
      if (c.lost || !d.ready()) ramps_[w].close();
      else ramps_[w].push(d.theta(), poses_[(index - delay_) % kPoseRing], index - delay_);
    }
    if (c.peak_sample < 0 || d.theta() > c.f1) {  // eq. 1
      c.f1 = d.theta();
      c.peak_sample = t;
    }
  }
  if (recorder_.full() && !touching) return completeEpisode();
  if (episode_samples_ >= options_.max_episode_samples) {
    episode_.truncated = true;
    return completeEpisode();
  }
  return nullptr;
}

const ContactEpisode* SignalPipeline::finish() {
  if (!in_episode_) return nullptr;
  episode_.finished_early = true;
  return completeEpisode();
}

const ContactEpisode* SignalPipeline::completeEpisode() {
  in_episode_ = false;
  ContactEpisode& e = episode_;
  e.length_samples = episode_samples_;
  e.duration_s = static_cast<double>(episode_samples_) * kSamplePeriod;
  bool any_shaft = false;
  for (int w = 0; w < kWhiskers; ++w) {
    WhiskerContact& c = e.whiskers[w];
    c.held_samples = static_cast<std::uint32_t>(detectors_[w].counts().held - held_at_start_[w]);
    c.peak_time_s = static_cast<double>(c.peak_sample) * kSamplePeriod;
    ramps_[w].close();
    c.ramp = ramps_[w].result();
    const double held_fraction =
        static_cast<double>(c.held_samples) / static_cast<double>(episode_samples_);
    if (c.lost || held_fraction > options_.max_held_fraction) e.reliable = false;
    if (!c.touched) continue;
    ++e.touched_count;
    if (radial_) {
      const RadialEstimate r = radial_->estimate(w, c.f1);
      c.has_r = true;
      c.r = r.r;
      c.tip = r.tip;
      c.extrapolated = r.extrapolated;
      any_shaft = any_shaft || !r.tip;
    }
  }
  if (radial_ && e.touched_count > 0) e.kind = any_shaft ? ContactKind::kShaft : ContactKind::kTip;
  e.window.decimation = recorder_.window().decimation;
  e.window.data = recorder_.window().data;  // same size: no allocation
  e.window_complete = recorder_.full();
  if (e.window_complete && orientation_) {
    orientation_->classify(e.window, e.orientation);
    e.has_orientation = true;
  }
  ++counts_.episodes;
  if (e.truncated) ++counts_.truncated;
  if (!e.reliable) ++counts_.unreliable;
  return &e;
}

}  // namespace crunch::signal
