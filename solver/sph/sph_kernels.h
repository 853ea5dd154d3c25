// The weakly compressible SPH physics of one particle pair and one particle, as DualSPHysics runs it in the
// comparative study (Bonus et al., section 4.2): small inline functions for the host and a CUDA device alike,
// so the OpenMP loops of sph_solver.cpp and a future CUDA kernel share one definition. Notation: r_ab = x_a -
// x_b, v_ab = v_a - v_b; the kernel gradient is grad_a W_ab = F(r) r_ab with F < 0
// (wendland_gradient_factor).
#pragma once
#include <cmath>

#include "common/host_device.h"

namespace flume::sph {

// Symmetric D x D tensors stored as their D(D+1)/2 upper entries, row by row (2D: xx, xz, zz).
template <int D>
struct Sym {
  static constexpr int kSize = D * (D + 1) / 2;
  FLUME_HD static constexpr int at(int i, int j) {
    return i <= j ? i * D - i * (i - 1) / 2 + (j - i) : j * D - j * (j - 1) / 2 + (i - j);
  }
};

// Everything a pair interaction reads, in the solver's precision. The pair functions take each particle's
// 1/rho as well as rho (computed once per particle and evaluation: a division per pair less).
template <typename T>
struct Params {
  T h = 0, inv_h = 0;
  T support2 = 0;   // (2h)^2
  T eta2 = 0;       // 0.01 h^2, keeps 1/r^2 finite
  T grad_coef = 0;  // -5 alpha_D / h^2: F(q) = grad_coef (1 - q/2)^3
  T w_alpha = 0;    // alpha_D of the kernel's value (wendland_w)
  T rho0 = 0, B = 0, gamma = 0, c0 = 0;
  T nu = 0;     // laminar kinematic viscosity (m^2/s)
  T alpha = 0;  // artificial viscosity coefficient; 0: laminar + SPS instead
  T ddt = 0;    // delta h c0 of the density diffusion term (Fourtakas et al. 2020)
  T g[3] = {0, 0, 0};
  T sps_cs2 = 0;  // (C_s Delta)^2, Smagorinsky (study eq. 12; C_s = 0.12)
  T sps_ci = 0;   // 2/3 C_I Delta^2 (study eq. 11; C_I = 0.0066)
  // Particle shifting (shift_displacement): A h, the free-surface threshold on div r, the dimension D, and
  // the largest displacement per step.
  T shift_ah = 0, shift_tfs = 0, shift_dim = 0, shift_max = 0;
};

// Wendland C2 (quintic) kernel, study eq. 6: W = alpha_D (1 - q/2)^4 (2q + 1), 0 <= q <= 2, with
// alpha_D = 7 / (4 pi h^2) in 2D and 21 / (16 pi h^3) in 3D (Wendland 1995).
template <int D>
inline double wendland_alpha(double h) {
  constexpr double kPi = 3.14159265358979323846;
  return D == 2 ? 7.0 / (4.0 * kPi * h * h) : 21.0 / (16.0 * kPi * h * h * h);
}
template <typename T>
FLUME_HD T wendland_w(T q, T alpha) {
  const T u = T(1) - T(0.5) * q;
  return q < T(2) ? alpha * u * u * u * u * (T(2) * q + T(1)) : T(0);
}
// dW/dr / r = -5 alpha_D q (1 - q/2)^3 / (h r) = -5 alpha_D (1 - q/2)^3 / h^2, for r^2 < (2h)^2.
template <typename T>
FLUME_HD T wendland_gradient_factor(T r2, const Params<T>& P) {
  const T u = T(1) - T(0.5) * std::sqrt(r2) * P.inv_h;
  return P.grad_coef * u * u * u;
}

// Tait equation of state, study eq. 13: p = B ((rho / rho0)^gamma - 1), B = c0^2 rho0 / gamma; with
// c0 = sqrt(K / rho0) it is MPM's Tait law p = K / gamma (J^-gamma - 1) for rho / rho0 = 1 / J.
template <typename T>
FLUME_HD T tait_pressure(T rho, const Params<T>& P) {
  return P.B * (std::pow(rho / P.rho0, P.gamma) - T(1));
}
// The elastic energy per unit mass stored by the Tait law, int_rho0^rho p / rho^2 drho (for the energy
// audit).
inline double tait_energy_per_mass(double rho, double rho0, double B, double gamma) {
  const double r = rho / rho0;
  return B / rho0 * ((std::pow(r, gamma - 1) - 1) / (gamma - 1) + 1 / r - 1);
}

// What one particle collects from its neighbours in one force evaluation.
template <int D, typename T>
struct Accum {
  T acc[D] = {};
  T drho = 0;
  T gradv[D * D] = {};  // velocity gradient dv_i/dx_j, for the sub-particle stress
  T visc_dt = 0;        // max_b |v_ab . r_ab| / (r^2 + eta^2), DualSPHysics' viscous step limit
  T gradc[D] = {};      // grad C = sum_b V_b grad_a W_ab, the gradient of the particle concentration
  T divr = 0;           // div r = -sum_b V_b r_ab . grad_a W_ab: D inside the fluid, about D/2 at its surface
  int pairs = 0;
};
// Adds the sums S to T (visc_dt: their maximum).
template <int D, typename T>
FLUME_HD void add_sums(const Accum<D, T>& S, Accum<D, T>& to) {
  for (int d = 0; d < D; ++d) to.acc[d] += S.acc[d];
  to.drho += S.drho;
  for (int k = 0; k < D * D; ++k) to.gradv[k] += S.gradv[k];
  to.visc_dt = S.visc_dt > to.visc_dt ? S.visc_dt : to.visc_dt;
  for (int d = 0; d < D; ++d) to.gradc[d] += S.gradc[d];
  to.divr += S.divr;
  to.pairs += S.pairs;
}

// The terms every pair shares: continuity (study eq. 7, rho_a sum_b m_b / rho_b v_ab . grad W), the symmetric
// pressure gradient (eq. 9: -sum_b m_b (p_a + p_b) / (rho_a rho_b) grad W) and the viscosity: laminar (Lo &
// Shao 2002, eq. 9's second term) or Monaghan's artificial viscosity when alpha > 0. v_ab uses a wall
// particle's prescribed velocity.
// Every pair function takes b's sums too (`B`, with a's mass m_a), for a fluid pair evaluated once for both
// particles: b's terms are a's with a and b exchanged, r_ba = -r_ab and v_ba = -v_ab with the same F, so the
// dot product, the kernel and the symmetric factors are computed once. Without B only a's side is summed.
template <int D, typename T>
FLUME_HD void pair_common(const Params<T>& P, const T* rab, T r2, T F, const T* vab, T rho_a, T inv_rho_a,
                          T p_a, T rho_b, T inv_rho_b, T p_b, T m_b, Accum<D, T>& A, T m_a = T(0),
                          Accum<D, T>* B = nullptr) {
  T dot = 0;
  for (int d = 0; d < D; ++d) dot += vab[d] * rab[d];
  A.drho += m_b * F * dot * (rho_a * inv_rho_b);
  const T inv_r2 = T(1) / (r2 + P.eta2);
  const T vdt = std::fabs(dot) * inv_r2;
  A.visc_dt = vdt > A.visc_dt ? vdt : A.visc_dt;
  // The acceleration's factors on r_ab (pressure, artificial viscosity) and on v_ab (laminar), per unit of
  // the other particle's mass.
  // Both viscosities are formed and one kept, so the function has no branch (a vector loop needs none).
  // Artificial: approaching pairs only (Monaghan 1992), Pi_ab = -alpha c0 mu / rho_mean.
  const T mu = P.h * dot * inv_r2;
  const T artificial = dot < T(0) ? F * P.alpha * P.c0 * mu / (T(0.5) * (rho_a + rho_b)) : T(0);
  const T laminar = F * T(4) * P.nu * r2 * inv_r2 / (rho_a + rho_b);
  const bool use_artificial = P.alpha > T(0);
  const T press = -F * (p_a + p_b) * (inv_rho_a * inv_rho_b) + (use_artificial ? artificial : T(0));
  const T lam = use_artificial ? T(0) : laminar;
  for (int d = 0; d < D; ++d) A.acc[d] += m_b * (press * rab[d] + lam * vab[d]);
  ++A.pairs;
  if (!B) return;
  B->drho += m_a * F * dot * (rho_b * inv_rho_a);
  B->visc_dt = vdt > B->visc_dt ? vdt : B->visc_dt;
  for (int d = 0; d < D; ++d) B->acc[d] -= m_a * (press * rab[d] + lam * vab[d]);
  ++B->pairs;
}

// d rho / d p at a particle, rho / c^2 with the Tait law's local sound speed c^2 = gamma (p + B) / rho: the
// hydrostatic density difference across r_ab is this times g . r_ab.
template <typename T>
FLUME_HD T hydrostatic_density_slope(T rho, T p, const Params<T>& P) {
  return rho * rho / (P.gamma * (p + P.B));
}

// Fluid-fluid extras: density diffusion (Fourtakas et al. 2020, delta-SPH on the dynamic density: the
// hydrostatic part k_a g . r_ab, k_a = hydrostatic_density_slope, is taken out so a still column does not
// diffuse; the paper's rho0 / c0^2 is k_a at rho0, and the local k_a keeps the term zero in a hydrostatic column
// at any compression, where the Tait law's c^2 grows by gamma - 1 times the density's), the sub-particle stress
// (eq. 9's third term, tau / rho^2 held per particle, Dalrymple & Rogers 2006) and the velocity gradient it is
// computed from next.
template <int D, typename T>
FLUME_HD void pair_density_diffusion(const Params<T>& P, const T* rab, T r2, T F, T rho_a, T k_a, T rho_b,
                                     T inv_rho_b, T m_b, Accum<D, T>& A, T k_b = T(0), T m_a = T(0),
                                     T inv_rho_a = T(0), Accum<D, T>* B = nullptr) {
  T g_dot_r = 0;
  for (int d = 0; d < D; ++d) g_dot_r += P.g[d] * rab[d];
  const T V_b = m_b * inv_rho_b, V_a = m_a * inv_rho_a;
  const T diffusion = P.ddt * T(2) * F * r2 / (r2 + P.eta2);
  A.drho += diffusion * ((rho_a - rho_b) - k_a * g_dot_r) * V_b;
  if (B) B->drho += diffusion * ((rho_b - rho_a) + k_b * g_dot_r) * V_a;
}
template <int D, typename T>
FLUME_HD void pair_sps(const T* rab, T F, const T* vab, T inv_rho_b, T m_b, const T* tau_a, const T* tau_b,
                       Accum<D, T>& A, T m_a = T(0), T inv_rho_a = T(0), Accum<D, T>* B = nullptr) {
  const T V_b = m_b * inv_rho_b, V_a = m_a * inv_rho_a;
  for (int i = 0; i < D; ++i) {
    T s = 0;
    for (int j = 0; j < D; ++j) {
      const int k = Sym<D>::at(i, j);
      s += (tau_a[k] + tau_b[k]) * rab[j];
      // grad v = sum_b V_b (v_b - v_a) (x) grad_a W; for b, V_a (v_a - v_b) (x) grad_b W: the same sign.
      const T gv = vab[i] * F * rab[j];
      A.gradv[i * D + j] -= V_b * gv;
      if (B) B->gradv[i * D + j] -= V_a * gv;
    }
    A.acc[i] += m_b * F * s;
    if (B) B->acc[i] -= m_a * F * s;
  }
}
// Both, the sub-particle stress only with laminar viscosity (P.alpha = 0).
template <int D, typename T>
FLUME_HD void pair_fluid_extras(const Params<T>& P, const T* rab, T r2, T F, const T* vab, T rho_a, T k_a,
                                T rho_b, T inv_rho_b, T m_b, const T* tau_a, const T* tau_b, Accum<D, T>& A,
                                T k_b = T(0), T m_a = T(0), T inv_rho_a = T(0), Accum<D, T>* B = nullptr) {
  pair_density_diffusion<D, T>(P, rab, r2, F, rho_a, k_a, rho_b, inv_rho_b, m_b, A, k_b, m_a, inv_rho_a, B);
  if (P.alpha > T(0)) return;
  pair_sps<D, T>(rab, F, vab, inv_rho_b, m_b, tau_a, tau_b, A, m_a, inv_rho_a, B);
}

// The sub-particle stress over rho^2 from the velocity gradient (study eqs. 11-12, DualSPHysics' SpsTau):
// tau / rho = nu_t (2 S - 2/3 tr S I) - 2/3 C_I Delta^2 |S|^2 I, nu_t = (C_s Delta)^2 |S|, |S| = sqrt(2 S:S).
template <int D, typename T>
FLUME_HD void sps_stress(const Params<T>& P, const T* gradv, T rho, T* tau) {
  T S[D * D], ss = 0, tr = 0;
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) {
      S[i * D + j] = T(0.5) * (gradv[i * D + j] + gradv[j * D + i]);
      ss += S[i * D + j] * S[i * D + j];
    }
  for (int i = 0; i < D; ++i) tr += S[i * D + i];
  const T s2 = T(2) * ss, mag = std::sqrt(s2);
  const T nut = P.sps_cs2 * mag;
  const T inv_rho = T(1) / rho;
  for (int i = 0; i < D; ++i)
    for (int j = i; j < D; ++j) {
      T t = nut * T(2) * S[i * D + j];
      if (i == j) t -= nut * T(2) / T(3) * tr + P.sps_ci * s2;
      tau[Sym<D>::at(i, j)] = t * inv_rho;
    }
}

// Particle shifting (Lind et al. 2012) as DualSPHysics 5 runs it and the study writes it (eq. 22): particles
// move down the gradient of their concentration, dr = -A h |u| dt grad C, which evens out the clumps and voids
// of tensile instability. Fluid and wall particles both count in C (DualSPHysics' shifting mode "full"), so
// the walls' side of a fluid particle is as full as its inside. At the free surface grad C points into the
// water, and shifting would push particles out of it; so, after DualSPHysics' ShiftTFS, a particle whose
// div r is below the threshold (the surface layer) is not shifted, and one between it and D is shifted by
// the fraction (div r - tfs) / (D - tfs). Pair sums:
template <int D, typename T>
FLUME_HD void pair_shift(const T* rab, T r2, T F, T V_b, Accum<D, T>& A, T V_a = T(0),
                         Accum<D, T>* B = nullptr) {
  const T vf = V_b * F;
  for (int d = 0; d < D; ++d) A.gradc[d] += vf * rab[d];
  A.divr -= vf * r2;
  if (!B) return;
  const T uf = V_a * F;  // grad_b W_ba = -F r_ab
  for (int d = 0; d < D; ++d) B->gradc[d] -= uf * rab[d];
  B->divr -= uf * r2;
}
// The displacement over a step dt for a particle moving at `speed`, at most P.shift_max long (DualSPHysics
// bounds each component by a tenth of the particle spacing; here the vector's length, so the direction is
// kept).
template <int D, typename T>
FLUME_HD void shift_displacement(const Params<T>& P, const T* gradc, T divr, T speed, T dt, T* dr) {
  T f = divr < P.shift_tfs ? T(0) : (divr - P.shift_tfs) / (P.shift_dim - P.shift_tfs);
  f *= -P.shift_ah * speed * dt;
  T len2 = 0;
  for (int d = 0; d < D; ++d) {
    dr[d] = f * gradc[d];
    len2 += dr[d] * dr[d];
  }
  if (len2 > P.shift_max * P.shift_max) {
    const T s = P.shift_max / std::sqrt(len2);
    for (int d = 0; d < D; ++d) dr[d] *= s;
  }
}

// mDBC (ghost_nodes.h): the water's density at a wall particle's ghost node g by a first-order corrected SPH
// interpolation (Liu & Liu 2006, as English et al. 2022 use it). With r = g - x_b and rho_b = rho_g - grad
// rho . r to first order, the sums of m_b W and m_b grad W over the water are the moment matrix
//   A = [[sum V W, sum V W r^T], [sum V grad W, sum V grad W r^T]]   (V = m_b / rho_b)
// times u = (rho_g, -grad rho).
// For the slip modes (ghost_slip_velocity) the sums also hold sum V W v, the water's velocity there times
// A[0].
template <int D, typename T>
struct GhostSums {
  static constexpr int kN = D + 1;
  T rhs[kN] = {};     // sum m_b W, sum m_b grad W
  T A[kN * kN] = {};  // row-major
  T vel[D] = {};      // sum V W v (with v_b given)
};
template <int D, typename T>
FLUME_HD void pair_ghost(const Params<T>& P, const T* r, T r2, T F, T m_b, T V_b, GhostSums<D, T>& S,
                         const T* v_b = nullptr) {
  constexpr int N = D + 1;
  const T W = wendland_w(std::sqrt(r2) * P.inv_h, P.w_alpha);
  if (v_b)
    for (int d = 0; d < D; ++d) S.vel[d] += V_b * W * v_b[d];
  T row[N];  // (W, grad W) of this pair
  row[0] = W;
  for (int d = 0; d < D; ++d) row[1 + d] = F * r[d];
  for (int i = 0; i < N; ++i) {
    S.rhs[i] += m_b * row[i];
    const T vr = V_b * row[i];
    S.A[i * N] += vr;
    for (int j = 0; j < D; ++j) S.A[i * N + 1 + j] += vr * r[j];
  }
}
// Sums gathered at the ghost's mirror image across a symmetry plane (sph/mirror.h), in the reflected frame,
// added to those at the ghost: the entries with exactly one index on the axis change sign.
template <int D, typename T>
FLUME_HD void add_reflected_ghost(int axis, const GhostSums<D, T>& m, GhostSums<D, T>& S) {
  constexpr int N = D + 1;
  auto flips = [&](int i) { return i == 1 + axis; };
  for (int i = 0; i < N; ++i) {
    S.rhs[i] += flips(i) ? -m.rhs[i] : m.rhs[i];
    for (int j = 0; j < N; ++j) S.A[i * N + j] += flips(i) != flips(j) ? -m.A[i * N + j] : m.A[i * N + j];
  }
  for (int d = 0; d < D; ++d) S.vel[d] += d == axis ? -m.vel[d] : m.vel[d];
}
// The wall particle's density, rho_g + grad rho . (x_k - g) for ghost vector gv = g - x_k, floored at rho0 as
// for DBC (a wall does not pull on the water: near its free surface the water's pressure extrapolates below
// zero). Returns 0 where the water round the ghost does not support the interpolation: a moment matrix near
// singular (|det| < 1e-3, DualSPHysics' limit) or a kernel sum sum V W under one half, the value at a flat
// free surface (the ghost outside the water: a splash or a thin sheet). There the caller keeps DBC's density
// by continuity, which grows as water closes in on the wall; the Shepard average of a few particles would
// not, and lets them through.
template <int D, typename T>
FLUME_HD T ghost_density(const GhostSums<D, T>& S, const T* gv, T rho0) {
  constexpr int N = D + 1;
  T a[N * N], b[N], det = 1;
  for (int i = 0; i < N * N; ++i) a[i] = S.A[i];
  for (int i = 0; i < N; ++i) b[i] = S.rhs[i];
  // Gaussian elimination with partial pivoting; det is the pivots' product.
  for (int c = 0; c < N; ++c) {
    int piv = c;
    for (int i = c + 1; i < N; ++i)
      if (std::fabs(a[i * N + c]) > std::fabs(a[piv * N + c])) piv = i;
    if (piv != c) {
      for (int j = 0; j < N; ++j) {
        const T t = a[c * N + j];
        a[c * N + j] = a[piv * N + j];
        a[piv * N + j] = t;
      }
      const T t = b[c];
      b[c] = b[piv];
      b[piv] = t;
      det = -det;
    }
    det *= a[c * N + c];
    if (a[c * N + c] == T(0)) break;
    for (int i = c + 1; i < N; ++i) {
      const T f = a[i * N + c] / a[c * N + c];
      for (int j = c; j < N; ++j) a[i * N + j] -= f * a[c * N + j];
      b[i] -= f * b[c];
    }
  }
  if (!(std::fabs(det) >= T(1e-3) && S.A[0] >= T(0.5))) return T(0);
  T u[N];
  for (int i = N - 1; i >= 0; --i) {
    T s = b[i];
    for (int j = i + 1; j < N; ++j) s -= a[i * N + j] * u[j];
    u[i] = s / a[i * N + i];
  }
  T rho = u[0];
  for (int d = 0; d < D; ++d) rho += u[1 + d] * gv[d];  // -grad rho . (x_k - g) = u[1:] . gv
  return rho > rho0 ? rho : rho0;
}

// mDBC's slip modes (DualSPHysics' SlipMode): the velocity a wall particle (its wall moving at vw) shows the
// water, from the water's at its ghost node, vg = sum V W v / sum V W (Shepard), and the unit normal n from
// the particle towards the ghost. No slip: 2 vw - vg, so the velocity interpolated across the face is the
// wall's. Free slip: vg's tangential part kept and its normal part mirrored about the wall's, vg_t + 2 vw_n -
// vg_n, so the face takes no shear and lets no water through. (DualSPHysics' free slip drops the tangential
// part on a moving wall; here the wall's tangential motion does not drag the water either way.)
enum class Slip { kWall, kNoSlip, kFreeSlip };
template <int D, typename T>
FLUME_HD void ghost_slip_velocity(Slip mode, const GhostSums<D, T>& S, const T* gv, const T* vw, T* out) {
  T vg[D];
  for (int d = 0; d < D; ++d) vg[d] = S.vel[d] / S.A[0];
  if (mode == Slip::kNoSlip) {
    for (int d = 0; d < D; ++d) out[d] = T(2) * vw[d] - vg[d];
    return;
  }
  T len2 = 0, gn = 0, wn = 0;
  for (int d = 0; d < D; ++d) len2 += gv[d] * gv[d];
  const T inv = T(1) / std::sqrt(len2);
  for (int d = 0; d < D; ++d) {
    gn += vg[d] * gv[d] * inv;
    wn += vw[d] * gv[d] * inv;
  }
  for (int d = 0; d < D; ++d) out[d] = vg[d] + (T(2) * wn - T(2) * gn) * gv[d] * inv;
}

// Symplectic position-Verlet stages (DualSPHysics' Symplectic, Monaghan 2005). Predictor to t + dt/2:
template <typename T>
FLUME_HD void predict(T x, T v, T a, T dt, T& xh, T& vh) {
  xh = x + T(0.5) * dt * v;
  vh = v + T(0.5) * dt * a;
}
// Corrector from t to t + dt with the mid-step acceleration: v1 = v0 + dt a, x1 = x0 + dt (v0 + v1) / 2.
template <typename T>
FLUME_HD void correct(T& x, T& v, T a, T dt) {
  const T v1 = v + dt * a;
  x += T(0.5) * dt * (v + v1);
  v = v1;
}
// Density: rho1 = rho0 (2 - eps) / (2 + eps), eps = -drho_half / rho_half dt (exact for a constant rate of
// the logarithm of the density, as DualSPHysics integrates it).
template <typename T>
FLUME_HD T correct_density(T rho, T rho_half, T drho_half, T dt) {
  const T eps = -drho_half / rho_half * dt;
  return rho * (T(2) - eps) / (T(2) + eps);
}

}  // namespace flume::sph
