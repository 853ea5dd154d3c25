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

// FLIP's old grid velocity (solver.flip): what node i receives from the transfer alone, the particle's
// momentum and APIC's affine part without the stress's impulse, before its weight: tmom0 + (m C) i dx, tmom0
// = m v - m C f dx. Divided by the node's mass it is the velocity the grid had before the step's forces.
template <int D, typename T>
FLUME_HD void p2g_transfer_momentum(T m, const T* v, const T* C, const T* f, T dx, T* tmom0) {
  for (int a = 0; a < D; ++a) {
    T sum = m * v[a];
    for (int b = 0; b < D; ++b) sum -= m * C[a * D + b] * f[b] * dx;
    tmom0[a] = sum;
  }
}

// G2P's velocity blended with FLIP (Zhu & Bridson 2005; over APIC, the alpha of Fei et al. 2021): the grid's
// new velocity at the particle plus alpha times what the transfer lost, the particle's own velocity less the
// grid's old velocity at it. APIC alone (alpha 0) loses that part at every step, a loss per step rather than
// per second, so that the flow through the sluice gate fell as the step shrank (docs/solver.md, "The
// transfer's loss per step"); alpha keeps that much of it.
template <typename T>
FLUME_HD T flip_velocity(T v_grid_new, T v_particle, T v_grid_old, T alpha) {
  return v_grid_new + alpha * (v_particle - v_grid_old);
}

// alpha for a step of dt (host code of both backends): solver.flip is the share kept over the reference step
// kFlipReferenceCfl dx / c, and a step of dt keeps flip^(dt / dt_ref), so that the share of the transfer's
// loss kept over a second does not depend on the step. A share fixed per step damped a fixed part of the loss
// at every step, so the water under the sluice gate and past a pier still changed with the step
// (docs/solver.md, "A blend per second"). flip 0 (APIC) stays 0.
constexpr double kFlipReferenceCfl = 0.4;
inline double flip_for_step(double flip, double dt, double dx, double sound_speed) {
  if (!(flip > 0)) return 0;
  return std::pow(flip, dt * sound_speed / (kFlipReferenceCfl * dx));
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

// G2P's strain update, one particle, from what it gathered over the free (non-wall) nodes of its stencil:
// the weighted sums of strain Jg, fill Fg and weight wsum, and the APIC matrix Cn (scaled, dv_a/dx_b).
// Returns the new strain e by the well-balanced J-bar and the volume constraint; e_jbar is the strain before
// the constraint (mpm::constraint_work). The grid average leaves out nodes that a wall set: their strain is an
// average over particles on one side only, and the discrete equilibrium next to a wall is not the linear field
// the average preserves, so mixing them in would drive a slow creep that never settles. The remaining nodes
// are renormalised; a particle with no free node in reach keeps its own J (psi = 0). Branch-free (both
// quotients are formed and one kept), so that the CPU runs it across a batch of particles in SIMD lanes.
template <int D, typename T>
FLUME_HD T g2p_strain(const G2pConstants<D, T>& k, T Jg, T Fg, T wsum, T e, const T* x, const T* Cn, T& e_jbar) {
  const T psi = k.psi;  // read unconditionally: a load under the condition below would not vectorise
  const bool have_grid = wsum > T(1e-3);
  const T e_grid = (have_grid ? Jg / wsum : T(0)) + hydrostatic_strain<D>(x, k.slope);
  e_jbar = jbar_update(e, e_grid, volume_change<D>(Cn, k.dt), have_grid ? psi : T(0));
  const T corrected = fill_correction(e_jbar, Fg / wsum, k.fill_rate, k.fill_tol);
  return have_grid ? corrected : e_jbar;
}

// The elastic energy (J) the volume constraint supplied to a particle of reference volume vol when it moved
// the strain from e_jbar to e_new; what it removes is dissipation and is not returned. The energy audit counts
// it as supplied. In double, from the exact law: the difference of two nearby energies.
template <int D, typename T>
FLUME_HD double constraint_work(const G2pConstants<D, T>& k, T vol, T e_jbar, T e_new) {
  if (e_new == e_jbar) return 0.0;
  const double work =
      double(vol) * (k.law_d.energy_density(double(e_new)) - k.law_d.energy_density(double(e_jbar)));
  return work > 0.0 ? work : 0.0;
}

// G2P, one particle, from what it gathered: velocity vn, APIC matrix Cn and the free-node sums (g2p_strain).
// Updates the strain e, then moves x; a particle carried across a symmetry plane is replaced by its image.
// Returns the constraint's work (constraint_work). The CPU runs the same three steps batch by batch.
template <int D, typename T>
FLUME_HD double g2p_particle(const G2pConstants<D, T>& k, T Jg, T Fg, T wsum, T vol, T& e, T* x, T* vn,
                             T* Cn) {
  T e_jbar;
  const T e_new = g2p_strain<D>(k, Jg, Fg, wsum, e, x, Cn, e_jbar);
  const double work = constraint_work<D>(k, vol, e_jbar, e_new);
  e = e_new;
  for (int d = 0; d < D; ++d) x[d] += k.dt * vn[d];
  if (k.has_sym) symmetry_reflect_particle<D>(k.sym, x, vn, Cn);  // carried across: its image instead
  return work;
}

}  // namespace flume::mpm
