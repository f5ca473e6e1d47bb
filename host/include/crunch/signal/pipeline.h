// The whole signal path for the four horizontal whiskers (paper §2.3-2.5): raw 2 kHz samples in,
// one ContactEpisode per contact out, with radial distance (eqs. 1-2), the tip/shaft decision
// (Fig. 1) and the surface orientation (eq. 3).
//
//   SampleFrame --> ContactDetector x4 (status, rest, 17 Hz low-pass, 5-point average, theta)
//                     |  first onset of any whisker starts an episode (alignment, §2.5)
//                     v
//               WindowRecorder (8 channels, 2 s, decimated) + per-whisker max theta (f1)
//                     |  episode ends: window full and no whisker touching,
//                     |  or max_episode_samples, or finish()
//                     v
//               RadialModel (r, tip) + OrientationModel (angle, e(T_i)) --> ContactEpisode
//
// Body motion. push(frame, pose) also takes the robot's pose at the sample; each whisker's
// first contact of an episode is then fitted against the heading (contact_ramp.h: the ramp's
// slope gives the contact distance, its intercept the heading at the touch). The pose is paired
// with the smoothed deflection it caused: the pose of smoothingDelaySamples() samples earlier.
// push(frame) knows no motion and fits no ramp.
//
// Episode end. The paper takes f1 as the peak over the body whisk (§2.3-2.4) and the template
// window as 2 s from the first contact (§2.5). An episode therefore lasts at least the window
// and until every whisker has released; max_episode_samples (default 10 s) ends one that never
// releases (marked truncated: whiskers still touching must release before they can start the
// next episode). finish() ends an episode early, e.g. when the behaviour layer knows the whisk
// is over; its window is then incomplete and no orientation is given.
//
// Decision (ContactEpisode::kind): kTip if every touched whisker's r is in the tip zone (the
// orientation is meaningful); kShaft if any touched whisker touched on the shaft: the robot
// should move and try again (§1, Fig. 1); r is still reported. kUnknown without a radial model.
//
// Without models the pipeline still detects episodes and reports f1 and the window: this is how
// training data is collected (docs/SIGNAL.md, "Training").
//
// push() does not allocate: every buffer is sized at create() or setModels(). Not thread-safe:
// one thread feeds it. The returned episode pointer is valid until the next push(), finish(),
// setModels() or clearModels(); copy the episode to keep it.
#pragma once

#include <array>
#include <cassert>
#include <cstdint>
#include <optional>

#include "crunch/core/result.h"
#include "crunch/signal/contact_detector.h"
#include "crunch/signal/models_io.h"
#include "crunch/signal/pipeline_options.h"
#include "crunch/signal/window.h"

namespace crunch::signal {


// One whisker's part in an episode. Sample indices are relative to the episode's start; times
// refer to the smoothed signal (about 14 ms behind the raw one, filters.h).
struct WhiskerContact {
  bool touched = false;            // had an onset during the episode
  std::int64_t onset_sample = -1;  // its first onset
  double f1 = 0.0;                 // eq. 1: max theta over the episode, radians
  std::int64_t peak_sample = -1;
  double peak_time_s = 0.0;
  bool has_r = false;              // touched and a radial model is set
  double r = 0.0;                  // eq. 2, metres from the base
  bool tip = false;                // r in the tip zone
  bool extrapolated = false;       // f1 outside the model's training range
  std::uint32_t held_samples = 0;  // samples held (not measurements) during the episode
  bool lost = false;               // the whisker was lost during the episode
  ContactRamp ramp;                // its first contact's ramp against the heading (push(frame, pose))
};

enum class ContactKind {
  kUnknown,  // no radial model
  kTip,      // every touched whisker in the tip zone: orientation usable
  kShaft,    // at least one shaft contact: move and retry
};

struct ContactEpisode {
  std::uint64_t start_sample = 0;  // pipeline sample index of the first onset
  std::int64_t length_samples = 0;
  double duration_s = 0.0;
  std::array<WhiskerContact, kWhiskers> whiskers;
  int touched_count = 0;
  ContactKind kind = ContactKind::kUnknown;
  bool truncated = false;       // ended by max_episode_samples
  bool finished_early = false;  // ended by finish()
  bool reliable = true;         // see PipelineOptions::max_held_fraction
  ContactWindow window;         // 8 channels from the first onset (window.h)
  bool window_complete = false;
  bool has_orientation = false;  // window complete and an orientation model is set
  OrientationEstimate orientation;
};

struct PipelineCounts {
  std::uint64_t samples = 0;
  std::uint64_t episodes = 0;
  std::uint64_t truncated = 0;
  std::uint64_t unreliable = 0;
};

class SignalPipeline {
 public:
  // An Error names the bad option.
  static Result<SignalPipeline> create(const PipelineOptions& options = {});

  // Sets both models. Error if the orientation model's window shape (decimation, columns)
  // differs from this pipeline's window, or validateModels() fails. An episode in progress
  // keeps running and is evaluated with the new models.
  Status setModels(const SignalModels& models);
  void setRadialModel(const RadialModel& model);
  Status setOrientationModel(const OrientationModel& model);
  void clearModels();

  // Feeds one 500 us sample of the four whiskers. Returns the episode that this sample
  // completed, or nullptr.
  const ContactEpisode* push(const SampleFrame& frame);
  // The same with the robot's pose at this sample (body motion: contact_ramp.h).
  const ContactEpisode* push(const SampleFrame& frame, const Pose2& pose);
  // Ends the episode in progress now and returns it (nullptr if none).
  const ContactEpisode* finish();

  bool inEpisode() const { return in_episode_; }
  // Asserts 0 <= whisker < kWhiskers.
  const ContactDetector& detector(int whisker) const {
    assert(whisker >= 0 && whisker < kWhiskers);
    return detectors_[whisker];
  }
  const PipelineCounts& counts() const { return counts_; }
  const PipelineOptions& options() const { return options_; }
  bool hasRadialModel() const { return radial_.has_value(); }
  bool hasOrientationModel() const { return orientation_.has_value(); }
  // The smoothing's group delay, whole samples: theta at sample k is paired with the pose of
  // sample k - this.
  int smoothingDelaySamples() const { return delay_; }

 private:
  explicit SignalPipeline(const PipelineOptions& options);
  const ContactEpisode* step(const SampleFrame& frame, const Pose2* pose);
  void startEpisode();
  const ContactEpisode* completeEpisode();

  PipelineOptions options_;
  std::array<ContactDetector, kWhiskers> detectors_;
  WindowRecorder recorder_;
  std::optional<RadialModel> radial_;
  std::optional<OrientationModel> orientation_;
  PipelineCounts counts_;

  bool in_episode_ = false;
  std::uint64_t episode_start_ = 0;
  std::int64_t episode_samples_ = 0;
  std::array<std::uint64_t, kWhiskers> held_at_start_{};
  ContactEpisode episode_;  // reused; its window and errors are preallocated
  static constexpr int kPoseRing = 128;  // > any smoothing delay (checked at create())
  std::array<Pose2, kPoseRing> poses_{};
  int delay_ = 0;
  std::array<RampFitter, kWhiskers> ramps_;
};

}  // namespace crunch::signal
