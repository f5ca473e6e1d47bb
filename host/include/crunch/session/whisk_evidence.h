// What one body whisk tells the mapper (paper §2.3-2.5, §2.8): the contact reports its
// episodes give, and the rays its whiskers swept without touching (negative evidence,
// free_space.h). Shared by the simulator's physics sensor and by `crunchhost --robot`/`--replay`,
// so both turn the signal pipeline's output into the mapper's input the same way.
//
// Reports. One whisk may give several contact episodes (the whisker meets the object on the
// toward and on the return pass); each whisker reports at most once per whisk, from the first
// episode in which it touched. The contact is located from its ramp against the body's turn
// (signal/contact_ramp.h, robot/whisker_beam.h; docs/SIGNAL.md, "Locating a contact from the
// ramp"):
//   robot  the pose at the touch: the position of the ramp's first sample with the ramp's touch
//          heading, where the straight rest whisker passes through the contact point;
//   r      the distance along the whisker whose rampSlope() is the ramp's slope (with the models'
//          RampCalibration), in [5 mm, the mount's length];
//   kind   kPoint: the contact's surface orientation is not known from one whisker (an edge,
//          a leg's corner, or a tip on a face: the ramp is the same), unless two whiskers of the
//          whisk located tip contacts on one face (kFlat, below);
//   phi    for kFlat the direction of the line through the two contact points, in the frame of
//          the touch pose, in [0, pi); for kPoint the orientation template's angle (eq. 3) as
//          before, which the blackboard does not use.
// Flat faces: two whiskers' tip contacts (r within the tip zone, RadialOptions) of one whisk
// whose contact points are further apart than kFlatSpan (more than any leg's diagonal, less than
// two whiskers' tips can reach on different objects at once) lie on one face: both are kFlat with
// that face's direction. A whisker without a ramp (it never bent past the ramp's band, or the
// body did not turn while it did) gives no report: counted as no_ramp, as are whiskers without
// a radial model (no_radial).
//
// Negative evidence: the caller samples the whisk every kFreeEvery pipeline samples with
// sample(pose, contact mask); a sample whose whisker shows no contact within kFreeGuard
// sample() calls either side (4 x 60 ms = +-0.24 s: far more than the smoothing's ~14 ms lag,
// so a whisker about to touch or just released is never taken as free) gives its straight
// rest ray.
//
// Allocation: begin() keeps the buffers; after the first whisks nothing is allocated.
// Thread-safety: none.
#pragma once

#include <cstdint>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/blackboard/free_space.h"
#include "crunch/robot/shapelet.h"
#include "crunch/robot/whisker_beam.h"
#include "crunch/signal/models_io.h"
#include "crunch/signal/pipeline.h"

namespace crunch {

class WhiskEvidence {
 public:
  static constexpr int kFreeEvery = 120;  // pipeline samples between free-ray samples (60 ms)
  static constexpr int kFreeGuard = 4;    // sample() calls either side with no contact (0.24 s)

  // One whisker's first-pass report of this whisk.
  struct Entry {
    bool have = false;     // the whisker touched in some episode of this whisk
    bool has_r = false;
    bool has_phi = false;
    bool located = false;  // a ramp located it
    bool tip = false;      // r in the tip zone
    double f1 = 0.0;
    ContactReport report;
  };
  struct Counts {
    int whisks = 0;
    int episodes = 0;
    int reports = 0;
    int no_radial = 0;       // touched whiskers without a radial model (models not set)
    int no_orientation = 0;  // touched whiskers whose episode had no orientation (unused)
    int no_ramp = 0;         // touched whiskers whose contact had no ramp to locate it
    int shaft = 0;           // reports located on the shaft (r below the tip zone)
    int flat = 0;            // reports on a face located by two whiskers
  };

  // Within this distance of the tip (the models' RadialOptions tip zone) a contact is a tip
  // contact; kFlatSpan: see the top of this file.
  static constexpr double kFlatSpan = 0.12;

  WhiskEvidence(std::vector<WhiskerMount> mounts, WhiskerBeam beam);
  // The models in use: their slope calibration and tip zone (nominal until set).
  void setModels(const signal::SignalModels& models);

  // Starts a whisk: forgets the last one's entries and samples.
  void begin();
  // Takes one episode of the current whisk. poseAt(std::uint64_t pipeline_sample) -> Pose2.
  // Returns a bit mask of the whiskers whose entry this episode set (first touch this whisk).
  template <typename PoseAt>
  std::uint32_t take(const signal::ContactEpisode& ep, PoseAt&& poseAt) {
    ++counts_.episodes;
    std::uint32_t set = 0;
    const Pose2 onset = poseAt(ep.start_sample);
    for (std::size_t w = 0; w < mounts_.size() && w < ep.whiskers.size(); ++w) {
      const signal::WhiskerContact& c = ep.whiskers[w];
      if (!c.touched || entries_[w].have) continue;
      const std::int64_t peak = c.peak_sample > 0 ? c.peak_sample : 0;
      const Pose2 peak_pose = poseAt(ep.start_sample + static_cast<std::uint64_t>(peak));
      const Pose2 ramp_pose = c.ramp.valid ? poseAt(c.ramp.first_sample) : peak_pose;
      fill(entries_[w], w, ep, c, onset, peak_pose, ramp_pose);
      set |= 1u << w;
    }
    return set;
  }
  // Forgets the entries taken so far (contacts that are not the whisk's own); keeps the
  // negative-evidence samples.
  void discardReports();
  // One negative-evidence sample: the pose now and the whiskers in contact (bit w = whisker w).
  void sample(const Pose2& pose, std::uint32_t contact_mask);
  // Ends the whisk: appends the reports to `reports` and the free rays to `free_rays`.
  void end(std::vector<ContactReport>& reports, std::vector<FreeRay>& free_rays);

  const Entry& entry(int w) const { return entries_[static_cast<std::size_t>(w)]; }
  const Counts& counts() const { return counts_; }
  const std::vector<WhiskerMount>& mounts() const { return mounts_; }
  double tipZone() const { return tip_zone_; }

 private:
  void fill(Entry& e, std::size_t w, const signal::ContactEpisode& ep,
            const signal::WhiskerContact& c, const Pose2& onset, const Pose2& peak,
            const Pose2& ramp) const;
  void classifyFaces();
  struct Sample {
    Pose2 pose;
    std::uint32_t mask = 0;
  };
  std::vector<WhiskerMount> mounts_;
  WhiskerBeam beam_;
  signal::RampCalibration calibration_;
  double tip_zone_ = 0.05;
  std::vector<Entry> entries_;
  std::vector<Sample> samples_;
  Counts counts_;
};


}  // namespace crunch
