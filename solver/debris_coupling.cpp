#include "solver/debris_coupling.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "common/errors.h"
#include "solver/checkpoint.h"

namespace flume {
namespace {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

Eigen::Vector3d v3(const Vec3d& a) { return {a[0], a[1], a[2]}; }

}  // namespace

DebrisCoupling::DebrisCoupling(const Scene& scene)
    : world_(ContactCoefficients{scene.debris.friction_flume, scene.debris.friction_debris,
                                 scene.debris.restitution_flume, scene.debris.restitution_debris},
             v3(scene.solver.gravity)),
      gravity_(v3(scene.solver.gravity)) {
  if (scene.dimension != 3) throw InputError(scene.file, "debris", "debris need a 3D scene");
  // The boxes collide with every solid of the scene and with the domain's walls.
  for (const auto& b : scene.boundaries) world_.add_static_shape(b.shape);
  for (int a = 0; a < 3; ++a) {
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    n[a] = 1.0;
    world_.add_static_half_space(v3(scene.domain_lo), n);
    world_.add_static_half_space(v3(scene.domain_hi), -n);
  }
  for (const auto& d : scene.debris.bodies) {
    RigidBoxSpec spec;
    spec.name = d.name;
    spec.size = v3(d.size);
    spec.mass = d.mass;
    spec.position = v3(d.position);
    spec.orientation = RigidQuaternion(d.orientation[0], d.orientation[1], d.orientation[2], d.orientation[3]);
    world_.add_box(spec);
    radius_.push_back(0.5 * spec.size.norm());
  }
  water_force_.assign(radius_.size(), Eigen::Vector3d::Zero());
  pending_.assign(radius_.size(), Eigen::Matrix<double, 6, 1>::Zero());
  recorder_ = std::make_unique<DebrisRecorder>(world_, scene.debris.resample_hz, scene.debris.record_rate_hz);
  recorder_->record();
}

int DebrisCoupling::locate(const double x[3], double tol, double n[3]) const {
  const auto& views = world_.box_views();
  int best = -1;
  double best_d = tol;
  for (int b = 0; b < int(views.size()); ++b) {
    const auto& v = views[b];
    const double r2 = (x[0] - v.centre[0]) * (x[0] - v.centre[0]) + (x[1] - v.centre[1]) * (x[1] - v.centre[1]) +
                      (x[2] - v.centre[2]) * (x[2] - v.centre[2]);
    if (r2 > radius_[b] * radius_[b] + 1e-12) continue;
    const double d = box_signed_distance(v, x);
    if (d <= best_d) {
      best_d = d;
      best = b;
    }
  }
  if (best >= 0) box_outward_normal(views[best], x, n);
  return best;
}

void DebrisCoupling::exchange(std::vector<CouplingNode>& nodes, double dt) {
  const int nb = body_count();
  // Nodes of each body, in the given (grid) order.
  std::vector<std::vector<size_t>> of(nb);
  for (size_t i = 0; i < nodes.size(); ++i) of[nodes[i].body].push_back(i);
  for (int b = 0; b < nb; ++b) {
    const BodyState s = world_.state(b);
    const double M = world_.mass(b);
    Matrix6d Mb = Matrix6d::Zero();
    Mb.topLeftCorner<3, 3>() = M * Eigen::Matrix3d::Identity();
    Mb.bottomRightCorner<3, 3>() = world_.inertia_world(b);
    Vector6d U;
    U << s.velocity, s.angular_velocity;
    Vector6d rhs0 = Mb * U + pending_[b];
    rhs0.head<3>() += M * gravity_ * dt;
    // Jacobians and normal node velocities.
    const auto& list = of[b];
    std::vector<Vector6d> G(list.size());
    std::vector<double> vn(list.size());
    for (size_t k = 0; k < list.size(); ++k) {
      const CouplingNode& c = nodes[list[k]];
      const Eigen::Vector3d n(c.n[0], c.n[1], c.n[2]), x(c.x[0], c.x[1], c.x[2]);
      G[k] << n, (x - s.position).cross(n);
      vn[k] = n.dot(Eigen::Vector3d(c.v[0], c.v[1], c.v[2]));
    }
    // Active set: nodes whose water approaches the box (normal velocity below the box surface's). Starts from
    // the box's current velocity and is iterated to a fixed point; it settles in one or two sweeps.
    Vector6d Unew = U;
    std::vector<char> active(list.size(), 0);
    Vector6d free_motion = Mb.ldlt().solve(rhs0);  // the box with no water load
    Unew = free_motion;
    for (int sweep = 0; sweep < 8; ++sweep) {
      bool changed = false;
      for (size_t k = 0; k < list.size(); ++k) {
        const char a = vn[k] < G[k].dot(sweep == 0 ? U : Unew) ? 1 : 0;
        changed |= a != active[k];
        active[k] = a;
      }
      if (!changed && sweep > 0) break;
      Matrix6d A = Mb;
      Vector6d rhs = rhs0;
      for (size_t k = 0; k < list.size(); ++k) {
        if (!active[k]) continue;
        const double m = nodes[list[k]].m;
        A.noalias() += m * G[k] * G[k].transpose();
        rhs += m * vn[k] * G[k];
      }
      Unew = A.ldlt().solve(rhs);
    }
    // The nodes take the box's normal velocity where the water approached it.
    for (size_t k = 0; k < list.size(); ++k) {
      CouplingNode& c = nodes[list[k]];
      const double target = G[k].dot(Unew);
      if (vn[k] < target)
        for (int d = 0; d < 3; ++d) c.v[d] += (target - vn[k]) * c.n[d];
    }
    // The water's load over the step: what moved the box from U to U' beyond gravity.
    const Vector6d load = Mb * (Unew - U) / dt;
    pending_[b].setZero();
    const Eigen::Vector3d force = load.head<3>() - M * gravity_;
    const Eigen::Vector3d torque = load.tail<3>();
    water_force_[b] = force;
    world_.apply_external(b, force, torque);
  }
  world_.step(dt);
  recorder_->record();
}

void DebrisCoupling::add_particle_impulse(int body, const double impulse[3], const double moment[3]) {
  const Eigen::Vector3d J(impulse[0], impulse[1], impulse[2]), L(moment[0], moment[1], moment[2]);
  const Eigen::Vector3d c(world_.box_view(body).centre[0], world_.box_view(body).centre[1],
                          world_.box_view(body).centre[2]);
  pending_[body].head<3>() += J;
  pending_[body].tail<3>() += L - c.cross(J);  // about the centre
}

void DebrisCoupling::checkpoint(StateArchive& ar) {
  ar.section("debris");
  world_.checkpoint(ar);
  recorder_->checkpoint(ar);
  ar(water_force_);
  ar(pending_);
}

double DebrisCoupling::energy() const {
  double e = 0;
  for (int b = 0; b < body_count(); ++b) {
    const BodyState s = world_.state(b);
    e += 0.5 * world_.mass(b) * s.velocity.squaredNorm();
    e += 0.5 * s.angular_velocity.dot(world_.inertia_world(b) * s.angular_velocity);
    e -= world_.mass(b) * gravity_.dot(s.position);
  }
  return e;
}

}  // namespace flume
