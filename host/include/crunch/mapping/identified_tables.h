// Which of a chain's tables the evidence identifies (issue 13; docs/BLACKBOARD.md "A table whose
// size the evidence leaves open", "A table whose place the evidence leaves open"). A map table
// has a size and a place; a chain may hold a table whose size (rooms model) or place (walls
// model) the contacts and the negative evidence leave open, and the map cannot report it. Each
// certainty is the posterior mass, at beta = 1 and given the chain's structure, of the chain's
// own choice among the alternatives the model allows. The global inference's chains and the
// pooled chain pass their tables through identifiedTablesOf before the fusion (global_chain.h,
// mapper.cc); the paper's model is left as its figures were.
#pragma once

#include <cstdint>
#include <vector>

#include "crunch/blackboard/blackboard.h"
#include "crunch/core/rng.h"
#include "crunch/mapping/map.h"

namespace crunch {

// How surely the evidence fixes the size of `board`'s live table `id` (ModelParams::sized(),
// the rooms model; issue 13; docs/BLACKBOARD.md "A table whose size the evidence leaves open"):
// the product, over the four edges of its top, of the posterior mass of that edge's position
// within +-tolerance/2 of where it is. Each edge's posterior is its conditional with everything
// else held and the table's legs its own: exp(J) at beta = 1, J the log joint over the table and
// its legs (Blackboard::localEnergy) with each leg's eq. 9 density the table's branch
// alpha_L exp(-Delta_TL), not the null prior's; a leg that explains no contact better than the
// background c_S is carried with its corner (the table's guess, not evidence). Quadrature over
// the size prior's range in steps of tolerance/5. Near 1 when touched legs or negative evidence
// pin every edge; small when an edge is free (a table touched on the two legs of one side: its
// other side could be anywhere nothing swept). The board is left as it was (the table and its
// carried legs are moved and restored; cached energies are invalidated, as by any change
// outside a sweep).
double sizeCertainty(Blackboard& board, int32_t id, double tolerance);
// How surely the evidence fixes where a table of the model's one size stands (ObjectModel::kWalls;
// docs/BLACKBOARD.md "A table whose place the evidence leaves open"): among the paper's 8
// placements of the table with its first touched leg at a corner (4 corners x 2 axes) that put
// every touched leg at a corner of its own, the posterior mass of the chain's own, each weighed
// as sizeCertainty weighs an edge (exp(J) at beta = 1 given the structure, untouched legs
// carried to the free corners). 1 for three legs in an L (one placement fits); about 1/2 for
// the two legs of one side when nothing tells the table's two mirror images apart; 1 when no
// leg is touched (nothing to place it by). The board is left as it was.
double placementCertainty(Blackboard& board, int32_t id);
// A draw of what table `id` leaves open, from the same conditionals the certainties integrate
// (exploration's posterior draws, Mapper::drawSamples; docs/EXPLORATION.md "Tables the evidence
// leaves open"): under the rooms model a Gibbs scan of its four edges, each drawn from its
// conditional given the others as drawn so far (quadrature in steps of `step` over the size
// prior, guessed legs carried with their corners), under the walls model one of the placements
// placementCertainty weighs, drawn by its weight. A table with three or more touched legs, or
// none, is returned as the chain holds it; under the paper's model always. At beta = 1 a chain
// barely moves between draws (docs/EXPLORATION.md "Posterior draws"), so without this every draw
// holds the same guess for a table's untouched side. The board is left as it was.
MapTable drawOpenTable(Blackboard& board, int32_t id, double step, Rng& rng);
// The map tables of `board`'s live tables the evidence identifies: under the rooms model those
// whose sizeCertainty is above one half (each of its own size), under the walls model those
// whose placementCertainty is above one half, under the paper's model all (its figures stay).
// A chain's MAP without the tables it only guessed.
void identifiedTablesOf(Blackboard& board, double tolerance, std::vector<MapTable>& out);

}  // namespace crunch
