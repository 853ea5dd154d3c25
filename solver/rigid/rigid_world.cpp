// RigidWorld on Bullet's discrete dynamics world (sequential-impulse solver).
//
// Settings for the 1:40 flume, and why (each is set in Impl's constructor):
// - Double-precision Bullet when the -float64 build is installed (CMake picks it): contact depths of 1e-6 m on
//   boxes 6 cm wide several metres from the origin need more than float's ~1e-6 relative resolution.
// - Every boundary, half-spaces included, is a btBoxShape, so every contact goes through the box-box detector
//   (Bullet's port of ODE's dBoxBox): an exact face-clipping manifold of up to 4 points, and points only where
//   the boxes overlap. A half-space as btStaticPlaneShape goes through the convex-plane algorithm instead,
//   which adds points up to the contact breaking threshold (~1.7 mm here) before the box arrives; the solver
//   then stops the box short of the floor with a target velocity of -gap/dt and the rebound is lost: measured
//   rebound heights were 35% (e = 0.3) down to 0.25% (e = 0.6) of e^2 h in the drop test.
// - Collision margin 1 mm (Bullet's default, 4 cm, is larger than a container's 3 cm half height). The box-box
//   detector uses the full box whatever the margin; the margin only pads the broadphase AABBs.
// - Contact processing threshold left at Bullet's default (every manifold point is solved). Since the box-box
//   detector creates a point only on overlap, no point exists ahead of an impact and the restitution target
//   e * v_n applies to the true impact velocity. A point that has separated by less than the breaking
//   threshold stays in the manifold and in the solver (target normal velocity -gap/dt), which keeps a resting
//   face in contact through the sub-micrometre lifts of the split impulse. Solving only overlapping points
//   (threshold 0) was tried: the resting face then loses and regains points every few substeps, the box
//   rocks, and on an incline with tan(theta) = 0.9 mu the rocking walked it downhill at 0.5 mm/s.
// - Split impulse for every penetration (threshold 0; Bullet's default -0.04 m only splits penetrations
//   deeper than 4 cm, i.e. never here): the push-out then goes to a pseudo-velocity and adds no energy, so a
//   rebound keeps exactly the restitution's velocity and a stack does not pump itself up. erp 0.8 removes
//   80% of a penetration per substep; any of 0.2-1.0 kept the 5 s stack creep under 1e-6 m.
// - Restitution velocity threshold 0.02 m/s (Bullet's default 0.2 m/s is tuned for metre-sized game objects
//   and would swallow every bounce below 2 mm here): a slower approach rebounds at most 0.02^2/(2g) = 20 um,
//   while at resting contact the per-substep approach speed g*dt = 1e-3 m/s stays well below it.
// - Substep 1e-4 s: at 3 m/s a box moves 0.3 mm per substep (0.5% of its size), so penetrations stay far
//   below the box size and thin walls are never tunnelled; the water's dt (~1e-5 s) is usually below it, so
//   step(dt) is then a single Bullet step.
// - 60 iterations: a face-on impact or a resting face has 4 points coupled through the box's rotation, and
//   the sweep needs iterations for their impulses to agree. A flat drop left the box spinning at 0.1 rad/s
//   after 5 iterations, 2e-4 rad/s after 10, 2e-9 after 20; the 6-box stack crept 5e-5 m in 5 s at 10
//   iterations and 4e-7 m at 60. The cost is small at this body count.
// - One friction direction per point (Bullet's default), along the point's slip velocity before the solve, or
//   along the way it would slip when at rest: a sliding point then spends its whole Coulomb budget against the
//   slip, as the friction cone requires. Bullet's optional second direction clamps each axis separately (a
//   square, not a cone), which gives a sliding point extra sideways grip.
// - No deactivation: a sleeping box would ignore the water's load.
// - CoulombContactSolver (below) fixes Bullet's stale friction on unloaded points.
#include "solver/rigid/rigid_world.h"

#include "solver/checkpoint.h"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/errors.h"

namespace flume {
namespace {

// Half-spaces become boxes this large (half-size, m): much larger than any flume, while small enough that the
// box-box clipping keeps ~1e-14 m resolution in double precision.
constexpr double kHalfSpaceHalfSize = 100.0;
constexpr double kMaxMargin = 1.0e-3;

btVector3 to_bt(const Eigen::Vector3d& v) { return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z())); }
Eigen::Vector3d from_bt(const btVector3& v) { return Eigen::Vector3d(v.x(), v.y(), v.z()); }

// Which coefficient a contact pair gets: static objects carry the flume-debris values, dynamic ones the
// debris-debris values (set in add_static_* / add_box). A pair with a static member is a flume contact; two
// dynamic members are a debris contact. The values live on the objects, so several worlds with different
// coefficients can coexist although Bullet's callback is a process-wide pointer.
btScalar pair_friction(const btCollisionObject* a, const btCollisionObject* b) {
  if (a->isStaticOrKinematicObject()) return a->getFriction();
  if (b->isStaticOrKinematicObject()) return b->getFriction();
  return a->getFriction();
}
btScalar pair_restitution(const btCollisionObject* a, const btCollisionObject* b) {
  if (a->isStaticOrKinematicObject()) return a->getRestitution();
  if (b->isStaticOrKinematicObject()) return b->getRestitution();
  return a->getRestitution();
}

// Bullet's sequential-impulse sweep re-clamps a point's friction only while its normal impulse is positive
// (friction limit = mu * normal impulse). A point whose normal impulse drops to zero during the sweep (a
// persisted point that lifted off, or one that carried load in an early iteration only) therefore keeps the
// friction impulse it had, up to mu times a load it no longer carries. On the Waseda container sliding down a
// 42 degree incline with mu = 0.8 (the resultant normal force 0.024 m from the centre of a 0.03 m half-width, so
// the rear points carry almost nothing) this stale friction made it slide at 30% of the Coulomb acceleration
// and spin about the normal. After each sweep, this solver clamps such points' friction to zero, as Coulomb's
// law requires of an unloaded point.
class CoulombContactSolver : public btSequentialImpulseConstraintSolver {
 protected:
  btScalar solveSingleIteration(int iteration, btCollisionObject** bodies, int num_bodies,
                                btPersistentManifold** manifolds, int num_manifolds, btTypedConstraint** constraints,
                                int num_constraints, const btContactSolverInfo& info,
                                btIDebugDraw* debug_draw) override {
    const btScalar residual = btSequentialImpulseConstraintSolver::solveSingleIteration(
        iteration, bodies, num_bodies, manifolds, num_manifolds, constraints, num_constraints, info, debug_draw);
    for (int j = 0; j < m_tmpSolverContactFrictionConstraintPool.size(); ++j) {
      btSolverConstraint& friction = m_tmpSolverContactFrictionConstraintPool[j];
      const btScalar normal = m_tmpSolverContactConstraintPool[friction.m_frictionIndex].m_appliedImpulse;
      if (normal > 0 || friction.m_appliedImpulse == 0) continue;
      friction.m_lowerLimit = 0;  // a [0, 0] window: the row solver removes the whole impulse from both bodies
      friction.m_upperLimit = 0;
      resolveSingleConstraintRowGeneric(m_tmpSolverBodyPool[friction.m_solverBodyIdA],
                                        m_tmpSolverBodyPool[friction.m_solverBodyIdB], friction);
    }
    return residual;
  }
};

bool finite(const Eigen::Vector3d& v) { return v.allFinite(); }

void check_coefficients(const ContactCoefficients& c) {
  const auto friction_ok = [](double mu) { return std::isfinite(mu) && mu >= 0.0; };
  const auto restitution_ok = [](double e) { return std::isfinite(e) && e >= 0.0 && e <= 1.0; };
  if (!friction_ok(c.friction_flume))
    throw InputError("", "debris.friction_flume", "must be a finite number >= 0");
  if (!friction_ok(c.friction_debris))
    throw InputError("", "debris.friction_debris", "must be a finite number >= 0");
  if (!restitution_ok(c.restitution_flume))
    throw InputError("", "debris.restitution_flume", "must be in [0, 1]");
  if (!restitution_ok(c.restitution_debris))
    throw InputError("", "debris.restitution_debris", "must be in [0, 1]");
}

}  // namespace

struct RigidWorld::Impl {
  ContactCoefficients coefficients;
  RigidSettings settings;
  Eigen::Vector3d gravity;
  double time = 0.0;

  btDefaultCollisionConfiguration collision_configuration;
  btCollisionDispatcher dispatcher{&collision_configuration};
  btDbvtBroadphase broadphase;
  CoulombContactSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &collision_configuration};

  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btRigidBody>> statics;

  struct Body {
    RigidBoxSpec spec;
    std::unique_ptr<btRigidBody> rb;
    Eigen::Vector3d force = Eigen::Vector3d::Zero();
    Eigen::Vector3d torque = Eigen::Vector3d::Zero();
    Eigen::Vector3d acceleration = Eigen::Vector3d::Zero();
    Eigen::Vector3d angular_acceleration = Eigen::Vector3d::Zero();
  };
  std::vector<Body> bodies;
  std::vector<RigidBoxView> views;

  Impl(const ContactCoefficients& c, const Eigen::Vector3d& g, const RigidSettings& s)
      : coefficients(c), settings(s), gravity(g) {
    gCalculateCombinedFrictionCallback = &pair_friction;
    gCalculateCombinedRestitutionCallback = &pair_restitution;
    world.setGravity(to_bt(g));
    btContactSolverInfo& info = world.getSolverInfo();
    info.m_numIterations = s.solver_iterations;
    info.m_splitImpulse = 1;
    info.m_splitImpulsePenetrationThreshold = 0;
    info.m_erp2 = btScalar(s.split_impulse_erp);
    info.m_restitutionVelocityThreshold = btScalar(s.restitution_velocity_threshold);
    info.m_linearSlop = 0;
  }

  ~Impl() {
    for (auto& b : bodies) world.removeRigidBody(b.rb.get());
    for (auto& s : statics) world.removeRigidBody(s.get());
  }

  void add_static(std::unique_ptr<btCollisionShape> shape, const btTransform& pose) {
    btRigidBody::btRigidBodyConstructionInfo ci(0.0, nullptr, shape.get());
    ci.m_startWorldTransform = pose;
    ci.m_friction = btScalar(coefficients.friction_flume);
    ci.m_restitution = btScalar(coefficients.restitution_flume);
    auto rb = std::make_unique<btRigidBody>(ci);
    world.addRigidBody(rb.get());
    statics.push_back(std::move(rb));
    shapes.push_back(std::move(shape));
  }

  static std::unique_ptr<btBoxShape> make_box(const Eigen::Vector3d& half) {
    auto shape = std::make_unique<btBoxShape>(to_bt(half));
    shape->setMargin(btScalar(std::min(kMaxMargin, 0.1 * half.minCoeff())));
    return shape;
  }

  void refresh_view(int i) {
    const btTransform& t = bodies[i].rb->getWorldTransform();
    RigidBoxView& v = views[i];
    const btMatrix3x3& r = t.getBasis();
    for (int a = 0; a < 3; ++a) {
      v.centre[a] = t.getOrigin()[a];
      v.velocity[a] = bodies[i].rb->getLinearVelocity()[a];
      v.angular_velocity[a] = bodies[i].rb->getAngularVelocity()[a];
      v.half_extent[a] = 0.5 * bodies[i].spec.size[a];
      for (int b = 0; b < 3; ++b) v.rotation[a * 3 + b] = r[a][b];
    }
  }

  const Body& body(int i) const {
    if (i < 0 || i >= int(bodies.size()))
      throw std::out_of_range("RigidWorld: no body " + std::to_string(i));
    return bodies[i];
  }
  Body& body(int i) { return const_cast<Body&>(static_cast<const Impl*>(this)->body(i)); }
};

RigidWorld::RigidWorld(const ContactCoefficients& coefficients, const Eigen::Vector3d& gravity,
                       const RigidSettings& settings) {
  check_coefficients(coefficients);
  if (!finite(gravity)) throw InputError("", "solver.gravity", "must be finite");
  if (!(settings.max_substep > 0.0) || !std::isfinite(settings.max_substep))
    throw InputError("", "debris.max_substep", "must be > 0");
  if (settings.solver_iterations < 1) throw InputError("", "debris.solver_iterations", "must be >= 1");
  if (!(settings.split_impulse_erp > 0.0 && settings.split_impulse_erp <= 1.0))
    throw InputError("", "debris.split_impulse_erp", "must be in (0, 1]");
  if (!(settings.restitution_velocity_threshold >= 0.0))
    throw InputError("", "debris.restitution_velocity_threshold", "must be >= 0");
  impl_ = std::make_unique<Impl>(coefficients, gravity, settings);
}

RigidWorld::~RigidWorld() = default;
RigidWorld::RigidWorld(RigidWorld&&) noexcept = default;
RigidWorld& RigidWorld::operator=(RigidWorld&&) noexcept = default;

void RigidWorld::add_static_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  if (!finite(lo) || !finite(hi) || !((hi - lo).array() > 0.0).all())
    throw InputError("", "boundaries.shape", "a static box needs finite lo < hi on every axis");
  btTransform pose;
  pose.setIdentity();
  pose.setOrigin(to_bt(0.5 * (lo + hi)));
  impl_->add_static(Impl::make_box(0.5 * (hi - lo)), pose);
}

void RigidWorld::add_static_half_space(const Eigen::Vector3d& point, const Eigen::Vector3d& outward_normal) {
  if (!finite(point) || !finite(outward_normal) || !(outward_normal.norm() > 0.0))
    throw InputError("", "boundaries.shape", "a half-space needs a finite point and a non-zero normal");
  const Eigen::Vector3d n = outward_normal.normalized();
  // A box whose +z face lies on the plane, its body z axis along the normal.
  const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), n);
  const Eigen::Vector3d centre = point - kHalfSpaceHalfSize * n;
  btTransform pose;
  pose.setIdentity();
  pose.setOrigin(to_bt(centre));
  pose.setRotation(btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())));
  impl_->add_static(Impl::make_box(Eigen::Vector3d::Constant(kHalfSpaceHalfSize)), pose);
}

void RigidWorld::add_static_shape(const Shape& shape) {
  const auto v = [](const Vec3d& a) { return Eigen::Vector3d(a[0], a[1], a[2]); };
  if (shape.type == ShapeType::kBox)
    add_static_box(v(shape.lo), v(shape.hi));
  else
    add_static_half_space(v(shape.point), v(shape.normal));
}

int RigidWorld::add_box(const RigidBoxSpec& spec_in) {
  RigidBoxSpec spec = spec_in;
  const std::string field = "debris." + (spec.name.empty() ? std::to_string(impl_->bodies.size()) : spec.name);
  if (!finite(spec.size) || !(spec.size.array() > 0.0).all())
    throw InputError("", field + ".size", "every edge length must be > 0 (m)");
  const double volume = spec.size.prod();
  if (spec.mass <= 0.0) {
    if (!(spec.density > 0.0) || !std::isfinite(spec.density))
      throw InputError("", field + ".mass", "give mass > 0 (kg) or density > 0 (kg/m^3)");
    spec.mass = spec.density * volume;
  }
  if (!std::isfinite(spec.mass)) throw InputError("", field + ".mass", "must be finite");
  spec.density = spec.mass / volume;
  if (!finite(spec.position) || !finite(spec.velocity) || !finite(spec.angular_velocity))
    throw InputError("", field, "position, velocity and angular_velocity must be finite");
  const double qn = spec.orientation.norm();
  if (!(qn > 0.0) || !std::isfinite(qn))
    throw InputError("", field + ".orientation", "must be a non-zero quaternion (w, x, y, z)");
  spec.orientation.normalize();
  for (const auto& b : impl_->bodies)
    if (!spec.name.empty() && b.spec.name == spec.name)
      throw InputError("", field + ".name", "names must be unique");

  auto shape = Impl::make_box(0.5 * spec.size);
  btVector3 inertia(0, 0, 0);
  shape->calculateLocalInertia(btScalar(spec.mass), inertia);  // m/12 (b^2 + c^2) about each axis
  btRigidBody::btRigidBodyConstructionInfo ci(btScalar(spec.mass), nullptr, shape.get(), inertia);
  btTransform pose;
  pose.setIdentity();
  pose.setOrigin(to_bt(spec.position));
  const auto& q = spec.orientation;
  pose.setRotation(btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())));
  ci.m_startWorldTransform = pose;
  ci.m_friction = btScalar(impl_->coefficients.friction_debris);
  ci.m_restitution = btScalar(impl_->coefficients.restitution_debris);
  auto rb = std::make_unique<btRigidBody>(ci);
  rb->setActivationState(DISABLE_DEACTIVATION);
  rb->setLinearVelocity(to_bt(spec.velocity));
  rb->setAngularVelocity(to_bt(spec.angular_velocity));
  impl_->world.addRigidBody(rb.get());
  impl_->shapes.push_back(std::move(shape));

  Impl::Body body;
  body.spec = spec;
  body.rb = std::move(rb);
  impl_->bodies.push_back(std::move(body));
  impl_->views.emplace_back();
  const int index = int(impl_->bodies.size()) - 1;
  impl_->refresh_view(index);
  return index;
}

int RigidWorld::body_count() const { return int(impl_->bodies.size()); }

int RigidWorld::body_index(const std::string& name) const {
  for (size_t i = 0; i < impl_->bodies.size(); ++i)
    if (impl_->bodies[i].spec.name == name) return int(i);
  return -1;
}

const RigidBoxSpec& RigidWorld::spec(int body) const { return impl_->body(body).spec; }
double RigidWorld::mass(int body) const { return impl_->body(body).spec.mass; }
Eigen::Vector3d RigidWorld::half_extents(int body) const { return 0.5 * impl_->body(body).spec.size; }

Eigen::Matrix3d RigidWorld::inertia_world(int body) const {
  const auto& b = impl_->body(body);
  const Eigen::Vector3d s = b.spec.size;
  const double m = b.spec.mass;
  // Solid cuboid about its centre: I_xx = m (b^2 + c^2) / 12, etc.
  const Eigen::Vector3d principal(m * (s.y() * s.y() + s.z() * s.z()) / 12.0,
                                  m * (s.x() * s.x() + s.z() * s.z()) / 12.0,
                                  m * (s.x() * s.x() + s.y() * s.y()) / 12.0);
  const Eigen::Matrix3d r = state(body).rotation;
  return r * principal.asDiagonal() * r.transpose();
}

void RigidWorld::apply_external(int body, const Eigen::Vector3d& force, const Eigen::Vector3d& torque) {
  auto& b = impl_->body(body);
  b.force += force;
  b.torque += torque;
}

void RigidWorld::apply_force_at(int body, const Eigen::Vector3d& force, const Eigen::Vector3d& point) {
  auto& b = impl_->body(body);
  const auto& v = impl_->views[body];
  const Eigen::Vector3d r = point - Eigen::Vector3d(v.centre[0], v.centre[1], v.centre[2]);
  b.force += force;
  b.torque += r.cross(force);
}

void RigidWorld::step(double dt) {
  if (!(dt > 0.0) || !std::isfinite(dt)) throw std::invalid_argument("RigidWorld::step: dt must be > 0");
  Impl& m = *impl_;
  const int n = std::max(1, int(std::ceil(dt / m.settings.max_substep * (1.0 - 1e-12))));
  const double h = dt / n;
  std::vector<Eigen::Vector3d> v0(m.bodies.size()), w0(m.bodies.size());
  for (size_t i = 0; i < m.bodies.size(); ++i) {
    v0[i] = from_bt(m.bodies[i].rb->getLinearVelocity());
    w0[i] = from_bt(m.bodies[i].rb->getAngularVelocity());
  }
  for (int k = 0; k < n; ++k) {
    // stepSimulation clears the accumulated forces after every call, so the water's load is re-applied for
    // each substep; maxSubSteps = 0 makes it take exactly one step of length h (no interpolation).
    for (auto& b : m.bodies) {
      b.rb->applyCentralForce(to_bt(b.force));
      b.rb->applyTorque(to_bt(b.torque));
    }
    m.world.stepSimulation(btScalar(h), 0, btScalar(h));
  }
  m.time += dt;
  for (size_t i = 0; i < m.bodies.size(); ++i) {
    auto& b = m.bodies[i];
    b.acceleration = (from_bt(b.rb->getLinearVelocity()) - v0[i]) / dt;
    b.angular_acceleration = (from_bt(b.rb->getAngularVelocity()) - w0[i]) / dt;
    b.force.setZero();
    b.torque.setZero();
    m.refresh_view(int(i));
  }
}

double RigidWorld::time() const { return impl_->time; }

void RigidWorld::checkpoint(StateArchive& ar) {
  Impl& m = *impl_;
  ar.section("rigid");
  ar.expect("debris bodies", m.bodies.size());
  ar(m.time);
  for (size_t i = 0; i < m.bodies.size(); ++i) {
    auto& b = m.bodies[i];
    btTransform t = b.rb->getWorldTransform();
    btVector3 v = b.rb->getLinearVelocity(), w = b.rb->getAngularVelocity();
    // Bullet integrates the basis, not a quaternion: keep its 9 entries and the origin exactly.
    btScalar basis[9], origin[3], lin[3], ang[3];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) basis[3 * r + c] = t.getBasis()[r][c];
      origin[r] = t.getOrigin()[r];
      lin[r] = v[r];
      ang[r] = w[r];
    }
    ar(basis);
    ar(origin);
    ar(lin);
    ar(ang);
    ar(b.acceleration);
    ar(b.angular_acceleration);
    if (ar.loading()) {
      t.setBasis(btMatrix3x3(basis[0], basis[1], basis[2], basis[3], basis[4], basis[5], basis[6], basis[7], basis[8]));
      t.setOrigin(btVector3(origin[0], origin[1], origin[2]));
      b.rb->setWorldTransform(t);
      b.rb->setInterpolationWorldTransform(t);
      b.rb->setLinearVelocity(btVector3(lin[0], lin[1], lin[2]));
      b.rb->setAngularVelocity(btVector3(ang[0], ang[1], ang[2]));
      b.rb->setInterpolationLinearVelocity(b.rb->getLinearVelocity());
      b.rb->setInterpolationAngularVelocity(b.rb->getAngularVelocity());
      b.rb->updateInertiaTensor();
      b.force.setZero();
      b.torque.setZero();
      m.refresh_view(int(i));
    }
  }
  if (ar.loading()) m.world.updateAabbs();
}

BodyState RigidWorld::state(int body) const {
  const auto& b = impl_->body(body);
  const btTransform& t = b.rb->getWorldTransform();
  const btQuaternion q = t.getRotation();
  BodyState s;
  s.position = from_bt(t.getOrigin());
  s.orientation = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z());
  const RigidBoxView& v = impl_->views[body];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) s.rotation(r, c) = v.rotation[r * 3 + c];
  s.velocity = from_bt(b.rb->getLinearVelocity());
  s.angular_velocity = from_bt(b.rb->getAngularVelocity());
  s.acceleration = b.acceleration;
  s.angular_acceleration = b.angular_acceleration;
  return s;
}

double RigidWorld::signed_distance(int body, const Eigen::Vector3d& point) const {
  return box_signed_distance(box_view(body), point.data());
}

Eigen::Vector3d RigidWorld::outward_normal(int body, const Eigen::Vector3d& point) const {
  Eigen::Vector3d n;
  box_outward_normal(box_view(body), point.data(), n.data());
  return n;
}

Eigen::Vector3d RigidWorld::surface_velocity(int body, const Eigen::Vector3d& point) const {
  Eigen::Vector3d v;
  box_surface_velocity(box_view(body), point.data(), v.data());
  return v;
}

const RigidBoxView& RigidWorld::box_view(int body) const {
  impl_->body(body);  // range check
  return impl_->views[body];
}
const std::vector<RigidBoxView>& RigidWorld::box_views() const { return impl_->views; }
const ContactCoefficients& RigidWorld::coefficients() const { return impl_->coefficients; }
const RigidSettings& RigidWorld::settings() const { return impl_->settings; }
const Eigen::Vector3d& RigidWorld::gravity() const { return impl_->gravity; }

}  // namespace flume
