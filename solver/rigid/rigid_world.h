// Rigid debris (shipping-container boxes) with 6-DOF dynamics and Coulomb/restitution contact against the flume's
// boundaries and each other. Contact is Bullet's (libbullet-dev); this header is Bullet-free so the solver and the
// CUDA code never include Bullet. The MPM water couples in through apply_external() (loads from the shared grid)
// and the geometry queries / box_views() (moving boundary for the grid update).
//
// Frame and units as in scene.h: SI, z up. 3D only.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "solver/rigid/rigid_box_geometry.h"
#include "solver/scene.h"

namespace flume {

class StateArchive;

// Orientation quaternion (w, x, y, z). Unaligned on purpose: Eigen aligns Quaterniond to 16 or 32 bytes depending
// on the SIMD flags a file is compiled with, so the layout of a struct holding one would differ between, say,
// this library (-march=native) and a CUDA host file (no -march); DontAlign makes the layout the same everywhere.
// Converts to and from Eigen::Quaterniond implicitly.
using RigidQuaternion = Eigen::Quaternion<double, Eigen::DontAlign>;

// Coulomb friction and restitution for the two kinds of contact pair. Bullet's default combine rule (product of
// the two bodies' values) cannot express these, so RigidWorld sets each pair's values itself.
// The paper's Table 2 ranges: friction 0.15-0.80 (flume) and 0.05-0.80 (debris), restitution 0.30-0.60 (flume)
// and 0.40-0.70 (debris); any value in [0, 1] for restitution and >= 0 for friction is accepted.
struct ContactCoefficients {
  double friction_flume = 0.5;       // debris against any boundary (floor, apron, quay, walls, columns)
  double friction_debris = 0.4;      // debris against debris
  double restitution_flume = 0.45;   // normal-velocity ratio after/before a debris-boundary impact
  double restitution_debris = 0.55;  // the same for a debris-debris impact
};

// One debris box. `size` holds the full edge lengths along the body axes; the Waseda container is
// {0.15, 0.06, 0.06} m, 0.226 kg, with body x (its long side) across the flow, i.e. along world y.
struct RigidBoxSpec {
  std::string name;  // instrument name, e.g. "D1" (HDF5 group /debris/D1)
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  double mass = 0.0;     // kg; when 0, mass = density * volume
  double density = 0.0;  // kg/m^3, used only when mass is 0
  Eigen::Vector3d position = Eigen::Vector3d::Zero();                  // centre (of mass), m
  RigidQuaternion orientation = RigidQuaternion::Identity();           // body -> world, (w, x, y, z)
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();                  // m/s
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();          // rad/s, world frame
};

struct BodyState {
  Eigen::Vector3d position;      // centre of mass, m
  RigidQuaternion orientation;   // body -> world
  Eigen::Matrix3d rotation;      // body -> world
  Eigen::Vector3d velocity;
  Eigen::Vector3d angular_velocity;  // world frame
  // Mean accelerations over the last step(dt): (v(t + dt) - v(t)) / dt; zero before the first step.
  Eigen::Vector3d acceleration;
  Eigen::Vector3d angular_acceleration;
};

// Integration and contact-solver settings. The defaults are chosen for the 1:40 flume (6 cm, 0.226 kg boxes,
// impact speeds up to a few m/s); rigid_world.cpp explains each.
struct RigidSettings {
  double max_substep = 1.0e-4;                    // s; step(dt) splits dt into equal substeps no longer than this
  int solver_iterations = 60;                     // sequential-impulse sweeps per substep
  double restitution_velocity_threshold = 0.02;   // m/s; slower normal approaches do not bounce
  double split_impulse_erp = 0.8;                 // fraction of a penetration removed per substep
};

class RigidWorld {
 public:
  RigidWorld(const ContactCoefficients& coefficients, const Eigen::Vector3d& gravity,
             const RigidSettings& settings = {});
  ~RigidWorld();
  RigidWorld(RigidWorld&&) noexcept;
  RigidWorld& operator=(RigidWorld&&) noexcept;
  RigidWorld(const RigidWorld&) = delete;
  RigidWorld& operator=(const RigidWorld&) = delete;

  // Static flume geometry (all of it uses the flume-debris coefficients). Box: the solid [lo, hi].
  // Half-space: the solid {x : (x - point) . outward_normal < 0}, as scene.h's Shape.
  void add_static_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);
  void add_static_half_space(const Eigen::Vector3d& point, const Eigen::Vector3d& outward_normal);
  void add_static_shape(const Shape& shape);  // a scene boundary's shape, either kind

  // Adds a debris box; returns its index (0, 1, ... in the order added). Throws InputError on a bad spec.
  int add_box(const RigidBoxSpec& spec);
  int body_count() const;
  int body_index(const std::string& name) const;  // -1 when there is none
  const RigidBoxSpec& spec(int body) const;       // as given (mass filled in when density was)
  double mass(int body) const;
  Eigen::Matrix3d inertia_world(int body) const;   // about the centre, current orientation
  Eigen::Vector3d half_extents(int body) const;

  // Loads from the water for the next step(): force through the centre and torque about the centre, both
  // world frame. Calls add up; the sum acts constantly over the whole next step(dt) and is then cleared.
  void apply_external(int body, const Eigen::Vector3d& force, const Eigen::Vector3d& torque_about_centre);
  // The same for a force acting at a world point (adds (point - centre) x force to the torque).
  void apply_force_at(int body, const Eigen::Vector3d& force, const Eigen::Vector3d& point);

  // Advances all bodies by dt (any dt > 0; 1e-6 .. 1e-3 s in practice) in equal substeps <= max_substep.
  void step(double dt);
  double time() const;

  BodyState state(int body) const;

  // Geometry for the grid coupling, at the state after the last step. Plain reads of cached data: safe to call
  // from many threads at once (not concurrently with step()).
  double signed_distance(int body, const Eigen::Vector3d& point) const;  // negative inside
  Eigen::Vector3d outward_normal(int body, const Eigen::Vector3d& point) const;
  Eigen::Vector3d surface_velocity(int body, const Eigen::Vector3d& point) const;  // v + omega x (p - c)
  const RigidBoxView& box_view(int body) const;
  const std::vector<RigidBoxView>& box_views() const;  // one per body, index = body; POD, copy to the GPU as is

  // The bodies' poses, velocities and last accelerations, and the clock (solver/checkpoint.h). Bullet's contact
  // caches (the warm-start impulses of the persistent manifolds) are not kept: after a resume they are
  // rebuilt from the next contact, so a resumed run with touching boxes differs from an uninterrupted one by
  // what one step's warm start changes (tests/solver/test_checkpoint.cpp measures it).
  void checkpoint(StateArchive& ar);

  const ContactCoefficients& coefficients() const;
  const RigidSettings& settings() const;
  const Eigen::Vector3d& gravity() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace flume
