// Walls across the global inference's chains (issue 13, --model walls or rooms): each chain ends
// with its own walls; a fused wall is a group of walls along one line (directions within
// `angle`, every end within `offset` of the group's line) that overlap or nearly meet along it
// (gap at most `gap`). Its score is the fraction of chains with a wall in the group; groups with
// score >= min_score are kept, spanning the median of the chains' ends along the group's line.
// Then walls end at walls (docs/BLACKBOARD.md "Walls end at walls"): a kept wall's end within
// `junction` of another kept wall's segment, at kWallJunctionAngle or more, is an end the chains
// joined to that wall, and is reported where the two lines cross: a corner's two ends at its
// corner, a T's stem on the wall it meets.
#pragma once

#include <vector>

#include "crunch/blackboard/hypotheses.h"
#include "crunch/mapping/map.h"

namespace crunch {

struct WallFuseOptions {
  double angle = 10.0 * kPi / 180.0;  // radians, modulo pi
  double offset = 0.05;               // metres across the line
  double gap = 0.10;                  // metres along it
  double min_score = 0.5;
  // Metres; 0 leaves every end at the chains' median. The mapper passes the model's
  // ModelParams::wallLinkRadius(), the distance within which the log joint counts an end joined.
  double junction = 0.0;
};

// chains[i]: the walls chain i ended with.
std::vector<MapWall> fuseWalls(const std::vector<std::vector<WallHyp>>& chains,
                               const WallFuseOptions& opt = {});

// How far a footprint reaches to each side of a wall's line, over the part of it within the
// wall's length: `front` on the left of a->b, `behind` on the right; both 0 when no part of it
// lies within the length.
struct WallStraddle {
  double front = 0.0, behind = 0.0;
};
WallStraddle straddle(const OrientedRect& r, const Vec2& a, const Vec2& b);

// The map is one world: no table stands through a wall. A kept table whose footprint reaches
// more than `band` to both sides of a kept wall's line (ModelParams::wall_solid_depth, the
// least thickness of a wall: a table flush with a wall's face, a fit a few millimetres into it,
// stays) is dropped when the wall's score is at least its own, and the wall otherwise. Inside
// the chains the overlap is only charged (log eps_b), so they can pass through it while they mix;
// the fused map reports the more probable of the two (docs/BLACKBOARD.md "One world").
void keepOneWorld(std::vector<MapTable>& tables, std::vector<MapWall>& walls, double band);

}  // namespace crunch
