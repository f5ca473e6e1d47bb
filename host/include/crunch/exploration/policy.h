// Where to whisk next (paper §2.9; docs/EXPLORATION.md): one interface, five policies.
//   grid      the paper's pre-determined pose list, in order (its §2.8 experiment);
//   random    a random reachable whisk pose: the baseline the paper compares with (§3.4);
//   frontier  the classical nearest-frontier explorer (Yamauchi 1997): the cheapest pose whose
//             whiskers reach unknown space next to known free space;
//   entropy   the paper's §2.9 as written: a foveal grid of leg-occupancy probabilities from the
//             hot sampler's frequencies (eqs. 31-36), the whisk pose whose cells carry the most
//             expected entropy reduction (eq. 34's dH);
//   infogain  ours: the mutual information between a whisk's predicted outcome and the map,
//             from posterior samples of the blackboard, per metre of travel.
// A policy sees an ExploreState (what the robot knows now) and returns a Decision: a goal pose
// or none, with the reason (nothing reachable; no candidate worth its travel; the list is done).
//
// Randomness: only the Rng passed in. Thread-safety: none. Allocation: a policy may allocate in
// next() (its candidate list), never inside the sampler.
#pragma once

#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "crunch/blackboard/params.h"
#include "crunch/core/geometry.h"
#include "crunch/core/result.h"
#include "crunch/core/rng.h"
#include "crunch/exploration/known_space.h"
#include "crunch/exploration/path_planner.h"
#include "crunch/mapping/map.h"
#include "crunch/robot/whiskers.h"

namespace crunch::exploration {

enum class ExplorePolicyKind { kGrid, kRandom, kFrontier, kEntropy, kInfogain };
// "grid", "random", "frontier", "entropy", "infogain"; an Error naming --explore and the
// choices otherwise.
Result<ExplorePolicyKind> explorePolicyByName(const std::string& name);
const char* explorePolicyName(ExplorePolicyKind kind);

// What a policy sees when it decides.
struct ExploreState {
  Pose2 robot;                          // where the robot is (odometry)
  const KnownSpace& known;              // swept, touched and mapped cells
  const Costmap& costmap;               // where the robot's centre may stand
  const DistanceField& travel;          // path cost from the robot to every cell
  std::span<const MapSample> samples;   // posterior draws (as many as samplesWanted())
  const std::vector<WhiskerMount>& mounts;
  const ModelParams& model;             // the blackboard's priors (object sizes, densities)
  std::span<const Pose2> grid_poses;    // the scene's pose list (grid policy)
  int whisks = 0;                       // whisks done so far
  double travel_m = 0.0;                // metres driven so far
  // --teleport: the robot jumps to the goal (the paper's idealisation), so a goal need not be
  // reachable by a path; the grid policy then visits every pose of the list, as the paper did.
  bool teleport = false;
  // Metres from a goal within which the driving loop counts it reached and whisks where it
  // stands (ExploreLoop::Options::waypoint_tolerance; 0 teleporting): a candidate that close to
  // the pose just whisked, at its heading, is that whisk again.
  double arrival_tolerance = 0.0;
  // Goals the driving loop gave up (not reached: no path, repeated bumps, out of time), and the
  // radius about each within which no whisk pose is chosen (ExploreLoop::Options). The well-known
  // frontier explorers' blacklist: a goal near one given up is approached the same way and fails
  // the same way, so choosing it again boxes the robot in.
  std::span<const Vec2> given_up{};
  double given_up_radius = 0.0;
};

// Whether a policy may choose a whisk pose at `p`: the robot's centre may stand there, a path
// reaches it, and it is not within given_up_radius of a goal given up.
bool choosable(const ExploreState& s, const Vec2& p);

struct Decision {
  std::optional<Pose2> goal;  // the next whisk pose; nullopt: stop
  std::string why;            // with no goal: why the run should end (for the report)
  double score = 0.0;         // the policy's value of the goal (bits per metre for infogain)
};

class ExplorePolicy {
 public:
  virtual ~ExplorePolicy() = default;
  virtual ExplorePolicyKind kind() const = 0;
  // Posterior draws the policy needs in ExploreState::samples (0: none).
  virtual int samplesWanted() const { return 0; }
  // The next whisk pose. Deterministic for a given state and rng.
  virtual Decision next(const ExploreState& state, Rng& rng) = 0;
};

struct PolicyOptions {
  int samples = 16;            // posterior draws for entropy and infogain; 1..256
  double candidate_spacing = 0.10;  // metres between candidate whisk positions; > 0
  int candidate_headings = 8;  // headings per candidate position; 1..64
  // infogain: stop when no candidate is worth at least this many bits per metre; >= 0.
  double min_bits_per_metre = 0.0;
  Status validate() const;
};

std::unique_ptr<ExplorePolicy> makePolicy(ExplorePolicyKind kind, const PolicyOptions& options);
// The policies, one per file (makePolicy picks one).
std::unique_ptr<ExplorePolicy> makeGridPolicy(const PolicyOptions& options);
std::unique_ptr<ExplorePolicy> makeRandomPolicy(const PolicyOptions& options);
std::unique_ptr<ExplorePolicy> makeFrontierPolicy(const PolicyOptions& options);
std::unique_ptr<ExplorePolicy> makeEntropyPolicy(const PolicyOptions& options);
std::unique_ptr<ExplorePolicy> makeInfogainPolicy(const PolicyOptions& options);

}  // namespace crunch::exploration
