#include "crunch_sim/world.h"

#include <ode/ode.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <functional>
#include <limits>
#include <mutex>

namespace crunch::sim {
namespace detail {
namespace {
std::mutex g_ode_mutex;
int g_ode_users = 0;  // guarded by g_ode_mutex
}  // namespace

OdeLibraryRef::OdeLibraryRef() {
  std::lock_guard<std::mutex> lock(g_ode_mutex);
  if (g_ode_users++ == 0) {
    [[maybe_unused]] const int ok = dInitODE2(0);
    assert(ok && "dInitODE2 failed");
    // Collision queries need the collision data set allocated (for the calling thread; this
    // ODE build keeps it global).
    [[maybe_unused]] const int allocated = dAllocateODEDataForThread(dAllocateFlagCollisionData);
    assert(allocated && "dAllocateODEDataForThread failed");
  }
}

OdeLibraryRef::~OdeLibraryRef() {
  std::lock_guard<std::mutex> lock(g_ode_mutex);
  if (--g_ode_users == 0) dCloseODE();
}

void SpaceDeleter::operator()(dxSpace* space) const { dSpaceDestroy(space); }
void GeomDeleter::operator()(dxGeom* geom) const { dGeomDestroy(geom); }

}  // namespace detail

namespace {

constexpr double kBoundaryTolerance = 1e-9;  // metres: a wall "on" the boundary line

// The body probe (see bodyCollides in world.h): a capsule centred half-way up the walls, its
// caps clear of the floor and of the lowest box top.
constexpr double kProbeZ = 0.5 * kWallHeight;
static_assert(kProbeZ - 0.5 * kBodyHeight - kRobotRadius > 0.0, "probe caps must clear the floor");
static_assert(kProbeZ + 0.5 * kBodyHeight + kRobotRadius < std::min(kWallHeight, kLegHeight),
              "probe caps must stay below the lowest box top");

struct RayQuery {
  double best = std::numeric_limits<double>::infinity();
  dContactGeom contact{};
};

void rayCallback(void* data, dGeomID o1, dGeomID o2) {
  auto* q = static_cast<RayQuery*>(data);
  dContactGeom c;
  if (dCollide(o1, o2, 1, &c, sizeof(dContactGeom)) > 0 && c.depth < q->best) {
    q->best = c.depth;
    q->contact = c;
  }
}

void overlapCallback(void* data, dGeomID o1, dGeomID o2) {
  auto* hit = static_cast<bool*>(data);
  if (*hit) return;
  dContactGeom c;
  if (dCollide(o1, o2, 1, &c, sizeof(dContactGeom)) > 0) *hit = true;
}

// The outward unit normal of the arena boundary side that wall [a, b] lies on, or zero if the
// wall is not on the boundary.
Vec2 boundaryOutward(const WallSpec& w, const Scene& scene) {
  auto on = [](double u, double v, double line) {
    return std::abs(u - line) < kBoundaryTolerance && std::abs(v - line) < kBoundaryTolerance;
  };
  if (on(w.a.x(), w.b.x(), 0.0)) return {-1.0, 0.0};
  if (on(w.a.x(), w.b.x(), scene.width)) return {1.0, 0.0};
  if (on(w.a.y(), w.b.y(), 0.0)) return {0.0, -1.0};
  if (on(w.a.y(), w.b.y(), scene.depth)) return {0.0, 1.0};
  return {0.0, 0.0};
}

constexpr double kGridCell = 0.5;  // metres: a whisker's ray spans one or two cells

// The grid cell holding coordinate v on an axis starting at `origin` with `cells` cells, clamped
// to the grid (a query reaching past the boxes' extent meets its border cells only).
int gridCell(double v, double origin, int cells) {
  const double c = std::floor((v - origin) / kGridCell);
  return static_cast<int>(std::clamp(c, 0.0, static_cast<double>(cells - 1)));
}

}  // namespace

World::World() : space_(dSimpleSpaceCreate(nullptr)) {
  // geoms_ owns the geoms and destroys them before the space goes.
  dSpaceSetCleanup(space_.get(), 0);
  ray_.reset(dCreateRay(nullptr, 1.0));
  // Only the closest hit matters; ODE applies this to trimeshes, boxes return one contact anyway.
  dGeomRaySetClosestHit(ray_.get(), 1);
  body_.reset(dCreateCapsule(nullptr, kRobotRadius, kBodyHeight));  // axis along z
}

World::~World() = default;

void World::addBox(const OrientedRect& footprint, double height) {
  dGeomID box = dCreateBox(space_.get(), footprint.size_x, footprint.size_y, height);
  dGeomSetPosition(box, footprint.pose.x, footprint.pose.y, 0.5 * height);
  dMatrix3 rot;
  dRFromAxisAndAngle(rot, 0.0, 0.0, 1.0, footprint.pose.theta);
  dGeomSetRotation(box, rot);
  geoms_.emplace_back(box);
  footprints_.push_back(footprint);
}

std::unique_ptr<World> World::build(const Scene& scene) {
  std::unique_ptr<World> world(new World());
  for (const WallSpec& w : scene.allWalls()) {
    const Vec2 d = w.b - w.a;
    const double len = d.norm();
    if (len < kBoundaryTolerance) continue;  // a point is no wall
    const double heading = std::atan2(d.y(), d.x());
    const Vec2 mid = 0.5 * (w.a + w.b);
    const Vec2 out = boundaryOutward(w, scene);
    OrientedRect box;
    if (out.isZero()) {
      box = {{mid.x(), mid.y(), heading}, len, kWallThickness};
    } else {
      // Inner face on the boundary; lengthened by the thickness at both ends so neighbouring
      // boundary walls close the corners.
      const Vec2 c = mid + 0.5 * kWallThickness * out;
      box = {{c.x(), c.y(), heading}, len + 2.0 * kWallThickness, kWallThickness};
    }
    world->addBox(box, kWallHeight);
  }
  for (const TableSpec& t : scene.tables) {
    for (const OrientedRect& leg : t.legs()) world->addBox(leg, kLegHeight);
  }
  world->buildGrid();
  return world;
}

void World::buildGrid() {
  const size_t n = footprints_.size();
  geom_lo_.resize(n);
  geom_hi_.resize(n);
  Vec2 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  Vec2 hi = -lo;
  for (size_t i = 0; i < n; ++i) {
    const OrientedRect& r = footprints_[i];
    // The footprint's axis-aligned bounding box: half-extents |c| hx + |s| hy and |s| hx + |c| hy.
    const double c = std::abs(std::cos(r.pose.theta)), s = std::abs(std::sin(r.pose.theta));
    const Vec2 half{c * 0.5 * r.size_x + s * 0.5 * r.size_y,
                    s * 0.5 * r.size_x + c * 0.5 * r.size_y};
    geom_lo_[i] = r.pose.position() - half;
    geom_hi_[i] = r.pose.position() + half;
    lo = lo.cwiseMin(geom_lo_[i]);
    hi = hi.cwiseMax(geom_hi_[i]);
  }
  if (n == 0) return;
  grid_lo_ = lo;
  grid_nx_ = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) / kGridCell)));
  grid_ny_ = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / kGridCell)));
  geom_cells_.resize(n);
  for (size_t i = 0; i < n; ++i)
    geom_cells_[i] = {
        gridCell(geom_lo_[i].x(), lo.x(), grid_nx_), gridCell(geom_lo_[i].y(), lo.y(), grid_ny_),
        gridCell(geom_hi_[i].x(), lo.x(), grid_nx_), gridCell(geom_hi_[i].y(), lo.y(), grid_ny_)};
  const size_t cells = static_cast<size_t>(grid_nx_) * static_cast<size_t>(grid_ny_);
  cell_start_.assign(cells + 1, 0);
  for (const CellRange& g : geom_cells_)
    for (int y = g.y0; y <= g.y1; ++y)
      for (int x = g.x0; x <= g.x1; ++x) ++cell_start_[static_cast<size_t>(y * grid_nx_ + x) + 1];
  for (size_t c = 0; c < cells; ++c) cell_start_[c + 1] += cell_start_[c];
  cell_items_.resize(static_cast<size_t>(cell_start_[cells]));
  std::vector<int> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (size_t i = 0; i < n; ++i) {
    const CellRange& g = geom_cells_[i];
    for (int y = g.y0; y <= g.y1; ++y)
      for (int x = g.x0; x <= g.x1; ++x)
        cell_items_[static_cast<size_t>(fill[static_cast<size_t>(y * grid_nx_ + x)]++)] =
            static_cast<int>(i);
  }
}

bool World::candidates(const Vec2& lo, const Vec2& hi, std::span<int> out, int& n) const {
  n = 0;
  if (geom_cells_.empty()) return true;
  const int qx0 = gridCell(lo.x(), grid_lo_.x(), grid_nx_),
            qy0 = gridCell(lo.y(), grid_lo_.y(), grid_ny_);
  const int qx1 = gridCell(hi.x(), grid_lo_.x(), grid_nx_),
            qy1 = gridCell(hi.y(), grid_lo_.y(), grid_ny_);
  for (int y = qy0; y <= qy1; ++y) {
    for (int x = qx0; x <= qx1; ++x) {
      const size_t c = static_cast<size_t>(y * grid_nx_ + x);
      for (int k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
        const int g = cell_items_[static_cast<size_t>(k)];
        const CellRange& r = geom_cells_[static_cast<size_t>(g)];
        if (x != std::max(r.x0, qx0) || y != std::max(r.y0, qy0)) continue;  // seen in another cell
        const Vec2& glo = geom_lo_[static_cast<size_t>(g)];
        const Vec2& ghi = geom_hi_[static_cast<size_t>(g)];
        if (glo.x() > hi.x() || glo.y() > hi.y() || ghi.x() < lo.x() || ghi.y() < lo.y()) continue;
        if (n == static_cast<int>(out.size())) return false;
        out[static_cast<size_t>(n++)] = g;
      }
    }
  }
  std::sort(out.begin(), out.begin() + n, std::greater<int>());  // the newest geom first
  return true;
}

void World::collideNear(dxGeom* geom, const Vec2& lo, const Vec2& hi, void* data,
                        void (*callback)(void*, dxGeom*, dxGeom*)) const {
  // The margin covers the footprints' rounding; each candidate is then tested exactly by the
  // callback's dCollide, with `geom` first as dSpaceCollide2(geom, space) passes it.
  const Vec2 margin{1e-6, 1e-6};
  std::array<int, 64> near;
  int n = 0;
  if (!candidates(lo - margin, hi + margin, near, n)) {
    dSpaceCollide2(geom, reinterpret_cast<dGeomID>(space_.get()), data, callback);
    return;
  }
  for (int i = 0; i < n; ++i)
    callback(data, geom, geoms_[static_cast<size_t>(near[static_cast<size_t>(i)])].get());
}

std::optional<RayHit> World::castRay(Vec2 origin, double heading, double length, double z) const {
  if (!(length > 0.0) || !std::isfinite(length) || !std::isfinite(heading) || !std::isfinite(z) ||
      !origin.allFinite()) {
    return std::nullopt;
  }
  const Vec2 dir(std::cos(heading), std::sin(heading));
  dGeomRaySet(ray_.get(), origin.x(), origin.y(), z, dir.x(), dir.y(), 0.0);
  dGeomRaySetLength(ray_.get(), length);

  RayQuery q;
  const Vec2 end = origin + length * dir;
  collideNear(ray_.get(), origin.cwiseMin(end), origin.cwiseMax(end), &q, &rayCallback);
  if (!std::isfinite(q.best)) return std::nullopt;

  RayHit hit;
  hit.distance = q.best;
  hit.point = {q.contact.pos[0], q.contact.pos[1]};
  // ODE gives the face normal; its sign depends on argument order, so orient it explicitly.
  Vec2 n(q.contact.normal[0], q.contact.normal[1]);
  const double norm = n.norm();
  n = norm > 1e-12 ? Vec2(n / norm) : Vec2(-dir);
  if (n.dot(dir) > 0.0) n = -n;
  hit.normal = n;
  return hit;
}

bool World::bodyCollides(const Pose2& pose) const {
  if (!std::isfinite(pose.x) || !std::isfinite(pose.y) || !std::isfinite(pose.theta)) {
    return true;
  }
  dGeomSetPosition(body_.get(), pose.x, pose.y, kProbeZ);
  bool hit = false;
  const Vec2 r{kRobotRadius, kRobotRadius};
  collideNear(body_.get(), pose.position() - r, pose.position() + r, &hit, &overlapCallback);
  return hit;
}

std::optional<Vec2> World::nearestSurfacePoint(const Vec2& p) const {
  std::optional<Vec2> best;
  double best_d = std::numeric_limits<double>::infinity();
  for (const OrientedRect& r : footprints_) {
    const PerimeterPoint q = closestOnPerimeter(r, p);
    if (q.distance < best_d) {
      best_d = q.distance;
      best = q.point;
    }
  }
  return best;
}

std::vector<Pose2> World::reachablePoses(const std::vector<Pose2>& candidates, int* skipped) const {
  std::vector<Pose2> kept;
  kept.reserve(candidates.size());
  int removed = 0;
  for (const Pose2& p : candidates) {
    if (bodyCollides(p)) {
      ++removed;
    } else {
      kept.push_back(p);
    }
  }
  if (skipped != nullptr) *skipped = removed;
  return kept;
}

}  // namespace crunch::sim
