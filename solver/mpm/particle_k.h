// One particle's share of the step, written once for both backends: what it scatters in P2G and how G2P
// updates it from what it gathered. The backends differ in how they sum over the stencil (the CPU's tiles,
// separable and vectorised, against the GPU's one thread per particle with atomics), not in these formulas.
#pragma once
#include "solver/mpm_kernels.h"

namespace flume::mpm {

// P2G, one particle (Hu et al. 2018, eq. 29): the affine momentum A = -dt (4/dx^2) V J sigma + m C, with
// sigma the fluid's stress at pressure p (mpm::viscous_stress_with_pressure), and what a node at offset i (in
// cells, from the stencil's base) receives before its weight: momentum mom0 + A i dx, where mom0 = m v - A f
// dx; the mass-weighted strain less its hydrostatic part (mpm::hydrostatic_strain), `strain`; and the
// particle's current volume V J, `volume`, for the fill of its nodes (mpm::fill_correction). stress_scale =
// -dt 4 / dx^2.
template <int D, typename T>
FLUME_HD void p2g_particle(T p, const T* C, T e, T V, T m, const T* v, const T* f, const T* x, T dx, T mu,
                           T stress_scale, const T* slope, T* A, T* mom0, T& strain, T& volume) {
  T sigma[D * D];
  viscous_stress_with_pressure<D>(p, C, mu, sigma);
  for (int k = 0; k < D * D; ++k) A[k] = stress_scale * V * (T(1) + e) * sigma[k] + m * C[k];
  for (int a = 0; a < D; ++a) {
    T sum = m * v[a];
    for (int b = 0; b < D; ++b) sum -= A[a * D + b] * f[b] * dx;
    mom0[a] = sum;
  }
  strain = m * (e - hydrostatic_strain<D>(x, slope));
  volume = V * (T(1) + e);
}

// The constants of G2P's particle update, the same for every particle of a step.
template <int D, typename T>
struct G2pConstants {
  T dt = 0, psi = 0;
  T fill_rate = 0, fill_tol = 0;  // mpm::fill_correction
  T slope[D] = {};                // mpm::hydrostatic_strain
  TaitLaw<double> law_d;          // for the work of the volume constraint, in double
  bool has_sym = false;
  SymmetryPlane sym;
};

// G2P, one particle, from what it gathered: velocity vn, APIC matrix Cn (scaled, dv_a/dx_b), and over the
// free (non-wall) nodes of its stencil the weighted sums of strain Jg, fill Fg and weight wsum. Updates the
// strain e by the well-balanced J-bar and the volume constraint, then moves x. The grid average leaves out
// nodes that a wall set: their strain is an average over particles on one side only, and the discrete
// equilibrium next to a wall is not the linear field the average preserves, so mixing them in would drive a
// slow creep that never settles. The remaining nodes are renormalised; a particle with no free node in reach
// keeps its own J (psi = 0). A particle carried across a symmetry plane is replaced by its image. Returns the
// elastic energy the constraint supplied (J; what it removes is dissipation and is not returned): the energy
// audit counts it as supplied.
template <int D, typename T>
FLUME_HD double g2p_particle(const G2pConstants<D, T>& k, T Jg, T Fg, T wsum, T vol, T& e, T* x, T* vn,
                             T* Cn) {
  const bool have_grid = wsum > T(1e-3);
  const T e_grid = (have_grid ? Jg / wsum : T(0)) + hydrostatic_strain<D>(x, k.slope);
  T e_new = jbar_update(e, e_grid, volume_change<D>(Cn, k.dt), have_grid ? k.psi : T(0));
  double work = 0;
  if (have_grid) {
    const T corrected = fill_correction(e_new, Fg / wsum, k.fill_rate, k.fill_tol);
    if (corrected != e_new) {
      work =
          double(vol) * (k.law_d.energy_density(double(corrected)) - k.law_d.energy_density(double(e_new)));
      work = work > 0.0 ? work : 0.0;
    }
    e_new = corrected;
  }
  e = e_new;
  for (int d = 0; d < D; ++d) x[d] += k.dt * vn[d];
  if (k.has_sym) symmetry_reflect_particle<D>(k.sym, x, vn, Cn);  // carried across: its image instead
  return work;
}

}  // namespace flume::mpm
