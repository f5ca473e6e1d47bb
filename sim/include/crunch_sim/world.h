// The simulated arena as ODE collision geometry (paper §2.8: "ODE ... for whisker contact
// detection"). Following ARCHITECTURE §3, it holds only what a whisker or the robot's body can
// touch: the walls and the table legs. Table tops stand above the whisker plane and the floor
// is never touched by the horizontal whiskers, so neither is built. There are no bodies or
// dynamics: the world answers geometric queries (ray casts, body overlap) only.
//
// Boxes built from a Scene:
//   - each wall of Scene::allWalls() is a box kWallThickness thick and kWallHeight tall standing
//     on the floor. A wall that lies on the arena boundary is pushed outward by its thickness so
//     its inner face is the boundary itself and the free arena is exactly [0,width]x[0,depth];
//     an interior wall straddles its segment (faces kWallThickness/2 either side).
//   - each leg of TableSpec::legs() is a box of the leg's footprint, kLegHeight tall.
//
// Ownership: every ODE handle is owned by a unique_ptr inside the World; the ODE library itself
// is initialised by the first live World and closed with the last (reference-counted).
// Thread-safety: none. The const queries reuse scratch geoms, and the system ODE is built
// without ODE_EXT_mt_collisions (its collision scratch is global), so all Worlds must be used
// from one thread at a time.
#pragma once

#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/robot/shapelet.h"  // kRobotRadius
#include "crunch/scene/scene.h"

// ODE's handle types (dSpaceID is dxSpace*, dGeomID is dxGeom*); <ode/ode.h> stays in world.cc.
struct dxSpace;
struct dxGeom;

namespace crunch::sim {

inline constexpr double kWallThickness = 0.02;  // metres
inline constexpr double kWallHeight = 0.5;      // metres
inline constexpr double kLegHeight = 0.7;       // metres
inline constexpr double kBodyHeight = 0.1;      // robot body height, metres (cf. bodyCollides)

// The nearest surface a ray meets.
struct RayHit {
  double distance = 0.0;  // from the ray origin along the ray, metres
  Vec2 point;             // hit point in the arena plane
  Vec2 normal;            // unit, in the plane, out of the surface toward the ray origin
};

namespace detail {
// Holds ODE initialised while any instance lives (dInitODE2 on 0 -> 1, dCloseODE on 1 -> 0).
class OdeLibraryRef {
 public:
  OdeLibraryRef();
  ~OdeLibraryRef();
  OdeLibraryRef(const OdeLibraryRef&) = delete;
  OdeLibraryRef& operator=(const OdeLibraryRef&) = delete;
};
struct SpaceDeleter {
  void operator()(dxSpace* space) const;
};
struct GeomDeleter {
  void operator()(dxGeom* geom) const;
};
}  // namespace detail

class World {
 public:
  // Builds the collision geometry of `scene` (walls and legs only; see above).
  static std::unique_ptr<World> build(const Scene& scene);

  World(const World&) = delete;
  World& operator=(const World&) = delete;
  ~World();

  // Casts a horizontal ray at height `z` from `origin` along `heading` (radians) for `length`
  // metres. Returns the nearest hit, or nullopt if nothing lies within `length` (or length is
  // not positive, or an argument is not finite). Does not allocate.
  std::optional<RayHit> castRay(Vec2 origin, double heading, double length, double z) const;

  // True if the robot body (a cylinder of radius kRobotRadius standing on the floor at `pose`)
  // intersects any wall or leg: exactly when the body's circle overlaps a box footprint. A
  // non-finite pose counts as colliding.
  // The ODE probe is a capsule, not a cylinder: ODE 0.16's cylinder-box test reports nothing
  // once a box passes right through the cylinder (measured: it misses about a quarter of the
  // overlapping positions against a 0.02 m wall). A vertical capsule of the body's radius whose
  // caps stay between the floor and the lowest box top meets every box (all are vertical prisms
  // standing on the floor) exactly where the body's circle meets the box's footprint.
  bool bodyCollides(const Pose2& pose) const;

  // The candidates whose body does not collide, in their original order. If `skipped` is not
  // null it receives the number of candidates removed.
  std::vector<Pose2> reachablePoses(const std::vector<Pose2>& candidates, int* skipped) const;

  // The footprint of every box built (walls first, then legs), for tests and drawing.
  const std::vector<OrientedRect>& footprints() const { return footprints_; }

  // The point of any wall's or leg's outline nearest to p (a bumper that knows where it was
  // pressed); nullopt in a world with nothing built.
  std::optional<Vec2> nearestSurfacePoint(const Vec2& p) const;

  // The ODE space holding the walls and legs (static geoms: no bodies, no geom data), for a
  // dynamics simulation that collides its own geoms against them (WhiskeredRobot). Callers may
  // collide against it but must not add, remove, move or destroy its geoms.
  dxSpace* space() const { return space_.get(); }

 private:
  World();
  void addBox(const OrientedRect& footprint, double height);
  // Fills the broad phase below from footprints_ (World::build, once every box is added).
  void buildGrid();
  // The geoms whose footprint's bounding box meets the box [lo, hi], in ODE's simple-space order
  // (the newest first, as dSpaceCollide2 visits them), into `out`; false when more than
  // out.size() do (the caller then asks the whole space).
  bool candidates(const Vec2& lo, const Vec2& hi, std::span<int> out, int& n) const;
  // What dSpaceCollide2(geom, space) does, through the broad phase: callback(data, geom, box)
  // for each box whose bounding box meets [lo, hi] (geom's own, with a margin), in the space's
  // order; the whole space when the candidates overflow.
  void collideNear(dxGeom* geom, const Vec2& lo, const Vec2& hi, void* data,
                   void (*callback)(void*, dxGeom*, dxGeom*)) const;

  using SpacePtr = std::unique_ptr<dxSpace, detail::SpaceDeleter>;
  using GeomPtr = std::unique_ptr<dxGeom, detail::GeomDeleter>;

  // Declaration order is destruction order reversed: geoms go before their space, and ODE is
  // closed only after every handle is gone.
  detail::OdeLibraryRef ode_;
  SpacePtr space_;              // does not destroy its geoms; geoms_ owns them
  std::vector<GeomPtr> geoms_;  // the walls and legs, inside space_
  std::vector<OrientedRect> footprints_;
  // The broad phase of castRay and bodyCollides (ODE's simple space, like its hash and SAP
  // spaces, tests a lone geom against every geom of the space: on a large floor's hundreds of
  // legs that was a third of a run). A uniform grid of 0.5 m cells (world.cc) over the boxes'
  // bounding boxes: cell_start_[c] .. cell_start_[c + 1] index cell_items_, the geoms whose
  // bounding box meets cell c (CSR, filled once). A geom spanning several cells is reported from
  // the first cell that it and the query share only.
  struct CellRange {
    int x0, y0, x1, y1;
  };
  Vec2 grid_lo_{0.0, 0.0};
  int grid_nx_ = 0, grid_ny_ = 0;
  std::vector<int> cell_start_;
  std::vector<int> cell_items_;
  std::vector<CellRange> geom_cells_;    // per geom, the cells its bounding box meets
  std::vector<Vec2> geom_lo_, geom_hi_;  // per geom, its footprint's bounding box
  GeomPtr ray_;                          // scratch ray for castRay, in no space
  GeomPtr body_;                         // scratch capsule for bodyCollides, in no space
};

}  // namespace crunch::sim
