#include "crunch_sim/whisker_physics.h"

#include <ode/ode.h>

#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>

#include "crunch/scene/scene.h"

namespace crunch::sim {
namespace {

Error optionError(const std::string& field, const std::string& what) {
  return Error{"WhiskeredRobot::Options::" + field + " " + what};
}
bool positive(double x) { return std::isfinite(x) && x > 0.0; }
bool nonNegative(double x) { return std::isfinite(x) && x >= 0.0; }

// Geom data tag of a whisker capsule: (whisker, segment) packed, never null. The World's geoms
// carry no data and no body.
void* packTag(int whisker, int segment) {
  return reinterpret_cast<void*>(static_cast<std::uintptr_t>(whisker) * 4096u +
                                 static_cast<std::uintptr_t>(segment) + 1u);
}
void unpackTag(const void* tag, int& whisker, int& segment) {
  const auto v = reinterpret_cast<std::uintptr_t>(tag) - 1u;
  whisker = static_cast<int>(v / 4096u);
  segment = static_cast<int>(v % 4096u);
}

// The rotation of a capsule pointing along heading `a`: local z (the capsule's axis) along the
// whisker, local x up, local y the horizontal normal to its right. (ODE's universal joint starts
// with axis 2 on the second body's local y; keeping that horizontal means setting axis 1
// vertical never meets a parallel pair.)
void whiskerRotation(double a, dMatrix3 R) {
  const double c = std::cos(a), s = std::sin(a);
  // Row-major 3x4: columns are the images of local x, y, z.
  R[0] = 0.0, R[1] = s, R[2] = c, R[3] = 0.0;
  R[4] = 0.0, R[5] = -c, R[6] = s, R[7] = 0.0;
  R[8] = 1.0, R[9] = 0.0, R[10] = 0.0, R[11] = 0.0;
}

// The base's motion over h at speed v and turn rate omega: an exact circular arc.
Pose2 integrateArc(const Pose2& p, double v, double omega, double h) {
  Pose2 q = p;
  const double dth = omega * h;
  if (std::abs(dth) < 1e-12) {
    q.x += v * h * std::cos(p.theta);
    q.y += v * h * std::sin(p.theta);
  } else {
    const double rad = v / omega;
    q.x += rad * (std::sin(p.theta + dth) - std::sin(p.theta));
    q.y -= rad * (std::cos(p.theta + dth) - std::cos(p.theta));
  }
  q.theta += dth;
  return q;
}

// Signed distance from p to the rectangle (negative inside).
double signedDistance(const OrientedRect& r, const Vec2& p) {
  const Vec2 local = r.pose.toLocal(p);
  const bool inside = std::abs(local.x()) <= 0.5 * r.size_x && std::abs(local.y()) <= 0.5 * r.size_y;
  const double d = closestOnPerimeter(r, p).distance;
  return inside ? -d : d;
}

// The implicit spring of a joint stop at lo = hi = 0 (ODE manual, "How do I make springs").
void setSpring(dJointID j, double kp, double kd, double h) {
  const double erp = h * kp / (h * kp + kd);
  const double cfm = 1.0 / (h * kp + kd);
  dJointSetUniversalParam(j, dParamHiStop, 0.0);
  dJointSetUniversalParam(j, dParamLoStop, 0.0);
  dJointSetUniversalParam(j, dParamStopERP, erp);
  dJointSetUniversalParam(j, dParamStopCFM, cfm);
  dJointSetUniversalParam(j, dParamBounce, 0.0);
  dJointSetUniversalParam(j, dParamHiStop2, 0.0);
  dJointSetUniversalParam(j, dParamLoStop2, 0.0);
  dJointSetUniversalParam(j, dParamStopERP2, erp);
  dJointSetUniversalParam(j, dParamStopCFM2, cfm);
  dJointSetUniversalParam(j, dParamBounce2, 0.0);
}

}  // namespace

// ---- WhiskeredRobot::Options -------------------------------------------------------------------

Status WhiskeredRobot::Options::validate() const {
  if (Status s = beam.validate(); !s) return s;
  if (elements < 2 || elements > 200) return optionError("elements", "must be in [2, 200]");
  if (!positive(dt) || dt > 0.01) return optionError("dt", "must be in (0, 0.01] seconds");
  if (substeps < 1 || substeps > 100) return optionError("substeps", "must be in [1, 100]");
  if (!std::isfinite(element_grading) || element_grading < 1.0 || element_grading > 3.0) {
    return optionError("element_grading", "must be in [1, 3]");
  }
  if (!std::isfinite(z)) return optionError("z", "must be finite");
  if (!nonNegative(friction)) return optionError("friction", "must be finite and >= 0");
  if (max_contacts_per_segment < 1 || max_contacts_per_segment > 8) {
    return optionError("max_contacts_per_segment", "must be in [1, 8]");
  }
  if (max_substeps < substeps || max_substeps > 100) {
    return optionError("max_substeps", "must be in [substeps, 100]");
  }
  if (!positive(max_rotation_per_substep)) {
    return optionError("max_rotation_per_substep", "must be finite and > 0");
  }
  if (!positive(max_correcting_velocity)) {
    return optionError("max_correcting_velocity", "must be finite and > 0");
  }
  if (!positive(contact_stiffness)) {
    return optionError("contact_stiffness", "must be finite and > 0");
  }
  if (!nonNegative(contact_damping)) {
    return optionError("contact_damping", "must be finite and >= 0");
  }
  if (!positive(wheel_base)) return optionError("wheel_base", "must be finite and > 0");
  if (!positive(max_wheel_speed)) return optionError("max_wheel_speed", "must be finite and > 0");
  if (!(std::isfinite(max_wheel_acceleration) && max_wheel_acceleration >= 0.0)) {
    return optionError("max_wheel_acceleration", "must be finite and >= 0");
  }
  return okStatus();
}

// ---- Handles -----------------------------------------------------------------------------------

void WhiskeredRobot::WorldDeleter::operator()(dxWorld* w) const { dWorldDestroy(w); }
void WhiskeredRobot::BodyDeleter::operator()(dxBody* b) const { dBodyDestroy(b); }
void WhiskeredRobot::JointDeleter::operator()(dxJoint* j) const { dJointDestroy(j); }
void WhiskeredRobot::JointGroupDeleter::operator()(dxJointGroup* g) const {
  dJointGroupDestroy(g);
}

// ---- WhiskeredRobot ----------------------------------------------------------------------------

Result<std::unique_ptr<WhiskeredRobot>> WhiskeredRobot::create(const World& world,
                                                               std::vector<WhiskerMount> mounts,
                                                               const Options& options) {
  if (Status s = options.validate(); !s) return s.error();
  for (size_t i = 0; i < mounts.size(); ++i) {
    const WhiskerMount& m = mounts[i];
    const std::string name = "whisker mount " + std::to_string(i);
    if (!m.base.allFinite() || !std::isfinite(m.bearing)) {
      return Error{name + " has a non-finite base or bearing"};
    }
    if (!(std::abs(m.length - options.beam.external_length) < 1e-9)) {
      return Error{name + " is " + std::to_string(m.length) +
                   " m long but the beam's external_length is " +
                   std::to_string(options.beam.external_length) + " m"};
    }
  }
  std::unique_ptr<WhiskeredRobot> robot(new WhiskeredRobot(world, std::move(mounts), options));
  robot->build();
  robot->place(Pose2{});
  return robot;
}

WhiskeredRobot::WhiskeredRobot(const World& world, std::vector<WhiskerMount> mounts,
                               const Options& options)
    : world_(world),
      mounts_(std::move(mounts)),
      options_(options),
      wheels_(DiffDrive::Options{options.wheel_base, options.max_wheel_speed,
                                 options.max_wheel_acceleration}),
      response_steps_(std::max(1L, std::lround(kFreeResponseTime / options.dt))) {}

WhiskeredRobot::~WhiskeredRobot() {
  // Contact joints reference the bodies; empty the group while everything still exists.
  if (contact_group_) dJointGroupEmpty(contact_group_.get());
}

void WhiskeredRobot::build() {
  const WhiskerBeam& beam = options_.beam;
  const int n = options_.elements;
  const double L = beam.external_length;

  // Beam element j (1..n) is [e_{j-1}, e_j]; its joint sits at the element's compliance
  // centroid (the 1/EI-weighted mean of s), which makes the lumped chain's compliance at any d
  // beyond the element exact up to the element's second moment. Capsule i spans from joint i
  // (the follicle for i = 0) to joint i + 1 (the tip for i = n).
  // Boundaries e_j = L (1 - (1 - j/n)^g): with g > 1 the elements shorten toward the tip, where
  // 1/EI grows fastest (D^-4) and the compliance of the tip contacts concentrates.
  const double grading = options_.element_grading;
  std::vector<double> e;
  for (int j = 0; j <= n; ++j) e.push_back(L * (1.0 - std::pow(1.0 - double(j) / n, grading)));
  joint_s_.push_back(0.0);
  joint_k_.push_back(beam.follicle_stiffness);
  joint_kd_.push_back(beam.follicle_damping);
  for (int j = 1; j <= n; ++j) {
    const double a = e[static_cast<size_t>(j) - 1], bb = e[static_cast<size_t>(j)];
    const double k = beam.elementStiffness(a, bb);
    joint_s_.push_back(beam.complianceCentroid(a, bb));
    joint_k_.push_back(k);
    joint_kd_.push_back(beam.material_damping_time * k);
  }
  std::vector<double> b = joint_s_;
  b.push_back(L);
  for (int i = 0; i <= n; ++i) {
    const double a = b[static_cast<size_t>(i)], bb = b[static_cast<size_t>(i) + 1];
    seg_start_.push_back(a);
    seg_len_.push_back(bb - a);
    seg_radius_.push_back(0.5 * beam.diameter(0.5 * (a + bb)));
    seg_mass_.push_back(beam.mass(a, bb));
  }

  dworld_.reset(dWorldCreate());
  dxWorld* w = dworld_.get();
  dWorldSetGravity(w, 0.0, 0.0, 0.0);
  // Joint error correction: 0.8 of a joint's positional error is removed per step (ODE's default
  // 0.2 let a whisker flicking free of a 45-degree bend open its tip joint by 1.4 mm). A little
  // constraint force mixing on every row (a stiffness above 1e8 N/m at these step sizes, so no
  // visible softness under millinewton loads) keeps the LCP regular where friction rows of two
  // contacts on one capsule coincide: without it ODE's Dantzig solver failed ("LCP internal
  // error") a dozen times in the stability tests.
  dWorldSetERP(w, 0.8);
  dWorldSetCFM(w, 1e-7);
  dWorldSetContactMaxCorrectingVel(w, options_.max_correcting_velocity);
  dWorldSetContactSurfaceLayer(w, 1e-5);
  dWorldSetAutoDisableFlag(w, 0);

  space_.reset(dSimpleSpaceCreate(nullptr));
  dSpaceSetCleanup(space_.get(), 0);
  contact_group_.reset(dJointGroupCreate(0));

  const int segs = n + 1;
  whiskers_.resize(mounts_.size());
  for (size_t wi = 0; wi < mounts_.size(); ++wi) {
    Whisker& wh = whiskers_[wi];
    wh.follicle.reset(dBodyCreate(w));
    dBodySetKinematic(wh.follicle.get());
    for (int i = 0; i < segs; ++i) {
      const auto si = static_cast<size_t>(i);
      dBodyID body = dBodyCreate(w);
      dMass m;
      dMassSetCapsuleTotal(&m, seg_mass_[si], 3, seg_radius_[si], seg_len_[si]);
      dBodySetMass(body, &m);
      wh.bodies.emplace_back(body);
      dGeomID g = dCreateCapsule(space_.get(), seg_radius_[si], seg_len_[si]);
      dGeomSetBody(g, body);
      dGeomSetData(g, packTag(static_cast<int>(wi), i));
      wh.geoms.emplace_back(g);
    }
    for (int j = 0; j < segs; ++j) {
      dJointID jt = dJointCreateUniversal(w, nullptr);
      wh.joints.emplace_back(jt);
    }
  }

  // The world's walls and legs, with their (static) bounding boxes for the broad phase.
  dxSpace* ws = world_.space();
  const int count = dSpaceGetNumGeoms(ws);
  for (int i = 0; i < count; ++i) {
    dGeomID g = dSpaceGetGeom(ws, i);
    world_geoms_.push_back(g);
    dReal aabb[6];
    dGeomGetAABB(g, aabb);
    world_aabbs_.insert(world_aabbs_.end(), aabb, aabb + 6);
  }

  // Room for every capsule touching two surfaces at its full contact count.
  contacts_.reserve(mounts_.size() * static_cast<size_t>(segs) *
                    static_cast<size_t>(options_.max_contacts_per_segment) * 2);
  contact_count_.assign(mounts_.size(), 0);
  free_angles_.assign(mounts_.size(), BaseAngles{});
}

void WhiskeredRobot::clearContacts() {
  dJointGroupEmpty(contact_group_.get());
  contacts_.clear();
  std::fill(contact_count_.begin(), contact_count_.end(), 0);
}

void WhiskeredRobot::resetWhiskers(std::uint32_t mask) {
  if (mask == allWhiskers()) clearContacts();

  const double z = options_.z;
  setBaseBodies(0.0, 0.0, 0.0);
  // The whiskers move rigidly with the base: at rest after place() (the wheels halted), turning
  // with it when free-running ends mid-turn.
  const double v = wheels_.v(), omega = wheels_.omega();

  for (size_t wi = 0; wi < mounts_.size(); ++wi) {
    if (!(mask & (1u << wi))) continue;
    const WhiskerMount& m = mounts_[wi];
    Whisker& wh = whiskers_[wi];
    const double a = pose_.theta + m.bearing;
    const Vec2 base = pose_.toWorld(m.base);
    const Vec2 u(std::cos(a), std::sin(a));
    dMatrix3 R;
    whiskerRotation(a, R);
    for (size_t i = 0; i < wh.bodies.size(); ++i) {
      dBodyID body = wh.bodies[i].get();
      const Vec2 c = base + (seg_start_[i] + 0.5 * seg_len_[i]) * u;
      dBodySetPosition(body, c.x(), c.y(), z);
      dBodySetRotation(body, R);
      if (v == 0.0 && omega == 0.0) {
        dBodySetLinearVel(body, 0.0, 0.0, 0.0);
        dBodySetAngularVel(body, 0.0, 0.0, 0.0);
      } else {  // rigid motion with the base: v along the heading plus omega x (c - centre)
        dBodySetLinearVel(body, v * std::cos(pose_.theta) - omega * (c.y() - pose_.y),
                          v * std::sin(pose_.theta) + omega * (c.x() - pose_.x), 0.0);
        dBodySetAngularVel(body, 0.0, 0.0, omega);
      }
    }
    // Re-attaching re-records the joints' rest configuration at the straight pose.
    for (size_t j = 0; j < wh.joints.size(); ++j) {
      dJointID jt = wh.joints[j].get();
      dBodyID b1 = j == 0 ? wh.follicle.get() : wh.bodies[j - 1].get();
      dBodyID b2 = wh.bodies[j].get();
      dJointAttach(jt, b1, b2);
      // Joint j joins capsule j-1 (the base for j = 0) to capsule j at the start of capsule j.
      const Vec2 at = base + joint_s_[j] * u;
      dJointSetUniversalAnchor(jt, at.x(), at.y(), z);
      dJointSetUniversalAxis1(jt, 0.0, 0.0, 1.0);
      dJointSetUniversalAxis2(jt, -u.y(), u.x(), 0.0);
    }
  }
  last_h_ = 0.0;  // springs are (re)set for the step size at the next substep
}

void WhiskeredRobot::place(const Pose2& pose) {
  assert(std::isfinite(pose.x) && std::isfinite(pose.y) && std::isfinite(pose.theta));
  pose_ = pose;
  wheels_.halt();
  resetWhiskers(allWhiskers());
  bumper_ = frontBumper(pose_);
  // Straight at rest with the wheels stopped: the settled state of the zero command.
  command_ = stepped_ = Command{};
  since_change_ = response_steps_;
  replay_ = nullptr;
  for (int w = 0; w < whiskerCount(); ++w) free_angles_[static_cast<size_t>(w)] = odeBaseAngles(w);
}

Status WhiskeredRobot::drive(double v, double omega) {
  Status s = wheels_.command(v, omega, "simulated base (WhiskeredRobot)");
  command_ = s.ok() ? Command{v, omega} : Command{};  // a bad command stops the wheels
  return s;
}

double WhiskeredRobot::clearance(const Pose2& p) const {
  double best = std::numeric_limits<double>::infinity();
  for (const OrientedRect& r : world_.footprints()) {
    best = std::min(best, signedDistance(r, p.position()));
  }
  return best - kRobotRadius;
}

void WhiskeredRobot::moveBase(double h) {
  wheels_.advance(h);
  const double omega = wheels_.omega();
  double v = wheels_.v();
  Pose2 next = integrateArc(pose_, v, omega, h);
  // The bumper feels where the wheels would take the body, whether or not they can.
  const Bumper pressed = frontBumper(next);
  bool refused = false;
  if (v != 0.0 && world_.bodyCollides(next) && clearance(next) < clearance(pose_) - 1e-12) {
    // No translation deeper into an obstacle (the wheels stall), ahead or behind; turning in
    // place is allowed (a round body cannot turn deeper).
    v = 0.0;
    next = integrateArc(pose_, 0.0, omega, h);
    ++refused_steps_;
    refused = true;
  }
  setBaseBodies(v, omega, h);
  pose_ = next;
  // Where the body ends, if not where the bumper was felt above.
  bumper_ = pressed != Bumper::kReleased || !refused ? pressed : frontBumper(pose_);
}

Bumper WhiskeredRobot::frontBumper(const Pose2& p) const {
  const Vec2 centre = p.position();
  const Vec2 ahead{std::cos(p.theta), std::sin(p.theta)};
  unsigned bits = 0;
  for (const OrientedRect& r : world_.footprints()) {
    if ((r.pose.position() - centre).norm() - r.circumradius() > kRobotRadius + kBumperReach) continue;
    const PerimeterPoint q = closestOnPerimeter(r, centre);
    const Vec2 d = q.point - centre;
    if (q.distance <= kRobotRadius + kBumperReach && d.dot(ahead) > 0.0) {
      bits |= static_cast<unsigned>(bumperAt(std::atan2(d.y(), d.x()) - p.theta));
    }
  }
  return static_cast<Bumper>(bits);
}

void WhiskeredRobot::setBaseBodies(double v, double omega, double h) {
  // The kinematic bodies start the step at the current pose with the step's velocity; ODE moves
  // them along the chord, within O(h^2) of the arc, and the next step starts them on the arc.
  dMatrix3 R;
  dRFromAxisAndAngle(R, 0.0, 0.0, 1.0, pose_.theta);
  const double mid = pose_.theta + 0.5 * omega * h;  // chord direction of the arc
  for (Whisker& wh : whiskers_) {
    dBodyID body = wh.follicle.get();
    dBodySetPosition(body, pose_.x, pose_.y, options_.z);
    dBodySetRotation(body, R);
    dBodySetLinearVel(body, v * std::cos(mid), v * std::sin(mid), 0.0);
    dBodySetAngularVel(body, 0.0, 0.0, omega);
  }
}

void WhiskeredRobot::nearCallback(void* data, dxGeom* o1, dxGeom* o2) {
  static_cast<WhiskeredRobot*>(data)->onNear(o1, o2);
}

void WhiskeredRobot::onNear(dxGeom* o1, dxGeom* o2) {
  // Exactly one of the pair is a whisker capsule (it has a body).
  dBodyID b1 = dGeomGetBody(o1), b2 = dGeomGetBody(o2);
  if ((b1 != nullptr) == (b2 != nullptr)) return;
  const bool first_is_whisker = b1 != nullptr;
  dGeomID wg = first_is_whisker ? o1 : o2;
  int wi = 0, seg = 0;
  unpackTag(dGeomGetData(wg), wi, seg);

  dContactGeom found[8];
  const int n = dCollide(o1, o2, options_.max_contacts_per_segment, found, sizeof(dContactGeom));
  for (int k = 0; k < n; ++k) {
    if (contacts_.size() == contacts_.capacity()) {
      ++dropped_contacts_;  // cannot happen with the reserved room; counted, never allocated
      continue;
    }
    dContact c{};
    c.geom = found[k];
    // A stiff spring-damper contact (implicit, as the joints): it regularises the LCP when a
    // capsule meets a box at two points or two boxes at once, which a rigid contact makes
    // degenerate for ODE's pivoting solver.
    c.surface.mode = dContactSoftERP | dContactSoftCFM;
    c.surface.soft_erp = contact_erp_;
    c.surface.soft_cfm = contact_cfm_;
    if (options_.friction > 0.0) {
      c.surface.mode |= dContactApprox1;
      c.surface.mu = options_.friction;
    } else {
      c.surface.mu = 0.0;
    }
    dJointID j = dJointCreateContact(dworld_.get(), contact_group_.get(), &c);
    dJointAttach(j, b1, b2);

    // ODE's normal points toward o1's side; report it out of the surface toward the whisker.
    const double sign = first_is_whisker ? 1.0 : -1.0;
    ContactRecord rec;
    rec.whisker = wi;
    rec.segment = seg;
    rec.depth = c.geom.depth;
    for (int d = 0; d < 3; ++d) {
      rec.pos[d] = c.geom.pos[d];
      rec.normal[d] = sign * c.geom.normal[d];
    }
    contacts_.push_back(rec);
    ++contact_count_[static_cast<size_t>(wi)];
  }
}

void WhiskeredRobot::collide() {
  dJointGroupEmpty(contact_group_.get());
  contacts_.clear();
  std::fill(contact_count_.begin(), contact_count_.end(), 0);
  // Broad phase: only walls and legs within reach of a whisker (a square around the base that
  // holds every whisker at any bend) are collided, each against the whisker capsules.
  double reach = 0.0;
  for (const WhiskerMount& m : mounts_) reach = std::max(reach, m.base.norm() + m.length);
  reach += 0.01;
  const double x0 = pose_.x - reach, x1 = pose_.x + reach;
  const double y0 = pose_.y - reach, y1 = pose_.y + reach;
  for (size_t i = 0; i < world_geoms_.size(); ++i) {
    const double* a = &world_aabbs_[6 * i];
    if (a[1] < x0 || a[0] > x1 || a[3] < y0 || a[2] > y1) continue;
    dSpaceCollide2(world_geoms_[i], reinterpret_cast<dGeomID>(space_.get()), this, &nearCallback);
  }
}

void WhiskeredRobot::substep(double h) {
  if (h != last_h_) {
    const double kp = options_.contact_stiffness, kd = options_.contact_damping;
    contact_erp_ = h * kp / (h * kp + kd);
    contact_cfm_ = 1.0 / (h * kp + kd);
    for (Whisker& wh : whiskers_) {
      for (size_t j = 0; j < wh.joints.size(); ++j) {
        setSpring(wh.joints[j].get(), joint_k_[j], joint_kd_[j], h);
      }
    }
    last_h_ = h;
  }
  collide();
  moveBase(h);
  dWorldStep(dworld_.get(), h);
  time_ += h;
}

int WhiskeredRobot::substepsNeeded() const {
  // A capsule turning fast (a whisker flicking free of a deep bend) needs shorter steps: the
  // joints are solved at velocity level, and a large rotation within one step opens them.
  double fastest = 0.0;
  for (size_t wi = 0; wi < whiskers_.size(); ++wi) {
    if (free_mask_ & (1u << wi)) continue;  // not in ODE: its bodies hold stale velocities
    for (const BodyPtr& b : whiskers_[wi].bodies) {
      const dReal* w = dBodyGetAngularVel(b.get());
      fastest = std::max(fastest, w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    }
  }
  const double per_step = std::sqrt(fastest) * options_.dt;
  const int n = static_cast<int>(std::ceil(per_step / options_.max_rotation_per_substep));
  return std::clamp(n, options_.substeps, options_.max_substeps);
}

void WhiskeredRobot::enableInOde(size_t w, bool on) {
  Whisker& wh = whiskers_[w];
  // All of the island: a disabled body reached through an enabled joint would be enabled again
  // by ODE's island search (its auto-enable), and the follicle alone would seed an island.
  for (BodyPtr& b : wh.bodies) on ? dBodyEnable(b.get()) : dBodyDisable(b.get());
  on ? dBodyEnable(wh.follicle.get()) : dBodyDisable(wh.follicle.get());
  for (JointPtr& j : wh.joints) on ? dJointEnable(j.get()) : dJointDisable(j.get());
  for (GeomPtr& g : wh.geoms) on ? dGeomEnable(g.get()) : dGeomDisable(g.get());
}

void WhiskeredRobot::setFreeWhiskers(std::uint32_t mask) {
  mask &= allWhiskers();
  if (mask == free_mask_) return;
  const std::uint32_t freed = mask & ~free_mask_, back = free_mask_ & ~mask;
  if (freed != 0) {
    // Exact when the whiskers have settled (since_change_ saturated) or each freed one is on the
    // tracked free trajectory; else a ringing whisker joins the replay mid-swing (counted).
    bool exact = since_change_ >= response_steps_;
    for (size_t w = 0; w < whiskers_.size() && !exact; ++w) {
      if (freed & (1u << w)) exact = onFreeTrajectory(static_cast<int>(w));
    }
    if (!exact) ++inexact_free_changes_;
    if (mask == allWhiskers()) clearContacts();
    // Hold the angles ODE has now until the next step replays the tracked response (if any).
    for (size_t w = 0; w < whiskers_.size(); ++w) {
      if (!(freed & (1u << w))) continue;
      free_angles_[w] = odeBaseAngles(static_cast<int>(w));
      enableInOde(w, false);
    }
    if (free_mask_ == 0 && !track_free_) replay_ = nullptr;
  }
  free_mask_ = mask;
  if (back != 0) {
    for (size_t w = 0; w < whiskers_.size(); ++w) {
      if (back & (1u << w)) enableInOde(w, true);
    }
    // Straight on the base (which also re-attaches the joints at their rest configuration), then,
    // where a free response with states is tracked, in its state: as if it had been in ODE.
    resetWhiskers(back);
    for (size_t w = 0; w < whiskers_.size(); ++w) {
      const double* state = (back & (1u << w)) ? freeState(w) : nullptr;
      if (state == nullptr) continue;
      for (size_t c = 0; c < whiskers_[w].bodies.size(); ++c) setBodyState(w, c, state + c * kBodyState);
    }
  }
}

void WhiskeredRobot::bodyState(size_t w, size_t c, double* out) const {
  dBodyID b = whiskers_[w].bodies[c].get();
  const double co = std::cos(pose_.theta), si = std::sin(pose_.theta);
  const auto rotate = [&](const dReal* v, double* o) {  // by -theta about z
    o[0] = co * v[0] + si * v[1];
    o[1] = -si * v[0] + co * v[1];
    o[2] = v[2];
  };
  const dReal* p = dBodyGetPosition(b);
  const dReal rel[3] = {p[0] - pose_.x, p[1] - pose_.y, p[2]};
  rotate(rel, out);
  const dReal* q = dBodyGetQuaternion(b);
  const dQuaternion base_inv = {std::cos(0.5 * pose_.theta), 0.0, 0.0, -std::sin(0.5 * pose_.theta)};
  dQuaternion qr;
  dQMultiply0(qr, base_inv, q);
  std::copy(qr, qr + 4, out + 3);
  rotate(dBodyGetLinearVel(b), out + 7);
  rotate(dBodyGetAngularVel(b), out + 10);
}

void WhiskeredRobot::setBodyState(size_t w, size_t c, const double* in) {
  dBodyID b = whiskers_[w].bodies[c].get();
  const double co = std::cos(pose_.theta), si = std::sin(pose_.theta);
  const auto rotate = [&](const double* v, double* o) {  // by +theta about z
    o[0] = co * v[0] - si * v[1];
    o[1] = si * v[0] + co * v[1];
    o[2] = v[2];
  };
  double v[3];
  rotate(in, v);
  dBodySetPosition(b, v[0] + pose_.x, v[1] + pose_.y, v[2]);
  const dQuaternion base = {std::cos(0.5 * pose_.theta), 0.0, 0.0, std::sin(0.5 * pose_.theta)};
  const dQuaternion rel = {in[3], in[4], in[5], in[6]};
  dQuaternion q;
  dQMultiply0(q, base, rel);
  dBodySetQuaternion(b, q);
  rotate(in + 7, v);
  dBodySetLinearVel(b, v[0], v[1], v[2]);
  rotate(in + 10, v);
  dBodySetAngularVel(b, v[0], v[1], v[2]);
}

const double* WhiskeredRobot::freeState(size_t w) const {
  if (replay_ == nullptr || replay_->states.empty()) return nullptr;
  const long i = std::clamp(since_change_, 1L, response_steps_) - 1;  // after the last step
  const size_t capsules = whiskers_[w].bodies.size();
  return &replay_->states[((static_cast<size_t>(i) * mounts_.size() + w) * capsules) * kBodyState];
}

bool WhiskeredRobot::onFreeTrajectory(int w) const {
  assert(w >= 0 && w < whiskerCount());
  const auto wi = static_cast<size_t>(w);
  if ((free_mask_ & (1u << wi)) || contact_count_[wi] != 0) return false;
  const double* free = freeState(wi);
  if (free == nullptr) return false;
  const double tol = kFreeTrajectoryTolerance;
  for (size_t c = 0; c < whiskers_[wi].bodies.size(); ++c, free += kBodyState) {
    double s[kBodyState];
    bodyState(wi, c, s);
    const double len = seg_len_[c], dt = options_.dt;
    double dq = 0.0, dq_flipped = 0.0;  // q and -q are the same orientation
    for (int k = 3; k < 7; ++k) {
      dq = std::max(dq, std::abs(s[k] - free[k]));
      dq_flipped = std::max(dq_flipped, std::abs(s[k] + free[k]));
    }
    if (std::min(dq, dq_flipped) * len > tol) return false;
    for (int k = 0; k < 3; ++k) {
      if (std::abs(s[k] - free[k]) > tol || std::abs(s[7 + k] - free[7 + k]) * dt > tol ||
          std::abs(s[10 + k] - free[10 + k]) * len * dt > tol) {
        return false;
      }
    }
  }
  return true;
}

const WhiskeredRobot::FreeResponse& WhiskeredRobot::freeResponse(const Command& from,
                                                                 const Command& to) {
  for (const FreeResponse& r : free_responses_) {
    if (r.from == from && r.to == to && (!track_free_ || !r.states.empty())) return r;
  }
  if (!probe_) {
    // An empty arena large enough for the probe to drive two response times at full speed.
    Scene empty;
    empty.width = empty.depth = 20.0;
    probe_world_ = World::build(empty);
    auto made = create(*probe_world_, mounts_, options_);
    assert(made.ok());  // the options and mounts this robot was made with
    probe_ = std::move(made).value();
  }
  WhiskeredRobot& probe = *probe_;
  if (probe_settled_ != from) {
    // Start straight at rest in the middle and run `from` long enough to settle.
    probe.place({10.0, 10.0, 0.0});
    if (from != Command{}) {
      (void)probe.drive(from.v, from.omega);
      for (long i = 0; i < response_steps_; ++i) probe.step();
    }
  }
  FreeResponse r;
  r.from = from;
  r.to = to;
  r.angles.reserve(static_cast<size_t>(response_steps_) * mounts_.size());
  const size_t capsules = static_cast<size_t>(segmentCount());
  if (track_free_) {
    r.states.resize(static_cast<size_t>(response_steps_) * mounts_.size() * capsules * kBodyState);
  }
  (void)probe.drive(to.v, to.omega);
  double* state = r.states.data();
  for (long i = 0; i < response_steps_; ++i) {
    probe.step();
    for (int w = 0; w < whiskerCount(); ++w) {
      r.angles.push_back(probe.baseAngles(w));
      if (!track_free_) continue;
      for (size_t c = 0; c < capsules; ++c, state += kBodyState) {
        probe.bodyState(static_cast<size_t>(w), c, state);
      }
    }
  }
  probe_settled_ = to;
  free_responses_.push_back(std::move(r));
  return free_responses_.back();
}

void WhiskeredRobot::step() {
  const bool changed = !(command_ == stepped_);
  if (changed) {
    // A command change before the free response has settled: the new response (recorded from
    // the settled previous command) does not describe the free whiskers. When tracking, they go
    // back to ODE in the state the tracked response gives them after the last step, exactly as if
    // they had been there all along, and may leave again once back on the new free trajectory.
    if (track_free_ && free_mask_ != 0 && since_change_ < response_steps_ && replay_ != nullptr &&
        !replay_->states.empty()) {
      setFreeWhiskers(0);
    }
    if (free_mask_ != 0 || track_free_) {
      if (free_mask_ != 0 && since_change_ < response_steps_) ++inexact_free_changes_;
      replay_ = &freeResponse(stepped_, command_);
    } else {
      replay_ = nullptr;
    }
    since_change_ = 0;
  }
  if (free_mask_ == allWhiskers()) {
    // The base exactly as substep() moves it; no collision, no dynamics (see the header).
    const double h = options_.dt / options_.substeps;
    for (int i = 0; i < options_.substeps; ++i) {
      moveBase(h);
      time_ += h;
    }
    ++free_steps_;
  } else {
    const int n = substepsNeeded();
    if (n > options_.substeps) ++refined_steps_;
    const double h = options_.dt / n;
    for (int i = 0; i < n; ++i) substep(h);
    partly_free_whisker_steps_ += std::popcount(free_mask_);
    ode_whisker_steps_ += static_cast<long long>(whiskers_.size()) - std::popcount(free_mask_);
  }
  if (free_mask_ != 0 && replay_ != nullptr) {
    const long i = std::min(since_change_, response_steps_ - 1);  // then hold the settled value
    const BaseAngles* row = &replay_->angles[static_cast<size_t>(i) * mounts_.size()];
    for (size_t w = 0; w < mounts_.size(); ++w) {
      if (free_mask_ & (1u << w)) free_angles_[w] = row[w];
    }
  }
  stepped_ = command_;
  since_change_ = std::min(since_change_ + 1, response_steps_);
}

int WhiskeredRobot::run(double seconds) {
  const int steps = static_cast<int>(std::lround(seconds / options_.dt));
  for (int i = 0; i < steps; ++i) step();
  return std::max(steps, 0);
}

BaseAngles WhiskeredRobot::baseAngles(int w) const {
  assert(w >= 0 && w < whiskerCount());
  return (free_mask_ & (1u << w)) ? free_angles_[static_cast<size_t>(w)] : odeBaseAngles(w);
}

BaseAngles WhiskeredRobot::odeBaseAngles(int w) const {
  const dReal* R = dBodyGetRotation(whiskers_[static_cast<size_t>(w)].bodies[0].get());
  const double ux = R[2], uy = R[6], uz = R[10];  // local z: the first capsule's direction
  const double c = std::cos(pose_.theta), s = std::sin(pose_.theta);
  const double lx = c * ux + s * uy, ly = -s * ux + c * uy;
  BaseAngles out;
  out.horizontal = wrapPi(std::atan2(ly, lx) - mounts_[static_cast<size_t>(w)].bearing);
  out.vertical = std::atan2(uz, std::hypot(lx, ly));
  return out;
}

int WhiskeredRobot::contactCount(int w) const {
  assert(w >= 0 && w < whiskerCount());
  return contact_count_[static_cast<size_t>(w)];
}

std::optional<WhiskerContact> WhiskeredRobot::contact(int w) const {
  assert(w >= 0 && w < whiskerCount());
  const ContactRecord* best = nullptr;
  double best_r = std::numeric_limits<double>::infinity();
  for (const ContactRecord& c : contacts_) {
    if (c.whisker != w) continue;
    const auto si = static_cast<size_t>(c.segment);
    const auto [a, e] = segmentEnds(w, c.segment);
    const Eigen::Vector3d p(c.pos[0], c.pos[1], c.pos[2]);
    const double t = std::clamp((p - a).dot((e - a).normalized()), 0.0, seg_len_[si]);
    const double r = seg_start_[si] + t;
    if (r < best_r) {
      best_r = r;
      best = &c;
    }
  }
  if (best == nullptr) return std::nullopt;
  WhiskerContact out;
  out.r = best_r;
  out.point = {best->pos[0], best->pos[1]};
  Vec2 n(best->normal[0], best->normal[1]);
  const double len = n.norm();
  out.normal = len > 1e-12 ? Vec2(n / len) : Vec2(0.0, 0.0);
  out.depth = best->depth;
  out.segment = best->segment;
  return out;
}

Eigen::Vector3d WhiskeredRobot::basePoint(int w) const {
  const Vec2 b = pose_.toWorld(mounts_[static_cast<size_t>(w)].base);
  return {b.x(), b.y(), options_.z};
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> WhiskeredRobot::segmentEnds(int w, int i) const {
  assert(w >= 0 && w < whiskerCount() && i >= 0 && i < segmentCount());
  if (free_mask_ & (1u << w)) {  // the straight whisker on the base
    const WhiskerMount& m = mounts_[static_cast<size_t>(w)];
    const Vec2 base = pose_.toWorld(m.base);
    const double a = pose_.theta + m.bearing;
    const Vec2 u(std::cos(a), std::sin(a));
    const Vec2 p0 = base + seg_start_[static_cast<size_t>(i)] * u;
    const Vec2 p1 = p0 + seg_len_[static_cast<size_t>(i)] * u;
    return {{p0.x(), p0.y(), options_.z}, {p1.x(), p1.y(), options_.z}};
  }
  dBodyID body = whiskers_[static_cast<size_t>(w)].bodies[static_cast<size_t>(i)].get();
  const dReal* p = dBodyGetPosition(body);
  const dReal* R = dBodyGetRotation(body);
  const Eigen::Vector3d c(p[0], p[1], p[2]);
  const Eigen::Vector3d u(R[2], R[6], R[10]);
  const double half = 0.5 * seg_len_[static_cast<size_t>(i)];
  return {c - half * u, c + half * u};
}

}  // namespace crunch::sim
