// What a posterior draw implies about legs no whisker has touched yet (docs/EXPLORATION.md,
// "Orphan legs: the tables a draw implies"): each leg the draw holds without a table (eq. 13's
// null parent; MapSample::legs) is completed into a four-legged object drawn from the model's
// own prior, conditioned on what the robot knows.
//
// A chain at the posterior's temperature (beta = 1) keeps a leg touched once as an orphan: a
// table through it that no other contact supports costs three missing legs (eq. 24), and the
// eight placements (times every size, under the rooms model) split what mass such tables have.
// The draws then agree that nothing stands around that leg, and a policy that scores where draws
// disagree (infogain) sees nothing to learn there. In a room, though, a leg stands under an
// object: its other legs are somewhere at a table's reach, and where exactly is what the next
// whisks can tell. So each orphan leg L at p, its faces at angle phi (modulo pi/2), side s, gets
// a parent T drawn from
//   p(T | L is one of T's legs, the known floor) ∝ p(T) [L at a corner of T] [T's other legs
//   stand where no whisker swept free and inside the region] [T's top overlaps no table of the
//   draw]
// by rejection: T's axes along L's faces (theta = phi + j pi/2, j in {0, 1}: a table's pose is
// meaningful modulo pi), the corner k in 0..3 holding L, each uniform, and its size from the
// model's prior (ModelParams: the paper's one size, or under the rooms model its mixture: the
// catalog's size at catalog_weight, each side Gaussian at catalog_sigma, else width and depth
// uniform over the prior's region; L's own leg side), the draw kept when every other leg's
// centre lies in a cell that is not known free (KnownSpace kFree: a whisker or the body passed
// there without touching; negative evidence, p_miss = 0.05, taken as certain) and inside the
// region, and the top overlaps none of the draw's tables (eq. 25, taken as certain). Every
// accepted T is an exact draw from that conditional; nothing is fitted, so it holds for any room
// the prior covers. An orphan for which `tries` proposals all fail (a leg boxed in by swept
// floor: a stray post, or a contact the chain could not explain) stays a lone leg.
//
// Randomness: only the Rng passed in. Allocation: appends to the draw's vectors.
#pragma once

#include "crunch/blackboard/params.h"
#include "crunch/core/rng.h"
#include "crunch/exploration/known_space.h"
#include "crunch/mapping/fused_map.h"
#include "crunch/mapping/map.h"

namespace crunch::exploration {

// Completes every orphan leg of `draw` (draw.legs) into a table appended to draw.tables and
// removes it from draw.legs; an orphan whose `tries` proposals (>= 1) are all rejected stays.
// Returns the number completed.
int completeOrphanLegs(MapSample& draw, const KnownSpace& known, const ModelParams& model,
                       Rng& rng, int tries = 64);

// One world per draw (docs/EXPLORATION.md "What the map reports"): a chain at the posterior's
// temperature may hold one table twice (eq. 25 charges two overlapping tops only log eps_b) or
// keep an orphan leg on a table's own leg (the same contacts explained twice). Neither is a second
// object: of the draw's tables, each that clashes with one kept before it is dropped
// (withoutClashes, the fused map's rule), and an orphan leg whose centre lies within a leg's side
// of a kept table's leg centre is that leg, and is dropped. Left alone, the orphan would be
// completed into a table beside the one it stands under, which nothing supports, and the
// duplicate's legs, millimetres off, would make the draws' predictions differ where they agree.
// Returns the number of tables and legs removed.
int mergeRepeats(MapSample& draw, const FuseOptions& fuse);

}  // namespace crunch::exploration
