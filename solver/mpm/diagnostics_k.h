// The particles' momentum and the rigid-rotation initial field, for both backends (Simulation::momentum and
// Simulation::set_rigid_velocity). Host code in double: diagnostics and set-up, not the step.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>

#include "solver/mpm_kernels.h"

namespace flume::mpm {

// Adds particle p's linear and angular momentum (about the origin, 3 components each) to P and L: x_p x m v_p
// plus the APIC spin m dx^2/4 eps_abc C_cb, the angular momentum the stencil's spread of mass gives the grid
// in P2G (Jiang et al. 2015, section 5.3; derivation and sign in docs/solver.md). C is row-major, C[a*D+b] =
// dv_a/dx_b; for a rigid rotation C = [omega]x and the spin is m dx^2/2 omega, turning with the body.
template <int D>
FLUME_HD void add_particle_momentum(double m, double dx, const double* x, const double* v, const double* C,
                                    double* P, double* L) {
  double x3[3] = {0, 0, 0}, v3[3] = {0, 0, 0};
  for (int d = 0; d < D; ++d) {
    x3[d] = x[d];
    v3[d] = v[d];
  }
  const double s = m * dx * dx / 4.0;
  for (int d = 0; d < 3; ++d) P[d] += m * v3[d];
  if constexpr (D == 3) {
    L[0] += m * (x3[1] * v3[2] - x3[2] * v3[1]) + s * (C[7] - C[5]);
    L[1] += m * (x3[2] * v3[0] - x3[0] * v3[2]) + s * (C[2] - C[6]);
    L[2] += m * (x3[0] * v3[1] - x3[1] * v3[0]) + s * (C[3] - C[1]);
  } else {
    L[2] += m * (x3[0] * v3[1] - x3[1] * v3[0]) + s * (C[2] - C[1]);
  }
}

// The velocity and APIC matrix of a rigid motion v = v0 + omega x r at r = x - centre (in 2D only omega[2],
// about the out-of-plane axis): C = [omega]x, the exact gradient of the field.
template <int D>
FLUME_HD void rigid_motion(const double* v0, const double* omega, const double* r, double* v, double* C) {
  if constexpr (D == 3) {
    v[0] = v0[0] + omega[1] * r[2] - omega[2] * r[1];
    v[1] = v0[1] + omega[2] * r[0] - omega[0] * r[2];
    v[2] = v0[2] + omega[0] * r[1] - omega[1] * r[0];
    const double W[9] = {0, -omega[2], omega[1], omega[2], 0, -omega[0], -omega[1], omega[0], 0};
    for (int k = 0; k < 9; ++k) C[k] = W[k];
  } else {
    v[0] = v0[0] - omega[2] * r[1];
    v[1] = v0[1] + omega[2] * r[0];
    const double W[4] = {0, -omega[2], omega[2], 0};
    for (int k = 0; k < 4; ++k) C[k] = W[k];
  }
}

// Simulation::momentum over n particles in host arrays (x, v: D arrays; C: D*D; vol: reference volumes):
// linear and angular momentum about the origin, summed in particle order.
template <int D, class Array>
void particles_momentum(size_t n, double rho, double dx, const Array* x, const Array* v, const Array* C,
                        const Array& vol, double* P, double* L) {
  for (int d = 0; d < 3; ++d) P[d] = L[d] = 0;
  for (size_t i = 0; i < n; ++i) {
    double xp[D], vp[D], Cp[D * D];
    for (int d = 0; d < D; ++d) {
      xp[d] = x[d][i];
      vp[d] = v[d][i];
    }
    for (int k = 0; k < D * D; ++k) Cp[k] = C[k][i];
    add_particle_momentum<D>(rho * double(vol[i]), dx, xp, vp, Cp, P, L);
  }
}

// Simulation::set_rigid_velocity over n particles in host arrays: v and C of the rigid motion (rigid_motion)
// about `centre`. Returns the largest speed.
template <int D, class Array>
double impose_rigid_motion(size_t n, const double* v0, const double* omega, const double* centre,
                           const Array* x, Array* v, Array* C) {
  using T = typename Array::value_type;
  for (size_t i = 0; i < n; ++i) {
    double r[D], vp[D], Cp[D * D];
    for (int d = 0; d < D; ++d) r[d] = x[d][i] - centre[d];
    rigid_motion<D>(v0, omega, r, vp, Cp);
    for (int d = 0; d < D; ++d) v[d][i] = T(vp[d]);
    for (int k = 0; k < D * D; ++k) C[k][i] = T(Cp[k]);
  }
  double max_speed = 0;
  for (size_t i = 0; i < n; ++i) {
    double s2 = 0;
    for (int d = 0; d < D; ++d) s2 += double(v[d][i]) * v[d][i];
    max_speed = std::max(max_speed, std::sqrt(s2));
  }
  return max_speed;
}

}  // namespace flume::mpm
