// What a body whisk at a pose would touch if the map were a given sample (paper §2.3, §2.9):
// the forward model that `infogain` scores candidate whisk poses with (docs/EXPLORATION.md,
// "Information gain and the paper's entropy").
//
// The robot turns in place theta0 -> theta0 + A -> theta0 - A -> theta0 (A = pi/12, the
// simulator's RaySensorModel and the real BodyWhisk). Each whisker is a straight, rigid ray of
// its mount's length; over the sweep the sample with the smallest hit distance is the
// whisker's one contact (the deepest bend, eq. 1), exactly as RaySensorModel reports it, but
// against the sample's geometry (tables' four leg squares flush in the corners, as
// TableSpec::legs() places them, and walls as segments) instead of ODE, and without noise.
// Pure geometry: a slab test per leg square and a segment test per wall, on the objects within
// whisker reach only.
//
// Two outcomes are the same at the sensor's resolution when the same whiskers touch and each
// pair of contact points is within `resolution` metres: the noise the sensor adds (eq. 4,
// sigma_r) makes nearer contacts indistinguishable from one whisk (sameOutcome).
//
// Units: metres, radians, arena frame. Thread-safety: none (a predictor owns scratch).
// Allocation: predict() allocates nothing once its scratch has grown to the largest sample.
#pragma once

#include <span>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/mapping/map.h"
#include "crunch/robot/whiskers.h"

namespace crunch::exploration {

struct WhiskPredictionOptions {
  double amplitude = kPi / 12;   // A, radians (RaySensorModel::Options::whisk_amplitude)
  // Heading step of the predicted sweep. Coarser than the simulator's pi/360: at the whisker
  // tip (0.305 m from the centre) pi/90 is 1.1 cm, a fifth of a leg, so a leg within reach is
  // never stepped over and the deepest contact is found to well under the 15 mm resolution.
  double sweep_step = kPi / 90;
  // Two contacts closer than this are one outcome: 3 sigma_r of the realistic regime (5 mm,
  // ARCHITECTURE.md §4), the distance at which two contacts are told apart by one report with
  // >93% probability (|N(0, sqrt(2) sigma_r)| < 3 sigma_r fails 3.4% of the time).
  double resolution = 0.015;

  static WhiskPredictionOptions forSigma(double sigma_r) {
    WhiskPredictionOptions o;
    o.resolution = std::max(0.003, 3.0 * sigma_r);
    return o;
  }
};

// One whisker's predicted contact.
struct WhiskerContact {
  bool hit = false;
  Vec2 point = Vec2::Zero();  // where it touches, arena frame (hit only)
  double distance = 0.0;      // from the whisker's base along it (hit only)
  int object = -1;            // index into the predictor's object list (hit only)
};

// A leg square prepared for ray tests (its rotation's cosine and sine computed once).
struct LegFrame {
  Vec2 centre = Vec2::Zero();
  double c = 1.0, s = 0.0;  // cos, sin of the square's angle
  double hx = 0.0, hy = 0.0;
  double radius = 0.0;      // half-diagonal
};

// The objects a whisk can touch, in arena frame.
struct WhiskObstacles {
  std::vector<OrientedRect> legs;
  std::vector<MapWall> walls;
  std::vector<LegFrame> frames;  // legs prepared (prepare(); assign() calls it)
  void clear() {
    legs.clear();
    walls.clear();
    frames.clear();
  }
  // Fills `frames` from `legs`. predict() prepares on the fly (slower) when they differ in size.
  void prepare();
  // The four leg squares of every table of `sample`, its orphan legs and its walls; `fixed`
  // walls (e.g. the arena's boundary) appended.
  void assign(const MapSample& sample, std::span<const MapWall> fixed = {});
};

// The four leg footprints of a map table (TableSpec::legs()' placement).
std::array<OrientedRect, 4> legSquares(const MapTable& table);

class WhiskPredictor {
 public:
  WhiskPredictor(std::vector<WhiskerMount> mounts, WhiskPredictionOptions options = {});

  // One contact per mount, in mount order, into `out` (resized to the mount count).
  void predict(const Pose2& pose, const WhiskObstacles& obstacles,
               std::vector<WhiskerContact>& out);
  // The same against only the listed legs and walls of `obstacles` (indices; e.g. those
  // nearReach() found for the position); identical to predict() when the lists hold every
  // object within reach.
  void predictNear(const Pose2& pose, const WhiskObstacles& obstacles, std::span<const int> legs,
                   std::span<const int> walls, std::vector<WhiskerContact>& out);
  // Appends the indices of the legs and walls within reach of `position`.
  void nearReach(const Vec2& position, const WhiskObstacles& obstacles, std::vector<int>& legs,
                 std::vector<int>& walls) const;
  // Whether anything of `obstacles` is within the whisk's reach of `position` (the body's
  // radius plus the longest whisker's tip, plus the object's own half-diagonal).
  bool anyInReach(const Vec2& position, const WhiskObstacles& obstacles) const;
  // Distance from the robot's centre beyond which nothing is touched.
  double reach() const { return reach_; }

  const std::vector<WhiskerMount>& mounts() const { return mounts_; }
  const WhiskPredictionOptions& options() const { return options_; }
  // Heading offsets of the predicted sweep: 0, +h .. +A, -h .. -A.
  const std::vector<double>& offsets() const { return offsets_; }

 private:
  std::vector<WhiskerMount> mounts_;
  WhiskPredictionOptions options_;
  std::vector<double> offsets_;
  double reach_ = 0.0;
  std::vector<int> near_legs_, near_walls_;  // scratch: objects within reach
  // Per sweep offset k and mount w (index k * mounts + w), in the robot frame at heading 0:
  // the whisker's base and unit direction after turning by offset k.
  std::vector<Vec2> base_, dir_;
  std::vector<double> spread_;  // per mount: angular spread of the whisker seen from the centre
  std::vector<double> leg_phi_, leg_halfwidth_;  // scratch: the angular screen
  struct Window {
    size_t q;       // index into the near-leg list
    double lo, hi;  // sweep offsets at which the whisker can meet it
  };
  std::vector<Window> rel_;
};

// Same outcome at the sensor's resolution: the same whiskers touch, each contact pair within
// `resolution`.
bool sameOutcome(std::span<const WhiskerContact> a, std::span<const WhiskerContact> b,
                 double resolution);

// First hit of the ray origin + t * dir (|dir| = 1), 0 <= t <= length, with a rectangle's
// outline or a segment; the distance t, or a negative number for none.
double rayRect(const Vec2& origin, const Vec2& dir, double length, const OrientedRect& r);
double raySegment(const Vec2& origin, const Vec2& dir, double length, const Vec2& a,
                  const Vec2& b);

}  // namespace crunch::exploration
