// The SPH run's debris particles from step to step (debris_particles.h says what they are): their positions and
// velocities taken from the boxes, their densities evolved as the walls', the water's force on each, and the
// loads summed from those forces. The pair loops that fill the rates are the solver's (sph_solver.cpp), beside
// the walls'.
//
// Within a step the boxes move as the symplectic scheme's predictor has them: the mid-step evaluation sees the
// particles at x + v dt/2 with the box's velocity at t, and the box is stepped by dt with the mid-step load, so
// the water and the box exchange that load's impulse exactly (the pair terms are antisymmetric).
#pragma once
#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <vector>

#include "common/errors.h"
#include "solver/debris_coupling.h"
#include "solver/sph/cell_list.h"
#include "solver/sph/debris_particles.h"
#include "solver/sph/sph_launch.h"

namespace flume::sph {

template <int D, typename T>
struct SphDebris {
  using Load = Eigen::Matrix<double, 6, 1>;

  std::size_t n = 0;
  std::vector<T> x[D], xh[D], v[D];    // at t, at the mid-step; velocity (the box's at t)
  std::vector<T> g[D];                 // to the ghost node (mDBC), in the world frame at t
  std::vector<T> rho, rhoh, drho;      // density at t and at the mid-step, its rate
  std::vector<T> p, ir, f[D];          // pressure and 1/rho of the state last evaluated; the water's force
  std::vector<T> mass;
  std::vector<int> body;
  std::vector<double> offset[3];       // body frame
  std::vector<double> ghost[3];        // body frame
  CellList list;

  void seed(const DebrisParticles& s, T rho0) {
    n = s.size();
    for (int a = 0; a < 3; ++a) {
      offset[a] = s.offset[a];
      ghost[a] = s.ghost[a];
    }
    body = s.body;
    mass.assign(s.mass.begin(), s.mass.end());
    for (int d = 0; d < D; ++d) {
      x[d].assign(n, T(0));
      xh[d].assign(n, T(0));
      v[d].assign(n, T(0));
      g[d].assign(n, T(0));
      f[d].assign(n, T(0));
    }
    rho.assign(n, rho0);
    rhoh.assign(n, rho0);
    drho.assign(n, T(0));
    p.assign(n, T(0));
    ir.assign(n, T(1) / rho0);
  }

  // Each particle at its box's present pose, moving with it.
  void place(const DebrisCoupling& debris) {
    if constexpr (D == 3) {
      std::vector<BodyState> s(debris.body_count());
      for (int b = 0; b < debris.body_count(); ++b) s[b] = debris.world().state(b);
      parallel_for(n, [&](std::size_t k) {
        const BodyState& b = s[body[k]];
        const Eigen::Vector3d r = b.rotation * Eigen::Vector3d(offset[0][k], offset[1][k], offset[2][k]);
        const Eigen::Vector3d u = b.velocity + b.angular_velocity.cross(r);
        const Eigen::Vector3d gk = b.rotation * Eigen::Vector3d(ghost[0][k], ghost[1][k], ghost[2][k]);
        for (int d = 0; d < 3; ++d) {
          x[d][k] = T(b.position[d] + r[d]);
          v[d][k] = T(u[d]);
          g[d][k] = T(gk[d]);
        }
      });
    }
  }

  // Orders the particles by cell, as the fluid's. False when one lies outside the grid.
  bool sort(const CellGrid<D>& grid) {
    list.cell.resize(n);
    bool inside = true;
    for (std::size_t k = 0; k < n; ++k) {
      T q[D];
      int c[D];
      for (int d = 0; d < D; ++d) q[d] = x[d][k];
      if (!grid.cell_of(q, c)) {
        inside = false;
        list.cell[k] = 0;
        continue;
      }
      list.cell[k] = static_cast<uint32_t>(grid.index(c));
    }
    list.build(grid.count);
    auto permute = [&](auto& a) {
      auto tmp = a;
      for (std::size_t k = 0; k < n; ++k) tmp[k] = a[list.order[k]];
      a.swap(tmp);
    };
    for (int d = 0; d < D; ++d) {
      permute(x[d]);
      permute(v[d]);
      permute(g[d]);
    }
    for (int a = 0; a < 3; ++a) {
      permute(offset[a]);
      permute(ghost[a]);
    }
    permute(rho);
    permute(mass);
    permute(body);
    permute(list.cell);
    return inside;
  }

  // The predictor's half step: positions and densities at t + dt/2.
  void predict(T dt, T rho0) {
    const T h = T(0.5) * dt;
    parallel_for(n, [&](std::size_t k) {
      for (int d = 0; d < D; ++d) xh[d][k] = x[d][k] + h * v[d][k];
      rhoh[k] = std::max(rho0, rho[k] + h * drho[k]);
    });
  }

  // The water's load on every box from the forces of the last evaluation, the torque about each box's centre
  // at t.
  std::vector<Load> loads(const DebrisCoupling& debris) const {
    std::vector<Load> load(debris.body_count(), Load::Zero());
    if constexpr (D == 3) {
      std::vector<Eigen::Vector3d> centre(debris.body_count());
      for (int b = 0; b < debris.body_count(); ++b) centre[b] = debris.world().state(b).position;
      for (std::size_t k = 0; k < n; ++k) {
        const Eigen::Vector3d F(f[0][k], f[1][k], f[2][k]);
        const Eigen::Vector3d r = Eigen::Vector3d(x[0][k], x[1][k], x[2][k]) - centre[body[k]];
        load[body[k]].template head<3>() += F;
        load[body[k]].template tail<3>() += r.cross(F);
      }
    }
    return load;
  }

  double max_speed2() const {
    return parallel_max<double>(n, [&](std::size_t k) {
      double s = 0;
      for (int d = 0; d < D; ++d) s += double(v[d][k]) * v[d][k];
      return s;
    });
  }
};

}  // namespace flume::sph
