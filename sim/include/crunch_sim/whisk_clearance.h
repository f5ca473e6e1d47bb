// Can an in-place whisk touch anything? A conservative geometric answer, so that the physics
// sensor can leave ODE out of whisks that cannot (PhysicsSensorModel::Options::skip_untouchable,
// docs/WHISKERS.md "Skipping untouchable whisks").
//
// The question: the robot stands at `pose` and turns in place through every heading in
// [pose.theta + from, pose.theta + to]; each whisker of `mounts` is a straight segment from its
// base to its tip, carried rigidly with the body. Does every point of every such segment stay
// farther than `margin` from every wall and leg of the World (World::footprints(), exactly the
// boxes ODE collides the whiskers with)? The boxes are vertical prisms standing on the floor and
// taller than the whisker plane, so the question is a planar one.
//
// How: the straight whiskers at headings k * step apart, each against every box footprint near
// the pose (exact segment-rectangle distance, distanceRectSegment). Between two such headings
// every point of a whisker is within reach * step / 2 of where it was at the nearer one (reach:
// the whisker point farthest from the turning centre; a turn by d moves a point at radius rho by
// 2 rho sin(d / 2) <= rho d), so the swept clearance is at least the smallest sampled distance
// minus reach * step / 2. step is chosen so that this slack is at most margin / 4, and the
// answer is "clear" only if the sampled distances all exceed margin + that slack: never clear
// when some whisker point comes within `margin` of a box; possibly "not clear" when the closest
// approach lies within `margin` + margin / 4 (a conservative no, which costs only time).
//
// What the margin must cover is the caller's business (the real whisker bends, has a radius,
// the turn overshoots its target): see PhysicsSensorModel::Options::skip_margin.
//
// Thread-safety: reads the World's footprints only (no ODE call), so it may run beside other
// readers. Allocation: none.
#pragma once

#include <span>

#include "crunch/core/geometry.h"
#include "crunch/robot/whiskers.h"
#include "crunch_sim/world.h"

namespace crunch::sim {

// True if no straight whisker of `mounts` comes within `margin` (metres, > 0) of any wall or leg
// while the robot at `pose` turns in place through headings pose.theta + [from, to] (radians,
// from <= to). See the top of this file for how exact the answer is. False for a non-finite
// argument, margin <= 0 or from > to.
bool inPlaceWhiskClear(const World& world, std::span<const WhiskerMount> mounts, const Pose2& pose,
                       double from, double to, double margin);

// True if no straight whisker of `mounts` comes within `margin` (metres, > 0) of any wall or leg
// while the robot drives straight from `from` along its heading for `distance` metres (>= 0),
// the heading fixed: the approach the physics sensor makes to a pose near a wall or leg. Every
// whisker point moves by the same vector, so positions `step` apart along the path leave each
// point within step / 2 of a sampled one; step is margin / 2 and the sampled distances must
// exceed margin + step / 2 (conservative as above). False for a non-finite argument, margin <= 0
// or distance < 0.
bool straightPathClear(const World& world, std::span<const WhiskerMount> mounts, const Pose2& from,
                       double distance, double margin);

}  // namespace crunch::sim
