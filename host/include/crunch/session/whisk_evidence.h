// What one body whisk tells the mapper (paper §2.3-2.5, §2.8): the contact reports its
// episodes give, and the rays its whiskers swept without touching (negative evidence,
// free_space.h). Shared by the simulator's physics sensor and by `crunchhost --robot`/`--replay`,
// so both turn the signal pipeline's output into the mapper's input the same way.
//
// Reports. One whisk may give several contact episodes (the whisker meets the object on the
// toward and on the return pass); each whisker reports at most once per whisk, from the first
// episode in which it touched: its f1 is the peak of that first pass (eq. 1), as the shipped
// models were trained (docs/TRAINING.md):
//   r      the radial model's estimate (eq. 2), clamped to [0, the mount's length];
//   phi    the orientation template's angle (eq. 3), which is relative to the heading at the
//          episode's first contact, turned into the frame of the robot at this whisker's peak,
//          as a value in [0, pi);
//   robot  the pose at the peak sample (poseAt(), the caller's odometry per pipeline sample).
// A whisker without an r estimate, or whose episode has no orientation (window cut short),
// gives no report; both are counted.
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
    double f1 = 0.0;
    ContactReport report;
  };
  struct Counts {
    int whisks = 0;
    int episodes = 0;
    int reports = 0;
    int no_radial = 0;       // touched whiskers without an r estimate
    int no_orientation = 0;  // touched whiskers whose episode had no orientation
  };

  explicit WhiskEvidence(std::vector<WhiskerMount> mounts);

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
      fill(entries_[w], w, ep, c, onset, poseAt(ep.start_sample + static_cast<std::uint64_t>(peak)));
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

 private:
  void fill(Entry& e, std::size_t w, const signal::ContactEpisode& ep,
            const signal::WhiskerContact& c, const Pose2& onset, const Pose2& peak) const;
  struct Sample {
    Pose2 pose;
    std::uint32_t mask = 0;
  };
  std::vector<WhiskerMount> mounts_;
  std::vector<Entry> entries_;
  std::vector<Sample> samples_;
  Counts counts_;
};

// An orientation modulo pi as a value in [0, pi) (ContactReport::phi's convention).
double halfTurn(double angle);

}  // namespace crunch
