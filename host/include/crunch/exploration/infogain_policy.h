// `--explore infogain` (docs/EXPLORATION.md, "Information gain and the paper's entropy"): the
// next whisk pose is the one whose outcome tells most about the map per metre it costs.
//
// For a candidate whisk pose c the value is the mutual information between the whisk's outcome
// Y and the map M, I(Y; M) = H(Y) - H(Y | M), in bits, from two sources the model knows of:
//   * the blackboard's hypotheses: posterior draws m_1..m_N (ExploreState::samples,
//     Mapper::drawSamples). For each draw the forward model (whisk_prediction.h) predicts what
//     the whiskers would touch; outcomes equal at the sensor's resolution are one outcome. The
//     draws are equally weighted, so H(Y) is the entropy of the partition of the draws by
//     outcome, and H(Y | M) = 0: the prediction per draw is deterministic once quantised at the
//     resolution (the noise is what the resolution already absorbs). This is Fig. 7 made exact:
//     the unvisited legs of rival tables are exactly where the draws' predictions disagree,
//     and a leg every draw agrees on (or empty space all agree is empty) scores nothing.
//   * what no draw can see: space no whisker has swept (KnownSpace kUnknown) may hold an object
//     the blackboard has no hypothesis for. Objects are a Poisson process of legs with density
//     lambda per m^2; with A the unknown area the whiskers would sweep (marched along each
//     whisker, stopped by occupied cells), the whisk touches something new with
//     p = 1 - exp(-lambda A), a Bernoulli outcome carrying H_b(p) bits. lambda is the
//     Gamma-Poisson posterior mean from a Gamma(1 leg, 1 m^2) prior and the legs the draws hold
//     (their mean count) over the area the robot knows: lambda = (1 + legs) / (1 + known m^2).
//     Legs come four to a table, though: a table with a leg in swept space would have been
//     touched there. With table_prior (off by default) each unswept cell counts its hidden weight
//     (hiddenLegWeights): the prior share of the tables through a leg there (the model's sizes,
//     every orientation, either corner) whose other three legs stand on cells not swept free.
//     An unswept strip narrower than any table's legs are apart counts nothing, deep unswept
//     space counts whole, the frontier counts the tables reaching away from swept space, and A
//     is that weighted area. Off, every unswept cell counts 1.
//     The two sources are added (independent: one concerns hypotheses, the other space that no
//     hypothesis covers).
//   * what the map reports (report_level): the run's product is the map, tables and walls up to
//     the map's tolerance, not the draw. With R the map a draw reports (sameReportedMap), the
//     draws' term is I(Y; R) = H(Y) - H(Y | R), from the joint counts of outcome class and
//     report class. I(Y; R) <= I(Y; M) (R is a function of M), with equality when every draw
//     reports a map of its own. Draws that place one table millimetres apart predict contacts
//     that differ at a whisker's tip or the sweep's end, a whole bit under H(Y); under I(Y; R)
//     they are worth nothing, since whatever the whisk shows, the report is the same. With
//     merge_repeats each draw is first made one world (mergeRepeats): a table held twice is one,
//     an orphan leg on a table's own leg is that leg and is not completed into a second table.
//     With path_sweep the unswept area counts the drive as well as the whisk: on its way to c the body (and the
//     whiskers ahead of it) sweeps a band of the body's width along the planned path, and a
//     leg in that band is touched on the way (a transit touch: the loop stops and whisks
//     there) or bumped. So A = the unknown cells of the band (the body's disc, radius
//     PlannerOptions::robot_radius, the disc KnownSpace::markBody marks, along the
//     DistanceField's shortest-path tree to c) united with those of the whisk at c. The band
//     is summed once per decision over the whole tree (each step adds its disc's leading
//     edge: exact for a path that does not come back within a body width of itself, an upper
//     bound otherwise) and the whisk's cells already in the band's last body widths are not
//     counted twice. Without it (path_sweep false, the default: see InfogainOptions) a policy
//     sees no value in driving through unknown space and nibbles at it a whisk's annulus at a
//     time (docs/EXPLORATION.md).
// score(c) = I(Y; M) / (travel(c) + whisk_cost_m), travel from the DistanceField. The whisk
// itself costs time (8 s: pi/12 each way at pi/24 rad/s, and back), counted as the metres the
// base would drive in that time. A pose already whisked (within resolution-sized tolerance)
// would repeat its outcome exactly and scores 0; so does a candidate within the driving loop's
// arrival tolerance (ExploreState::arrival_tolerance) of the pose just whisked, at its heading:
// the loop counts it reached where the robot stands and whisks there again (one l_room run
// whisked one spot 30 times over). A goal the robot went to and whisked at is whisked too, at
// the goal's own pose: the loop stops anywhere within its tolerance of a goal, so the pose it
// whisked at is not the candidate it was sent for (the default arena chose one goal 5.1 cm from
// the robot six times in twenty whisks). Stops ("no candidate worth its travel") when
// the best score is at most PolicyOptions::min_bits_per_metre.
//
// Candidates: a lattice over the costmap's free cells (candidate_spacing, candidate_headings)
// whose travel is finite, and for every leg of every draw the poses at whisker reach facing it
// from 8 directions (the poses that would settle that leg).
//
// Randomness: the rng completes the draws' orphan legs (InfogainOptions::complete_orphans); ties
// go to the first candidate. Allocation: in next().
#pragma once

#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "crunch/exploration/policy.h"
#include "crunch/exploration/whisk_prediction.h"
#include "crunch/mapping/fused_map.h"

namespace crunch::exploration {

struct InfogainOptions {
  // Metres of driving that one whisk's 8 s are worth: the time at the explore loop's cruise
  // speed (0.2 m/s, the Create's, session/explore_loop.h).
  double whisk_cost_m = 1.6;
  // Distance from the robot's centre at which a leg-aimed candidate puts the leg: the middle of
  // the whiskers' span (rim 0.165 m .. tip 0.305 m).
  double aim_distance = 0.235;
  double prior_legs = 1.0;     // Gamma prior on the leg density: shape (legs) ...
  double prior_area_m2 = 1.0;  // ... and rate (m^2)
  // Count the unknown band swept on the way to a candidate. Off by default: measured on the
  // default arena (gaussian sensor, 30 m, 8 seeds) it drives more and whisks less (41 against
  // 118 whisks) for a lower recall per metre (0.67 against 0.88); on hil_two_tables with the
  // physics sensor (10 m, 4 seeds) 0.75 against 0.63 (docs/EXPLORATION.md, "Driving through
  // unknown space").
  bool path_sweep = false;
  // Complete each draw's orphan legs into the tables they imply before scoring
  // (draw_completion.h): the draws then disagree about where a once-touched leg's other legs
  // stand, as the posterior does, instead of agreeing that nothing stands there. On by default:
  // docs/EXPLORATION.md ("Orphan legs: the tables a draw implies") has the measurement.
  bool complete_orphans = true;
  int completion_tries = 64;
  // Weigh each unswept cell by the prior probability that a table with a leg there could still
  // be undiscovered: that its other three legs stand on cells of the region not swept free
  // (hiddenLegWeights). Off (the default): every unswept cell counts whole, legs as independent
  // points. Measured on (rooms model, seeds 1-5), it cuts the mean travel to recall 0.9 on
  // l_room from 18.3 to 13.6 m and on adjacent_tables from 32.1 to 23.0 m, but never finds
  // table_at_wall's tables flush against the walls within 50 m: once discovery is valued as the
  // prior says, the draws' residual disagreement about a mapped table (0.5-1.4 bits a whisk)
  // outbids the thin strips along the walls, where few orientations of a table fit
  // (docs/EXPLORATION.md "The bar on every scene measured so far, and where an undiscovered
  // table can hide").
  bool table_prior = false;
  // Score the information about the map the run reports, I(Y; R), not about the draw, I(Y; M):
  // R is the draw's tables (clashing ones merged, withoutClashes) and walls up to the map's
  // tolerance (sameReportedMap with `report`). Draws that report the same map but predict
  // different contacts (a whisker's tip grazing a leg the draws place millimetres apart) then
  // tell the report nothing (docs/EXPLORATION.md "What the map reports, and a map that loses a
  // table it had"). Off (the default), R is the draw itself and the value is H(Y). Measured with
  // merge_repeats (50 m, seeds 1-5) the mean travel to recall 0.9 went from 32.0 to 34.6 m on
  // table_at_wall, from 28.1 (four seeds reaching it) to 33.3 (five) on adjacent_tables, and
  // from 29.4 to 33.8 on interior_walls: no gain beyond the seeds' noise, so both stay off.
  bool report_level = false;
  // Merge each draw's repeats before scoring (mergeRepeats, draw_completion.h): a table held
  // twice is one, an orphan leg on a table's leg is that leg. Off by default (see above).
  bool merge_repeats = false;
  // The map's tolerance: FuseOptions' defaults, the vote's (compare_sizes follows the model).
  FuseOptions report;
  WhiskPredictionOptions prediction;
};

// What one candidate is worth (for tests and pictures).
struct CandidateValue {
  Pose2 pose;
  double sample_bits = 0.0;   // H of the draws' outcome partition
  double unknown_bits = 0.0;  // H of touching something in unswept space (path and whisk)
  double unknown_m2 = 0.0;    // that unswept area, each cell weighted by hiddenLegWeight
  double travel_m = 0.0;
  double score = 0.0;         // bits per metre
};

class InfogainPolicy final : public ExplorePolicy {
 public:
  InfogainPolicy(const PolicyOptions& options, const InfogainOptions& infogain = {});
  ExplorePolicyKind kind() const override { return ExplorePolicyKind::kInfogain; }
  int samplesWanted() const override { return options_.samples; }
  Decision next(const ExploreState& state, Rng& rng) override;

  // The value of whisking at `pose` in `state` (uses the state's samples and known space).
  CandidateValue value(const ExploreState& state, const Pose2& pose);
  // Candidates of the last next(), with their values (best first is not guaranteed).
  const std::vector<CandidateValue>& lastCandidates() const { return values_; }
  // lambda (legs per m^2) used by the last next() or value().
  double legDensity() const { return lambda_; }
  // The last next()'s or value()'s hiddenLegWeight per cell (KnownSpace order, iy * nx + ix).
  std::span<const float> hiddenWeights() const { return hidden_; }

 private:
  void prepare(const ExploreState& state);
  // The draws' objects within reach of `position` (flat lists, per-draw ranges) and which
  // draws share them; sampleBits(pose) needs gather(pose.position()) first.
  void gather(const Vec2& position);
  double sampleBits(const Pose2& pose);
  // report_of_, report_count_ and report_bits_ for the state's draws (after obstacles_).
  void reportClasses(const ExploreState& state);
  // The map's tolerance for `model`: InfogainOptions::report, sizes compared when it sizes tables.
  FuseOptions reportTolerance(const ModelParams& model) const;
  // The unknown cells each ray from `position` would sweep; unknownBits(pose) needs
  // march(known, pose.position()) first. Both need prepare() (the whiskers' radii).
  void march(const KnownSpace& known, const Vec2& position);
  // An upper bound on any heading's bits at the gathered and marched position, whose path
  // sweeps `band` unknown cells (weighted).
  double positionBound(double cell, double band) const;
  // An upper bound on the hidden weight a whisk at `p` can count: hidden_ summed over the square
  // of cells within rmax_ of p (hidden_sat_, built by prepare()).
  double hiddenNear(const KnownSpace& known, const Vec2& p) const;
  double unknownBits(const ExploreState& state, const Pose2& pose, double* area_m2 = nullptr);
  // band_: unknown cells swept by the body along the shortest-path tree (path_sweep), each
  // counting its hidden weight.
  void sweepBand(const ExploreState& state);
  // Stamps the body's discs of the path's last cells before `position`, as far back as a whisk
  // there can reach (unknownBits then skips them).
  void stampPathEnd(const ExploreState& state, const Vec2& position);
  double bandAt(const ExploreState& state, const Vec2& p) const;
  bool whiskedBefore(const Pose2& pose) const;

  PolicyOptions options_;
  InfogainOptions io_;
  WhiskPredictor predictor_;
  std::vector<WhiskObstacles> obstacles_;        // one per draw
  std::vector<std::vector<WhiskerContact>> outcomes_;  // one per draw, scratch
  std::vector<int> cls_count_;
  std::vector<size_t> rep_scratch_;
  std::vector<int> cls_of_;
  std::vector<int> near_legs_, near_walls_, leg_begin_, wall_begin_, uniq_;
  bool any_near_ = false;
  int n_rays_ = 8;
  std::vector<int> ray_begin_, ray_cells_;
  std::vector<double> ray_radius_;
  mutable std::vector<int> bound_scratch_;
  std::vector<int> stamp_;
  int stamp_now_ = 0;
  std::vector<float> hidden_;       // per cell: hiddenLegWeight (1 without table_prior)
  std::vector<double> hidden_sat_;  // its summed-area table, (nx + 1) x (ny + 1)
  std::vector<double> band_;        // per cell: the hidden weight of the band's unknown cells
  std::vector<int> path_stamp_;     // per cell: the position whose path end covers it
  int path_stamp_now_ = 0;
  std::vector<int> disc_dx_, disc_dy_;  // the body's disc, cell offsets
  std::vector<int> edge_begin_, edge_dx_, edge_dy_;  // per step direction: its leading edge
  double ring_cells_max_ = 0.0;     // cells one whisk can count at most (a bound)
  double rmin_ = 0.0, rmax_ = 0.0;  // the whiskers' bases and tips from the centre (prepare)
  double lambda_ = 1.0;
  std::vector<Pose2> whisked_;
  // The pose whisked since the last decision (where the robot stands), and the loop's arrival
  // tolerance (ExploreState::arrival_tolerance): a candidate within it is that whisk again.
  std::optional<Pose2> just_whisked_;
  double arrival_tol_ = 0.0;
  int whisks_seen_ = 0;
  std::optional<Pose2> last_goal_;  // the last decision's goal, whisked once whisks grow
  std::vector<MapSample> completed_;  // next(): the state's draws with their orphans completed
  std::vector<CandidateValue> values_;
  // Per draw, its reported map's class (report_level; else the draw's own index), the classes'
  // sizes, and H(R): I(Y; R) is at most H(R).
  std::vector<int> report_of_, report_count_;
  double report_bits_ = 0.0;
  std::vector<int> joint_;  // scratch: outcome class x report class counts
};

// Whether two draws report the same map: as many tables and walls, and a one-to-one match of
// tables agreeing within `tolerance` (tablesAgree: centre, angle, and sizes when compare_sizes)
// and of walls whose ends lie within tolerance.radius of each other's (either way round). The
// tables should be without clashes (withoutClashes), as a report's are.
bool sameReportedMap(std::span<const MapTable> a_tables, std::span<const MapWall> a_walls,
                     std::span<const MapTable> b_tables, std::span<const MapWall> b_walls,
                     const FuseOptions& tolerance);

// The tables a leg of an undiscovered table may belong to, as cell offsets from that leg to the
// table's other three legs with their prior weights (summing to 1): the model's sizes (the paper's
// one; the rooms model's catalog size at catalog_weight and the uniform size prior's midpoints of
// a 4 x 2 grid over its sides, the rest), every orientation in 12 steps and both mirror images
// (which corner the leg is). Legs flush in the corners, leg side the model's (mid-range when
// sized).
struct HiddenTableOffsets {
  std::vector<int> dx, dy;     // 3 per configuration, in cells
  std::vector<double> weight;  // 1 per configuration
};
HiddenTableOffsets hiddenTableOffsets(const ModelParams& model, double cell);

// Per cell of `known` (iy * nx + ix), the prior probability that a leg there belongs to a table
// the robot has not yet touched: 0 unless the cell is unknown; else the weight of the
// configurations whose other three legs all stand in the region on cells not swept free
// (unknown or occupied: a table may stand flush against a wall, its legs on the cells the wall's
// contacts mark). A table with a leg in swept space would have been touched there (a leg is an
// obstacle the sweep would have met), so the posterior of an undiscovered table given what has
// been swept is this restriction of its uniform prior (position, orientation, size). An unswept
// strip narrower than any table's legs are apart, or a pocket in swept space, holds no
// undiscovered table: sweeping it tells nothing new about the map.
void hiddenLegWeights(const KnownSpace& known, const HiddenTableOffsets& offsets, std::vector<float>& out);

// H_b(p) in bits.
double binaryEntropyBits(double p);
// The entropy of a whisk's outcome over `area` m^2 of unswept space with legs a Poisson process
// of density `lambda`: no touch, or a first touch at one of area / resolution^2 places.
double unknownOutcomeBits(double lambda, double area, double resolution);

}  // namespace crunch::exploration
