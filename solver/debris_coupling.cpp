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
  for (const auto& b : scene.boundaries) solids_.push_back(b.shape);
  domain_lo_ = v3(scene.domain_lo);
  domain_hi_ = v3(scene.domain_hi);
  dx_ = scene.solver.dx;
  rho_water_ = scene.fluid.density;
  water_force_.assign(radius_.size(), Eigen::Vector3d::Zero());
  film_force_.assign(radius_.size(), Eigen::Vector3d::Zero());
  pending_.assign(radius_.size(), Eigen::Matrix<double, 6, 1>::Zero());
  recorder_ = std::make_unique<DebrisRecorder>(world_, scene.debris.resample_hz, scene.debris.record_rate_hz);
  recorder_->record();
}

int DebrisCoupling::locate(const double x[3], double tol, double n[3]) const {
  return mpm::locate_box(world_.box_views().data(), radius_.data(), static_cast<int>(radius_.size()), x, tol, n);
}

bool DebrisCoupling::in_static_solid(const Eigen::Vector3d& x) const {
  for (int a = 0; a < 3; ++a)
    if (x[a] < domain_lo_[a] || x[a] > domain_hi_[a]) return true;
  const Vec3d p{x[0], x[1], x[2]};
  for (const Shape& s : solids_)
    if (shape_distance(s, p, 3) < 0) return true;
  return false;
}

int DebrisCoupling::box_at(const Eigen::Vector3d& x, int skip) const {
  const auto& views = world_.box_views();
  for (int b = 0; b < int(views.size()); ++b)
    if (b != skip && box_signed_distance(views[b], x.data()) < 0) return b;
  return -1;
}

// The film under each box's lowest face (debris_coupling.h).
void DebrisCoupling::film_loads(const std::vector<CouplingNode>& nodes, const std::vector<std::vector<size_t>>& of,
                                std::vector<Vector6d>& load) {
  const int nb = body_count();
  for (int b = 0; b < nb; ++b) load[b].setZero();
  const double g = gravity_.norm();
  if (!(g > 0)) return;
  const auto& views = world_.box_views();
  constexpr int kGapSteps = 8;        // the gap is sought in eighths of a cell,
  constexpr int kGapBisections = 5;   // then to 1/256 of a cell
  constexpr double kRimBin = 1.5;     // rim bins at least this many cells long
  for (int b = 0; b < nb; ++b) {
    const RigidBoxView& v = views[b];
    Eigen::Matrix3d R;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) R(i, j) = v.rotation[i * 3 + j];
    const Eigen::Vector3d c(v.centre[0], v.centre[1], v.centre[2]);
    // The lowest face: the outward normal closest to gravity's direction, within 45 degrees.
    int axis = 0;
    double sign = 1, best = -2;
    for (int a = 0; a < 3; ++a)
      for (const double s : {1.0, -1.0}) {
        const double dot = s * R.col(a).dot(gravity_) / g;
        if (dot > best) {
          best = dot;
          axis = a;
          sign = s;
        }
      }
    if (best < std::sqrt(0.5)) continue;
    const Eigen::Vector3d n = sign * R.col(axis);
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    const double h1 = v.half_extent[a1], h2 = v.half_extent[a2], ha = v.half_extent[axis];
    const Eigen::Vector3d e1 = R.col(a1), e2 = R.col(a2), face = c + ha * n;
    // The rim's pressure at the face's level: bins along the four sides.
    const int m1 = std::max(1, int(std::floor(2 * h1 / (kRimBin * dx_))));  // bins along a1 (the sides normal to a2)
    const int m2 = std::max(1, int(std::floor(2 * h2 / (kRimBin * dx_))));  // bins along a2 (the sides normal to a1)
    const int bins = 2 * (m1 + m2);
    std::vector<double> mass(bins, 0.0), mp(bins, 0.0);
    const double gn = gravity_.dot(n);
    for (const size_t i : of[b]) {
      const CouplingNode& nd = nodes[i];
      const Eigen::Vector3d x(nd.x[0], nd.x[1], nd.x[2]), r = R.transpose() * (x - c);
      const double q = sign * r[axis] - ha;  // beyond the face's plane
      if (q < -0.5 * dx_ || q > 0.5 * dx_ || !(nd.m > 0)) continue;  // the one node layer at the face's level
      const double d1 = std::fabs(r[a1]) - h1, d2 = std::fabs(r[a2]) - h2;
      if (d1 <= 0 && d2 <= 0) continue;  // under the face, not round it
      int bin;
      if (d1 >= d2) {  // beside a side normal to a1, binned along a2
        const int k = std::clamp(int(std::floor((r[a2] + h2) / (2 * h2) * m2)), 0, m2 - 1);
        bin = (r[a1] > 0 ? 0 : m2) + k;
      } else {
        const int k = std::clamp(int(std::floor((r[a1] + h1) / (2 * h1) * m1)), 0, m1 - 1);
        bin = 2 * m2 + (r[a2] > 0 ? 0 : m1) + k;
      }
      mass[bin] += nd.m;
      mp[bin] += nd.m * (nd.p - rho_water_ * q * gn);  // carried to the face's level
    }
    double sum = 0;
    int counted = 0;
    for (int k = 0; k < bins; ++k) {
      // The bin's centre, a quarter cell above the face's level and half a cell out: inside a solid, no water
      // can stand there and the bin is left out.
      Eigen::Vector3d at = face - 0.25 * dx_ * n;
      if (k < 2 * m2) {
        const int j = k % m2;
        at += (k < m2 ? 1.0 : -1.0) * (h1 + 0.5 * dx_) * e1 + (-h2 + (j + 0.5) * 2 * h2 / m2) * e2;
      } else {
        const int j = (k - 2 * m2) % m1;
        at += (k - 2 * m2 < m1 ? 1.0 : -1.0) * (h2 + 0.5 * dx_) * e2 + (-h1 + (j + 0.5) * 2 * h1 / m1) * e1;
      }
      if (in_static_solid(at) || box_at(at, b) >= 0) continue;
      ++counted;
      if (mass[k] > 0) sum += mp[k] / mass[k];
    }
    const double pf = counted ? std::max(0.0, sum / counted) : 0.0;
    if (!(pf > 0)) continue;  // a dry rim: no film, whatever lies beneath
    // Patches of the face with a solid less than a cell beneath.
    const int n1 = std::max(1, int(std::ceil(4 * h1 / dx_))), n2 = std::max(1, int(std::ceil(4 * h2 / dx_)));
    const double s1 = 2 * h1 / n1, s2 = 2 * h2 / n2;
    struct Patch {
      Eigen::Vector3d at;
      double w;
      int support;  // the box beneath, or -1 for a static solid
    };
    std::vector<Patch> patches;
    for (int i1 = 0; i1 < n1; ++i1)
      for (int i2 = 0; i2 < n2; ++i2) {
        const Eigen::Vector3d P = face + (-h1 + (i1 + 0.5) * s1) * e1 + (-h2 + (i2 + 0.5) * s2) * e2;
        // What lies at P + t dx n: -2 nothing, -1 a static solid, else the box.
        const auto solid_at = [&](double t) {
          const Eigen::Vector3d Q = P + t * dx_ * n;
          if (in_static_solid(Q)) return -1;
          const int box = box_at(Q, b);
          return box >= 0 ? box : -2;
        };
        for (int k = 1; k <= kGapSteps; ++k) {
          int support = solid_at(double(k) / kGapSteps);
          if (support == -2) continue;
          double lo = double(k - 1) / kGapSteps, hi = double(k) / kGapSteps;  // the surface lies between
          for (int it = 0; it < kGapBisections; ++it) {
            const double mid = 0.5 * (lo + hi);
            const int at = solid_at(mid);
            if (at == -2) {
              lo = mid;
            } else {
              hi = mid;
              support = at;
            }
          }
          patches.push_back({P, 1.0 - 0.5 * (lo + hi), support});
          break;
        }
      }
    for (const Patch& p : patches) {
      const Eigen::Vector3d F = -pf * p.w * s1 * s2 * n;  // pushes the face off the solid
      load[b].head<3>() += F;
      load[b].tail<3>() += (p.at - c).cross(F);
      if (p.support >= 0) {
        const Eigen::Vector3d cs(views[p.support].centre[0], views[p.support].centre[1], views[p.support].centre[2]);
        load[p.support].head<3>() -= F;
        load[p.support].tail<3>() -= (p.at - cs).cross(F);
      }
    }
  }
}

std::vector<std::vector<size_t>> DebrisCoupling::points_of(const std::vector<CouplingNode>& points) const {
  std::vector<std::vector<size_t>> of(body_count());
  for (size_t i = 0; i < points.size(); ++i) of[points[i].body].push_back(i);
  return of;
}

std::vector<Vector6d> DebrisCoupling::recorded_film(const std::vector<CouplingNode>& points,
                                                    const std::vector<std::vector<size_t>>& of) {
  std::vector<Vector6d> load(body_count());
  film_loads(points, of, load);
  for (int b = 0; b < body_count(); ++b) film_force_[b] = load[b].head<3>();
  return load;
}

void DebrisCoupling::exchange(std::vector<CouplingNode>& nodes, double dt) {
  const int nb = body_count();
  const auto of = points_of(nodes);  // the nodes of each body, in the given (grid) order
  const std::vector<Vector6d> film = recorded_film(nodes, of);
  for (int b = 0; b < nb; ++b) {
    const BodyState s = world_.state(b);
    const double M = world_.mass(b);
    Matrix6d Mb = Matrix6d::Zero();
    Mb.topLeftCorner<3, 3>() = M * Eigen::Matrix3d::Identity();
    Mb.bottomRightCorner<3, 3>() = world_.inertia_world(b);
    Vector6d U;
    U << s.velocity, s.angular_velocity;
    Vector6d rhs0 = Mb * U + pending_[b] + film[b] * dt;
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

std::vector<Vector6d> DebrisCoupling::film(const std::vector<CouplingNode>& points) {
  return recorded_film(points, points_of(points));
}

void DebrisCoupling::step_with_loads(const std::vector<Vector6d>& load, double dt) {
  for (int b = 0; b < body_count(); ++b) {
    water_force_[b] = load[b].head<3>();
    world_.apply_external(b, load[b].head<3>(), load[b].tail<3>());
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
