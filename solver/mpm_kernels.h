// The MPM physics, written once as small inline functions that both backends call: the OpenMP loops in
// solver/mpm/cpu_*.cpp and the CUDA kernels in cuda/. Nothing here allocates, branches on the backend or knows
// about the grid's storage. Quadratic B-splines and MLS-MPM transfers follow Hu et al. (2018), "A moving
// least squares material point method", eqs. 16-29; the fluid is the weakly compressible Tait/Murnaghan
// water of the comparative study (Bonus et al., section 4.1) with a Newtonian viscous stress.
#pragma once
#include <cmath>

#include "common/host_device.h"

namespace flume::mpm {

// Tile geometry: grid blocks are kBlock^D nodes. A block of particles scatters into a tile covering
// nodes [kBlock*B - 1, kBlock*B - 1 + kTile) on each axis: the quadratic stencil of a particle whose base
// node has drifted at most one cell from its block since the last sort.
constexpr int kBlock = 4;
constexpr int kTile = kBlock + 4;

template <int D>
struct Pow {
  static constexpr int of(int n) { return n * Pow<D - 1>::of(n); }
};
template <>
struct Pow<0> {
  static constexpr int of(int) { return 1; }
};

// Quadratic B-spline weights of the three nodes base, base+1, base+2 for a particle at fractional
// position f = x/dx - base, f in [0.5, 1.5) (Hu et al. 2018, eq. 6 of the supplementary).
template <typename T>
FLUME_HD void bspline_weights(T f, T w[3]) {
  const T a = T(1.5) - f, b = f - T(1), c = f - T(0.5);
  w[0] = T(0.5) * a * a;
  w[1] = T(0.75) - b * b;
  w[2] = T(0.5) * c * c;
}

// Base node of a particle's stencil and its fractional offset, from the position in grid units.
template <typename T>
FLUME_HD int stencil_base(T x_grid, T& f) {
  const int base = static_cast<int>(std::floor(x_grid - T(0.5)));
  f = x_grid - T(base);
  return base;
}

// A grid node's coordinate, lo + i dx, rounded as a product and then a sum on every backend and build. The
// boxes' geometry (wall_faces, ghost_box) compares it exactly with faces that often lie on grid lines; a fused
// multiply-add, nvcc's default, moved nodes across such ties and held or mirrored them unlike the CPU
// (docs/benchmarks.md).
FLUME_HD double node_coordinate(double lo, int i, double dx) {
#if defined(__CUDA_ARCH__)
  return __dadd_rn(lo, __dmul_rn(double(i), dx));
#else
  const volatile double product = double(i) * dx;  // volatile: no contraction with the sum (-march=native GCC)
  return lo + product;
#endif
}

// Volumes are carried as the volumetric strain e = J - 1, not as J: water under a 0.2 m head has
// e ~ -1e-4 at K = 2e7 Pa, which 1 + e stored in float would resolve to only three digits, and a step's
// change (~1e-8) would be lost entirely. Every function below takes e and stays accurate as e -> 0.

// The exponent gamma is an integer for water in practice (7, Monaghan's value and the scenes' default) or a
// short binary fraction (7.125 = 57/8, the value ClaymoreUW's Waseda twin uses and the Waseda scenes copy),
// and then J^gamma needs no transcendental function. With gamma = m / 2^k (k <= 3): x = J^(1/2^k) - 1 by k
// halvings x <- x / (1 + sqrt(1 + x)), then (1 + x)^m by binary powering, carrying P_a = (1 + x)^a - 1 and
// R_a = P_a - a x with P_{a+b} = P_a + P_b + P_a P_b and R_{a+b} = R_a + R_b + P_a P_b: no step forms a
// quantity of size 1 next to a small one, so P = J^gamma - 1 and R = J^gamma - 1 - gamma e keep the relative
// precision of e (and it is cheap: docs/solver.md, "Measurements behind the constants"). R needs x - e/2^k,
// which each halving gives exactly as well: x_j - x_{j-1}/2 = -x_j^2/2. Other exponents (not m / 2^k with k
// <= 3, or m above the limit) use expm1/log1p.
constexpr int kTaitMaxHalvings = 3;
constexpr int kTaitMaxNumerator = 255;
// m with gamma = m / 2^halvings exactly (the smallest such halvings), or 0 when gamma takes the libm path.
template <typename T>
FLUME_HD int tait_dyadic_gamma(T gamma, int& halvings) {
  for (int k = 0; k <= kTaitMaxHalvings; ++k) {
    const T scaled = gamma * T(1 << k);  // exact: a power of two
    const int m = static_cast<int>(scaled);
    if (T(m) == scaled && m >= 1 && m <= kTaitMaxNumerator) {
      halvings = k;
      return m;
    }
  }
  halvings = 0;
  return 0;
}
// P = J^gamma - 1, R = J^gamma - 1 - gamma e, Q = J^gamma (the relatively exact denominator that 1 + P would not
// be when the water is compressed far, e -> -1, P -> -1). False, and nothing set, on the libm path.
// m and k are tait_dyadic_gamma's, found once per law (TaitLaw), not per particle.
template <typename T>
FLUME_HD bool tait_powers(T e, int m, int k, T& P, T& R, T& Q) {
  if (m == 0) return false;
  // x_j = e / prod_{i <= j} (1 + J^(1/2^i)): the roots of the rounded J are good to an epsilon next to 1, so the
  // product is relatively exact and one division serves all k halvings.
  T x = e, c = T(0);  // c = x - e / 2^k
  if (k > 0) {
    T root[kTaitMaxHalvings], D = T(1), r = T(1) + e;
    for (int j = 0; j < k; ++j) {
      r = std::sqrt(r);
      root[j] = T(1) + r;
      D *= root[j];
    }
    x = e / D;
    T xj = x;  // x_k, x_{k-1}, ... by x_{j-1} = x_j (1 + J^(1/2^j)); c = -sum_j x_j^2 / 2^(k-j+1)
    T w = T(0.5);
    for (int j = k - 1; j >= 0; --j) {
      c -= w * xj * xj;
      xj *= root[j];
      w *= T(0.5);
    }
  }
  T Pa = x, Ra = T(0), Qa = T(1) + x;  // (1 + x)^a for a = 1, 2, 4, ...
  T Pm = T(0), Rm = T(0), Qm = T(1);   // the product of the powers taken so far: a = 0 to start
  for (int rest = m;;) {
    if (rest & 1) {
      const T PP = Pm * Pa;
      Pm += Pa + PP;
      Rm += Ra + PP;
      Qm *= Qa;
    }
    rest >>= 1;
    if (rest == 0) break;
    const T PP = Pa * Pa;
    Pa = T(2) * Pa + PP;
    Ra = T(2) * Ra + PP;
    Qa *= Qa;
  }
  P = Pm;
  R = Rm + T(m) * c;  // P - m x + m (x - e / 2^k)
  Q = Qm;
  return true;
}

// The Tait/Murnaghan law of one fluid, set up once per solver: the particle loops evaluate it per particle and
// per step. Water stays within |e| ~ 1e-2 of rest (a 0.5 m head is e = -2.6e-3 at K = 2e6 Pa), where both the
// pressure and the stored energy are their Taylor series in e to round-off with a handful of terms: a
// polynomial that vectorises, with no division. Beyond `cut` (set so that the first term left out is below a
// quarter of an epsilon of the leading one) the exact forms below take over: gamma = m / 2^k by halvings and
// binary powering (m and k found here, once), else expm1/log1p.
template <typename T>
struct TaitLaw {
  static constexpr int kTerms = sizeof(T) >= 8 ? 10 : 5;
  T K = 0, gamma = 0;
  int m = 0, k = 0;  // gamma = m / 2^k; m = 0: the libm path
  // p = K e sum_{i < kTerms} cp[i] e^i and W = K e^2 sum_{i < kTerms} cw[i] e^i, for |e| <= cut.
  T cp[kTerms] = {}, cw[kTerms] = {}, cut = 0;
  TaitLaw() = default;
  FLUME_HD TaitLaw(T bulk_modulus, T exponent) : K(bulk_modulus), gamma(exponent) {
    m = tait_dyadic_gamma(gamma, k);
    // (1 + e)^-gamma - 1 = sum_k binom(-gamma, k) e^k, so p/K has c_1 = -1, c_{k+1} = -c_k (gamma + k)/(k + 1);
    // W/K = sum_{k >= 2} binom(1 - gamma, k) e^k / (gamma (gamma - 1)): d_2 = 1/2, d_{k+1} = -d_k (gamma + k - 1)/(k + 1).
    const double g = double(gamma);
    double c = -1, d = 0.5;
    for (int i = 0; i < kTerms; ++i) {
      cp[i] = T(c);
      cw[i] = T(d);
      c = -c * (g + i + 1) / (i + 2);
      d = -d * (g + i + 1) / (i + 3);
    }
    // c and d are now the first terms left out, of e^kTerms relative to the leading ones.
    const double eps = sizeof(T) >= 8 ? 2.220446049250313e-16 : 1.1920929e-07;
    const double worst = std::fmax(std::fabs(c), std::fabs(d) / 0.5);
    cut = T(std::pow(0.25 * eps / worst, 1.0 / kTerms));
  }

  FLUME_HD bool in_series(T e) const { return std::fabs(e) <= cut; }
  FLUME_HD T pressure_series(T e) const {
    T s = cp[kTerms - 1];
    for (int i = kTerms - 2; i >= 0; --i) s = s * e + cp[i];
    return K * e * s;
  }
  FLUME_HD T energy_series(T e) const {
    T s = cw[kTerms - 1];
    for (int i = kTerms - 2; i >= 0; --i) s = s * e + cw[i];
    return K * e * e * s;
  }

  // p = K/gamma (J^-gamma - 1) = -K/gamma P/Q; on the libm path K/gamma expm1(-gamma log1p(e)).
  FLUME_HD T pressure_exact(T e) const {
    T P, R, Q;
    if (tait_powers(e, m, k, P, R, Q)) return -K / gamma * P / Q;
    return K / gamma * std::expm1(-gamma * std::log1p(e));
  }
  FLUME_HD T pressure(T e) const { return in_series(e) ? pressure_series(e) : pressure_exact(e); }

  // Stored energy per unit reference volume whose derivative with respect to J is -p:
  // W = K/gamma [(J^(1-gamma) - 1)/(gamma - 1) + J - 1]; gamma = 1 is the limit K (J - 1 - ln J). With
  // J^(1-gamma) - 1 = (e - P)/J^gamma the bracket is ((gamma - 1) e P - R) / ((gamma - 1) J^gamma), whose leading
  // terms gamma (gamma - 1) e^2 and gamma (gamma - 1) e^2 / 2 cancel only by half. Used by the energy audit that
  // flags an unstable run.
  FLUME_HD T energy_exact(T e) const {
    if (std::fabs(gamma - T(1)) < T(1e-6)) return K * (e - std::log1p(e));
    T P, R, Q;
    if (tait_powers(e, m, k, P, R, Q)) return K / (gamma * (gamma - T(1))) * ((gamma - T(1)) * e * P - R) / Q;
    return K / gamma * (std::expm1((T(1) - gamma) * std::log1p(e)) / (gamma - T(1)) + e);
  }
  FLUME_HD T energy_density(T e) const { return in_series(e) ? energy_series(e) : energy_exact(e); }
};

// One-off forms (tests, diagnostics): the law built for a single call.
template <typename T>
FLUME_HD T tait_pressure(T e, T bulk_modulus, T gamma) {
  return TaitLaw<T>(bulk_modulus, gamma).pressure(e);
}
template <typename T>
FLUME_HD T tait_energy_density(T e, T bulk_modulus, T gamma) {
  return TaitLaw<T>(bulk_modulus, gamma).energy_density(e);
}

// Wave speed of the linearised fluid, c = sqrt(K / rho), which sets the explicit step.
template <typename T>
FLUME_HD T sound_speed(T bulk_modulus, T density) {
  return std::sqrt(bulk_modulus / density);
}

// Cauchy stress of the fluid: -p I + 2 mu dev(sym(grad v)), with grad v taken from the APIC matrix C
// (for quadratic MLS-MPM, C is the velocity gradient estimate); e = J - 1. Row-major D x D.
template <int D, typename T>
FLUME_HD void viscous_stress_with_pressure(T p, const T* C, T viscosity, T* sigma) {
  T trace = 0;
  for (int a = 0; a < D; ++a) trace += C[a * D + a];
  for (int a = 0; a < D; ++a)
    for (int b = 0; b < D; ++b) {
      const T sym = T(0.5) * (C[a * D + b] + C[b * D + a]);
      sigma[a * D + b] = T(2) * viscosity * (sym - (a == b ? trace / T(D) : T(0))) - (a == b ? p : T(0));
    }
}

// det(I + dt C) - 1, the particle's volumetric strain over one step, summed from the invariants of dt C so
// that nothing of size 1 is added and subtracted: 2D dt tr C + dt^2 det C; 3D dt tr C + dt^2 (sum of the
// principal 2x2 minors) + dt^3 det C.
template <int D, typename T>
FLUME_HD T volume_change(const T* C, T dt) {
  if constexpr (D == 2) {
    return dt * (C[0] + C[3]) + dt * dt * (C[0] * C[3] - C[1] * C[2]);
  } else {
    const T tr = C[0] + C[4] + C[8];
    const T minors = C[0] * C[4] - C[1] * C[3] + C[0] * C[8] - C[2] * C[6] + C[4] * C[8] - C[5] * C[7];
    const T det = C[0] * (C[4] * C[8] - C[5] * C[7]) - C[1] * (C[3] * C[8] - C[5] * C[6]) +
                  C[2] * (C[3] * C[7] - C[4] * C[6]);
    return dt * (tr + dt * (minors + dt * det));
  }
}

// J-bar antilocking with the linear mixing ratio psi (Bonus et al., eqs. 3-4): the new J blends the
// grid-averaged J (Zhao et al. 2023's projection, taken from the previous step's particle J and carried
// forward by this step's volume change) with the particle's own J. psi = 0 is plain MLS-MPM. In strains:
// J_new - 1 = (1 + a)(1 + de) - 1 = a + de + a de, with a = psi e_grid + (1 - psi) e_particle.
template <typename T>
FLUME_HD T jbar_update(T e_particle, T e_grid_average, T de, T psi) {
  const T a = psi * e_grid_average + (T(1) - psi) * e_particle;
  return a + de + a * de;
}

// Unilateral volume constraint. J (integrated from the grid's velocity divergence, and smoothed by J-bar)
// does not see particles that crowd together without the grid registering it (in a still 3D tank the level
// fell by a third: docs/solver.md, "Measurements behind the constants"). The particles' own volumes say it:
// scattered to the grid, V_p = V0 J_p per cell volume is the node's fill, 1 where particles tile space as
// their J says, below 1 at a free surface or a wall. Where the fill (averaged back to the particle over free
// nodes) exceeds 1 + tol, the particle's J is lowered in proportion, at `rate` per step: the pressure rises
// and spreads the crowd. Over-fill only, as the density constraint of position-based fluids is one-sided, so
// free surfaces and splashes are untouched; `tol` keeps the sampling noise of an irregular particle set out
// of it (0.03, the smallest that keeps a still tank still: docs/solver.md; test_hydrostatic StillTank), at
// the price of letting the water crowd up to 3% before the constraint acts. The rate relaxes the excess over
// ten acoustic crossings of a cell (rate = 0.1 c dt / dx per step, 0.04 at CFL 0.4): fast against the drift
// (seconds), slow against the step, so it adds no acoustic noise.
constexpr double kFillTolerance = 0.03;
inline double fill_rate(double dt, double sound_speed, double dx) {
  const double r = 0.1 * sound_speed * dt / dx;
  return r < 1.0 ? r : 1.0;
}
template <typename T>
FLUME_HD T fill_correction(T e, T fill, T rate, T tol) {
  const T excess = fill - (T(1) + tol);
  return excess > T(0) ? e - rate * excess * (T(1) + e) : e;
}

// Well-balanced J-bar. The grid average of eq. 3 is exact for a constant strain but not for the linear one of
// water at rest: next to a floor or a free surface the stencil sees particles on one side only, the average
// is taken off-centre, and every step would pull the strain there away from hydrostatic balance (a column
// at psi = 0.9 never settles: docs/solver.md). So the averaged quantity is the
// strain minus its hydrostatic part e_h(x) = s . x, s = -rho g / K, and e_h is added back at the particle:
// at rest the averaged field is constant and the average leaves it untouched. This is the hydrostatic
// correction the delta-SPH density diffusion applies for the same reason (Antuono et al. 2012; the study's
// eq. 21, rho^H). Away from rest it changes nothing but which linear field the smoothing preserves.
template <int D, typename T>
FLUME_HD T hydrostatic_strain(const T* x, const T* slope) {
  T e = 0;
  for (int a = 0; a < D; ++a) e += slope[a] * x[a];
  return e;
}

// Bed stress by the wall law, for a rough channel bed (a half-space's roughness_m): tau = rho C_f |u_t| u_t
// on the velocity u_t along the bed at height z, with the log law's C_f = (kappa / ln(z / z0))^2 over a fully
// rough wall, z0 = k_s / 30 (Nikuradse). The node on the bed carries the water of the cell layer above it
// (its stencil reaches 1.5 cells), so z = dx / 2; below z = e^2 z0 the velocity lies within the roughness,
// where the law does not hold, and C_f stops growing. Coulomb friction (`friction`) scales with the weight
// and holds still water back; this stress is zero at rest and grows as u^2, as a channel's roughness acts
// (Soares-Frazao & Zech's dam break: docs/validation.md, section 6).
constexpr double kKarman = 0.41;
inline double bed_drag_coefficient(double roughness, double dx) {
  if (!(roughness > 0)) return 0;
  const double log_ratio = std::log(0.5 * dx / (roughness / 30.0));
  const double k = kKarman / (log_ratio > 2.0 ? log_ratio : 2.0);
  return k * k;
}
// The stress on a node of mass m on a bed of normal n moving at vb, for a step dt, implicit in the speed so
// it can only slow the node: u_t <- u_t / (1 + k |u_t| dt / m), k = rho C_f times the node's bed area
// (dx^(D-1)).
template <int D, typename T>
FLUME_HD void bed_stress(T* v, const T* n, const T* vb, T k, T m, T dt) {
  if (!(m > T(0))) return;
  T u[D], un = 0, ut2 = 0;
  for (int a = 0; a < D; ++a) {
    u[a] = v[a] - vb[a];
    un += u[a] * n[a];
  }
  for (int a = 0; a < D; ++a) {
    u[a] -= un * n[a];
    ut2 += u[a] * u[a];
  }
  const T slow = T(1) / (T(1) + k * std::sqrt(ut2) * dt / m);
  for (int a = 0; a < D; ++a) v[a] -= (T(1) - slow) * u[a];
}

// Boundary projection of a grid-node velocity (paper eq. 2). n is the outward normal of the solid (into
// the fluid), vb the boundary's velocity. Separate: only motion into the solid is removed, and the
// tangential slip is reduced by Coulomb friction mu |v_n| (Hu et al. 2018's separable friction).
// kSymmetry is not a wall: a mirror plane of the flow (SymmetryPlane), handled by folding the grid across it.
enum class Bc : int { kSticky = 0, kSlip = 1, kSeparate = 2, kSymmetry = 3 };

template <int D, typename T>
FLUME_HD void project_velocity(T* v, const T* n, const T* vb, Bc bc, T mu) {
  T vr[D];
  T vn = 0;
  for (int a = 0; a < D; ++a) {
    vr[a] = v[a] - vb[a];
    vn += vr[a] * n[a];
  }
  if (bc == Bc::kSticky) {
    for (int a = 0; a < D; ++a) v[a] = vb[a];
    return;
  }
  if (bc == Bc::kSeparate && vn >= T(0)) return;  // leaving the wall: free
  T vt[D];
  T vt_norm2 = 0;
  for (int a = 0; a < D; ++a) {
    vt[a] = vr[a] - vn * n[a];
    vt_norm2 += vt[a] * vt[a];
  }
  T scale = T(1);
  if (bc == Bc::kSeparate && mu > T(0) && vt_norm2 > T(0)) {
    const T vt_norm = std::sqrt(vt_norm2);
    scale = vt_norm + mu * vn > T(0) ? (vt_norm + mu * vn) / vt_norm : T(0);  // vn < 0 here
  }
  for (int a = 0; a < D; ++a) v[a] = vb[a] + scale * vt[a];
}

// Free slip by reflection. A grid node half a cell or more inside a solid (a ghost node) gets its mass from the
// few particles within reach of it, and a slip wall leaves its tangential velocity free: computed from that thin,
// one-sided stencil it drifts, and a column of water at rest grew a convection along its side walls (up at the
// walls, down in the middle; docs/validation.md, section 1). A free-slip wall is a mirror: the tangential velocity
// is even about it. So a ghost node at depth d cells is paired with the fluid node nearest its reflection (the
// node round(2 d) cells out along the normal), and the pair exchanges tangential momentum until both move alike
// (ghost_exchange); the normal velocity stays what the wall condition gave the ghost. Sticky walls keep their
// own rule. These functions add, per solid holding the node, the reflection's offset in nodes along the solid's
// (axis-aligned) normal, and the axis to `axes`; `ambiguous` is set where the reflection is not defined (a normal
// off the grid axes, two solids along one axis as inside a thin panel), and the node then keeps its velocity.
// In cells: the margin by which every rule below compares a node's position with a wall. Walls mostly lie on grid
// lines or half cells, so nodes sit exactly on the rules' thresholds, where the last bit of a coordinate (rounded
// otherwise by a fused multiply-add, another compiler, a GPU) would decide; with the margin a node at a threshold
// takes the side the rule states, whatever its round-off (tests/solver/test_geometry_ties.cpp).
constexpr double kTieCells = 1e-6;
// In cells: a node at least this far inside is a ghost node: from a quarter cell in, the node nearest its
// reflection is another node (a node half a cell inside, next to a wall between two grid lines such as the
// quay face at x = 4.45 m with dx = 0.02 m, is one). Shallower, the node is its own image and keeps its
// velocity. Left to its one-sided stencil, a node a quarter cell inside drifted as the deeper ghosts did
// before them (docs/solver.md, "Walls between grid lines").
constexpr double kGhostDepth = 0.25 - kTieCells;
// In cells: how far the quadratic B-spline stencil reaches; a particle further than this from a node gives it
// nothing, so water beyond a face cannot reach a node deeper than this inside the solid.
constexpr double kStencilReach = 1.5;
// `axes` holds the normal axes in bits 0..2 and, kGhostSignShift above each, whether the fluid (the mirror node)
// lies towards lower indices along it.
constexpr int kGhostSignShift = 3;

FLUME_HD void ghost_axis_step(int axis, double depth_cells, int sign, int* offset, unsigned& axes,
                                     bool& ambiguous) {
  if (depth_cells < kGhostDepth) return;
  if (axes & (1u << axis)) {
    ambiguous = true;
    return;
  }
  axes |= 1u << axis;
  if (sign < 0) axes |= 1u << (axis + kGhostSignShift);  // the fluid lies towards lower indices
  offset[axis] += sign * static_cast<int>(2 * depth_cells + 0.5 + kTieCells);  // the node nearest the reflection
}

template <int D>
FLUME_HD void ghost_half_space(const double* x, const double* point, const double* n, double dx, int* offset,
                               unsigned& axes, bool& ambiguous) {
  double dist = 0;
  int axis = -1;
  for (int a = 0; a < D; ++a) {
    dist += (x[a] - point[a]) * n[a];
    if (n[a] > 0.999 || n[a] < -0.999) axis = a;
  }
  if (-dist < kGhostDepth * dx) return;
  if (axis < 0) {
    ambiguous = true;
    return;
  }
  ghost_axis_step(axis, -dist / dx, n[axis] > 0 ? 1 : -1, offset, axes, ambiguous);
}

// A node inside a box [lo, hi]: each face it lies 0.5 to kStencilReach cells inside of (the faces that hold
// it, wall_faces). Near a convex edge the node is reached by water on two sides (over the quay's top and in
// front of its face): the method of images has no image for a convex edge (the diagonal reflection is the image
// of a concave corner only, ghost_domain), and the diagonal mirror pushed back the water about to flow over the
// edge. Such a node keeps its own velocity, as a node whose reflection is undefined does.
template <int D>
FLUME_HD void ghost_box(const double* x, const double* lo, const double* hi, double dx, int* offset, unsigned& axes,
                        bool& ambiguous) {
  const double tol = kTieCells * dx;
  for (int a = 0; a < D; ++a)
    if (!(x[a] > lo[a] + tol && x[a] < hi[a] - tol)) return;  // not strictly inside
  const double reach = kStencilReach - kTieCells;
  const unsigned axes_before = axes;
  int stepped = 0;
  for (int a = 0; a < D; ++a) {
    const double below = (x[a] - lo[a]) / dx, above = (hi[a] - x[a]) / dx;
    const unsigned seen = axes;
    const bool thin = below <= 2 + kTieCells && above <= 2 + kTieCells;  // undefined: wall_faces holds it by both
    if (below < reach || thin) ghost_axis_step(a, below, -1, offset, axes, ambiguous);
    if (above < reach || thin) ghost_axis_step(a, above, 1, offset, axes, ambiguous);
    stepped += axes != seen;
  }
  if (stepped > 1) {
    ambiguous = true;
    axes = axes_before;
  }
}

// Nodes beyond the domain box's faces (the container).
template <int D>
FLUME_HD void ghost_domain(const double* x, const double* lo, const double* hi, double dx, int* offset,
                           unsigned& axes, bool& ambiguous) {
  for (int a = 0; a < D; ++a) {
    if (x[a] < lo[a]) ghost_axis_step(a, (lo[a] - x[a]) / dx, 1, offset, axes, ambiguous);
    if (x[a] > hi[a]) ghost_axis_step(a, (x[a] - hi[a]) / dx, -1, offset, axes, ambiguous);
  }
}

// The exchange between a mirror node (mass mm, velocity vm) and the ghost nodes that reflect onto it: along
// each axis tangential to a ghost, that ghost and the mirror take their mass-weighted mean velocity, a
// perfectly inelastic collision. Momentum is conserved (the exchange is internal to the water, a free-slip
// wall exerts no tangential force). Overwriting the ghost's velocity with the mirror's instead is not
// conservative (docs/solver.md, "Measurements behind the constants").
//
// Next to a concave edge or corner several ghosts share one mirror (up to 7 in a 3D corner). They exchange as
// one group: along each axis, the mirror and every ghost tangential to it take the group's mean. Pairwise
// exchanges computed from the same velocities and summed at the mirror are not a collision: their impulses do
// work sum_{i!=j} a_i a_j (dv_i . dv_j) / mm on the final velocities (a_i the pair's reduced mass, dv_i the
// ghost's velocity relative to the mirror), every step, which grew a particle-scale mode along the floor's
// edges of a stiff 3D bore (docs/tradeoff.md, "The debris scene"). The group's mean does none.
//
// Along the normal axes the ghost is the mirror node's image: the mirror takes the ghost's mass and its
// normal momentum reflected, mg (-vg_pre), vg_pre being the velocity the particles alone gave the ghost (the
// push of the water's pressure into the wall), before gravity and the wall condition. Gravity is left out:
// the image of the ghost's weight would lift the first node above a floor. Without it, the first fluid node
// off a wall feels the pressure of the particles on its fluid side only (its stencil reaches into the wall,
// where there are none) and is pushed towards the wall by 1/8 of p per cell face: the water crowds along
// every wall until its compression balances that (a still tank's surface rose along its walls:
// docs/solver.md). The image's push is what the missing particles would have given; the wall takes it (it is
// counted in the wall's load). The push only ever slows a mirror node that moves towards the wall, down to
// rest at most: it is a contact force and does no positive work (unbounded, it pumped energy into a soft
// tank). Ghosts pushing along one axis pool their images, so that together they too stop the mirror at most;
// images from both sides of it (a channel a few cells wide) leave it unpushed, as an undefined reflection
// does. It acts on the axes in `push_axes` (image_push_axes: walls with a normal across gravity); elsewhere a
// normal axis keeps its velocity.
//
// The group's sums, kGhostPoolLanes per axis (lane c of axis a at pool[c * D + a]): the tangential ghosts'
// mass and momentum, then the pushing ghosts' mass, mass signed by the side away from the wall, and pre-wall
// momentum. A ghost's terms (ghost_pool_terms) are summed in any order, atomically on a device.
constexpr int kGhostPoolLanes = 5;

template <int D, typename T>
FLUME_HD void ghost_pool_terms(const T* vg, const T* vg_pre, T mg, unsigned axes, unsigned push_axes,
                               T* terms) {
  for (int k = 0; k < kGhostPoolLanes * D; ++k) terms[k] = T(0);
  for (int a = 0; a < D; ++a) {
    if (!(axes & (1u << a))) {
      terms[a] = mg;
      terms[D + a] = mg * vg[a];
    } else if (push_axes & (1u << a)) {
      terms[2 * D + a] = mg;
      terms[3 * D + a] = (axes & (1u << (a + kGhostSignShift))) ? -mg : mg;
      terms[4 * D + a] = mg * vg_pre[a];
    }
  }
}

// From a mirror's pool: u, the velocity the mirror and its tangential ghosts take along each axis (the
// mirror's own where no ghost is tangential to it), and push_dv, the image's push on the mirror (the wall's
// load; zero where none). The push acts first, then the tangential mean: the group ends with one velocity per
// axis.
//
// The mirror may itself lie on a wall (`held`: the axes its walls hold, mpm::apply_boundaries): along those
// it keeps its velocity and takes no push, and its ghosts keep theirs (ghost_takes_mean); along the others it
// is free and exchanges as any mirror. Next to a wall between two grid lines the ghost on the floor's row
// reflects onto a floor node, free along the floor; left out, that node lacked the image's push of the
// deepest water and a current rose along the wall for good (docs/solver.md, "Walls between grid lines").
template <int D, typename T>
FLUME_HD void ghost_pool_velocity(const T* pool, const T* vm, T mm, unsigned held, T* u, T* push_dv) {
  for (int a = 0; a < D; ++a) {
    if (held & (1u << a)) {
      u[a] = vm[a];
      push_dv[a] = T(0);
      continue;
    }
    T v = vm[a];
    const T nm = pool[2 * D + a], ns = pool[3 * D + a];
    const T minority = (nm - (ns < T(0) ? -ns : ns)) / T(2);  // the pushing mass on the less weighted side
    if (nm > T(0) && minority <= T(1e-6) * nm) {
      const T out = ns > T(0) ? T(1) : T(-1);  // away from the wall
      const T toward = out * v;                // < 0: moving towards it
      if (toward < T(0)) {
        const T pooled = out * (mm * v - pool[4 * D + a]) / (nm + mm);
        const T slowed = pooled < T(0) ? (pooled > toward ? pooled : toward) : T(0);
        v = out * slowed;
      }
    }
    push_dv[a] = v - vm[a];
    const T tm = pool[a];
    u[a] = tm > T(0) ? (pool[D + a] + mm * v) / (tm + mm) : v;
  }
}

// Whether a ghost takes its group's velocity u[a] along axis a (ghost_pool_velocity): along an axis
// tangential to it (not in its `axes`) that its mirror's walls leave free (not in `held`).
FLUME_HD bool ghost_takes_mean(unsigned axes, unsigned held, int a) { return !((axes | held) & (1u << a)); }

// One ghost and its mirror alone, as changes: dvg along the ghost's tangential axes, dvm the mirror's.
template <int D, typename T>
FLUME_HD void ghost_exchange(const T* vg, const T* vg_pre, T mg, const T* vm, T mm, unsigned axes,
                             unsigned push_axes, T* dvg, T* dvm) {
  T pool[kGhostPoolLanes * D], u[D], push_dv[D];
  ghost_pool_terms<D>(vg, vg_pre, mg, axes, push_axes, pool);
  ghost_pool_velocity<D>(pool, vm, mm, 0u, u, push_dv);
  for (int a = 0; a < D; ++a) {
    dvg[a] = ghost_takes_mean(axes, 0u, a) ? u[a] - vg[a] : T(0);
    dvm[a] = u[a] - vm[a];
  }
}

// The axes along which walls push with their ghosts' image: those gravity has no component along (side walls,
// the gate and quay faces; a symmetry plane is no wall, SymmetryPlane), not floors. The image is the mirror
// image of the pressure, right where the pressure is locally even about the wall; a floor carries the
// hydrostatic gradient across it, and there the push did harm (it slowed the bore over the Waseda apron:
// docs/solver.md, "Measurements behind the constants").
template <int D>
FLUME_HD unsigned image_push_axes(const double* gravity) {
  double g2 = 0;
  for (int a = 0; a < D; ++a) g2 += gravity[a] * gravity[a];
  unsigned axes = 0;
  for (int a = 0; a < D; ++a)
    if (gravity[a] * gravity[a] <= 1e-12 * g2) axes |= 1u << a;
  return axes;
}

// A symmetry plane: the flow is the mirror image of itself about x[axis] = at, and only the side `sign` of it
// (+1: x[axis] >= at, -1: x[axis] <= at) is modelled, as in a half-width basin. It is exact, not a wall: the
// grid of the modelled half is folded so that every node receives what the particles of the missing half (the
// images of the modelled ones) would have given it, and the nodes beyond the plane then take the mirror image of
// their reflection. P2G of a particle and of its image are reflections of each other (the stencil weights are
// even, the image's velocity, APIC matrix and stress are R v, R C R, R sigma R with R the reflection), so the
// image's share of node i is the reflection of what the particle gave node i' = mirror(i). Before the grid
// update, node i on the modelled side adds R * node i' (i' beyond the plane), and a node on the plane adds its
// own reflection (its mass doubles, its normal momentum cancels); after the update, a node beyond the plane is
// the reflection of its mirror. The modelled half then moves exactly as that half of the whole (to round-off),
// whatever the walls, the gravity or the resolution, where a slip wall would make the plane's first fluid node
// feel the pressure from one side only (mpm::ghost_exchange). A particle that the step carries across the plane
// is replaced by its image, which the step carries into the modelled side. The plane must lie on a grid line or
// midway between two: `twice` = 2 (at - grid_lo) / dx, an integer, and node i's mirror is twice - i.
struct SymmetryPlane {
  int axis = 0;
  int sign = 1;
  int twice = 0;
  double at = 0;
};

// Where node index i (along the plane's axis) lies: -1 on the modelled side, 0 on the plane, +1 beyond it.
FLUME_HD int symmetry_side(const SymmetryPlane& s, int i) {
  const int r = 2 * i - s.twice;
  if (r == 0) return 0;
  return (r > 0) == (s.sign > 0) ? -1 : 1;
}

// The sign that reflection gives grid channel c (mass, momentum D, strain, volume, then with FLIP the
// transfer's momentum D): -1 for the normal momentum, in either place.
template <int D>
FLUME_HD int symmetry_channel_sign(const SymmetryPlane& s, int c) {
  return c == 1 + s.axis || c == D + 3 + s.axis ? -1 : 1;
}

// Whether a particle at coordinate xa along the plane's axis lies beyond the plane.
template <typename T>
FLUME_HD bool symmetry_beyond(const SymmetryPlane& s, T xa) {
  const T d = xa - T(s.at);
  return s.sign > 0 ? d < T(0) : d > T(0);
}

// Replaces a particle that lies beyond the plane by its image: position, velocity and APIC matrix reflected.
template <int D, typename T>
FLUME_HD void symmetry_reflect_particle(const SymmetryPlane& s, T* x, T* v, T* C) {
  const int a = s.axis;
  if (!symmetry_beyond(s, x[a])) return;
  const T at = T(s.at), d = x[a] - at;
  x[a] = at - d;
  v[a] = -v[a];
  for (int b = 0; b < D; ++b) {
    if (b == a) continue;
    C[a * D + b] = -C[a * D + b];
    C[b * D + a] = -C[b * D + a];
  }
}

// Signed distance and outward normal of an axis-aligned solid box [lo, hi] (negative inside).
template <int D, typename T>
FLUME_HD T box_distance(const T* x, const T* lo, const T* hi, T* normal) {
  T outside2 = 0, inside = -T(1e30);
  int inside_axis = 0;
  T inside_sign = 1;
  T out_dir[D];
  for (int a = 0; a < D; ++a) {
    const T below = lo[a] - x[a], above = x[a] - hi[a];
    const T q = below > above ? below : above;
    out_dir[a] = below > 0 ? -below : (above > 0 ? above : T(0));
    if (q > 0) outside2 += q * q;
    if (q > inside) {
      inside = q;
      inside_axis = a;
      inside_sign = below > above ? T(-1) : T(1);
    }
  }
  if (outside2 > 0) {
    const T d = std::sqrt(outside2);
    for (int a = 0; a < D; ++a) normal[a] = out_dir[a] / d;
    return d;
  }
  for (int a = 0; a < D; ++a) normal[a] = a == inside_axis ? inside_sign : T(0);
  return inside;
}

template <int D, typename T>
FLUME_HD T half_space_distance(const T* x, const T* point, const T* n, T* normal) {
  T d = 0;
  for (int a = 0; a < D; ++a) {
    d += (x[a] - point[a]) * n[a];
    normal[a] = n[a];
  }
  return d;
}

// Which analytic wall holds grid node x, and through which face normals: a node on or in the wall (within
// kTieCells dx) is held, any other is free. Decided in double: walls usually sit on grid lines, and in float the
// node on the wall would fall on either side of it by round-off (docs/solver.md).
//
// A node inside a box is held by every face whose outside water can reach it, not only by the nearest: near
// the quay's top edge the nearest face is the top, and a node constrained by it alone would let the basin's
// water flow sideways into the wall. Inside a thin wall (both faces of an axis within two cells), such as the
// gate panel, both faces hold it. Otherwise water beyond a face reaches a node less than kStencilReach cells in
// from it; a face deeper than that has nothing to stop there, and holding the node by it anyway stopped the
// sheet flowing over the quay's crest (a node 1.5 cells behind the front face and under the top lost its
// streamwise velocity; docs/validation.md, section 1). Returns the number of normals written to n (0: the node
// is free).
//
// So a wall face between two grid lines acts from the next node inside it (a `subcell` boundary resolves it:
// subcell_cover below; docs/calibration.md).
template <int D>
FLUME_HD int wall_faces(const double* x, bool box, const double* a, const double* b, double dx, double (*n)[D]) {
  const double tol = kTieCells * dx;
  double nd[D];
  const double dist = box ? box_distance<D>(x, a, b, nd) : half_space_distance<D>(x, a, b, nd);
  if (dist > tol) return 0;
  if (!box) {
    for (int d = 0; d < D; ++d) n[0][d] = nd[d];
    return 1;
  }
  int count = 0;
  for (int ax = 0; ax < D; ++ax) {
    const bool thin = x[ax] - a[ax] <= 2 * dx + tol && b[ax] - x[ax] <= 2 * dx + tol;
    for (int side = 0; side < 2; ++side) {
      const double depth = side == 0 ? x[ax] - a[ax] : b[ax] - x[ax];  // distance in from this face
      if (thin ? depth > 2 * dx + tol : depth > kStencilReach * dx - tol) continue;
      for (int d = 0; d < D; ++d) n[count][d] = d == ax ? (side == 0 ? -1.0 : 1.0) : 0.0;
      ++count;
    }
  }
  if (count == 0) {  // deep inside: the nearest face; of faces equally near, the first in axis order, low side first
    double nearest = 1e300;
    for (int ax = 0; ax < D; ++ax)
      for (int side = 0; side < 2; ++side) {
        const double depth = side == 0 ? x[ax] - a[ax] : b[ax] - x[ax];
        if (!(depth < nearest - tol)) continue;
        nearest = depth;
        for (int d = 0; d < D; ++d) n[0][d] = d == ax ? (side == 0 ? -1.0 : 1.0) : 0.0;
      }
    count = 1;
  }
  return count;
}

// A wall's action on a held grid node's velocity: the projection through each of its faces (project_velocity).
template <int D, typename T>
FLUME_HD void apply_wall(T* v, const double (*n)[D], int faces, const T* vb, Bc bc, T mu) {
  for (int f = 0; f < faces; ++f) {
    T nf[D];
    for (int d = 0; d < D; ++d) nf[d] = T(n[f][d]);
    project_velocity<D>(v, nf, vb, bc, mu);
  }
}

// The faces of a box within a cell of node x (outward normals n, at most one per axis) and each one's share
// s_f = 1 - depth_f / dx: 1 on the face, 0 a cell in. A node under one face is a point of a plane wall, free
// along it; under two it is on a convex edge, which water passes round (the gate's lip, the quay's crest, a
// column). The shares let apply_box_wall pass from wall_faces' hold to those rules smoothly as a face moves
// across the grid, since the gate's height is calibrated. None where an axis has both faces within a cell (a
// wall thinner than two cells keeps wall_faces' hold).
template <int D>
FLUME_HD int surface_faces(const double* x, const double* lo, const double* hi, double dx, double (*n)[D],
                           double* s) {
  int count = 0;
  for (int a = 0; a < D; ++a) {
    const double below = (x[a] - lo[a]) / dx, above = (hi[a] - x[a]) / dx;
    if (below < 1 && above < 1) return 0;
    const bool low = below <= above;
    const double depth = low ? below : above;
    if (!(depth < 1)) continue;
    for (int d = 0; d < D; ++d) n[count][d] = d == a ? (low ? -1.0 : 1.0) : 0.0;
    s[count++] = 1 - (depth > 0 ? depth : 0.0);
  }
  return count;
}

// The velocity on a convex edge: one that enters the box through every face of the edge (into the solid's
// corner) is held by all of them, as wall_faces holds the node; any other passes, round the edge. Holding, not
// the nearest admissible velocity: that would remove the smaller normal component and keep the larger, turning
// the push of still water into the corner into a current along one face (a held reservoir then stirred itself,
// docs/validation.md, section 1). The wall's reaction at an edge may point anywhere in its normal cone, so
// stopping the inward velocity whole is admissible and dissipates instead of redirecting.
template <int D, typename T>
FLUME_HD void apply_convex_edge(T* v, const double (*n)[D], int faces, const T* vb, Bc bc, T mu) {
  for (int f = 0; f < faces; ++f) {
    double vn = 0;
    for (int d = 0; d < D; ++d) vn += double(v[d] - vb[d]) * n[f][d];
    if (vn >= 0) return;
  }
  apply_wall<D>(v, n, faces, vb, bc, mu);
}

// A box's faces between grid lines, resolved below a cell (a `subcell` boundary: the basin's gate panel,
// whose opening is a calibrated parameter). wall_faces holds the nodes on or inside a box, so a face between
// two grid lines acts from the next node inside it, and WG1's peak was a staircase of the gate's height. Here
// a node outside the box by s < dx across a resolved face is partly covered, cover = prod_a (1 - s_a / dx): 1
// on the face (held, as wall_faces holds it), 0 one cell out (free), so that as the face moves by a cell the
// held row hands over to the next one without a jump. A partly covered node is drawn towards the velocity the
// box would give it (v_held, through the faces of its nearest point on the box) at the rate lambda = rate0
// cover / (1 - cover), integrated implicitly over the step: u <- u / (1 + lambda dt), u = v - v_held. rate0 =
// kSubcellRate c / dx, a quarter of the sound speed over a cell. The form and the constant are a sub-cell
// model, chosen so that the flow through a partly covered row falls linearly with its cover, and WG1's peak
// grows steadily with the gate's height across a cell (tests/waseda, Waseda.GateHeightActsBelowACell; the
// alternatives tried and their figures in docs/solver.md, "Measurements behind the constants").
constexpr double kSubcellRate = 0.25;
FLUME_HD double subcell_rate0(double sound_speed, double dx) { return kSubcellRate * sound_speed / dx; }
template <int D>
FLUME_HD double subcell_cover(const double* x, const double* lo, const double* hi, double dx, unsigned axes,
                              double* nearest) {
  double cover = 1;
  for (int a = 0; a < D; ++a) {
    const double s = x[a] < lo[a] ? lo[a] - x[a] : (x[a] > hi[a] ? x[a] - hi[a] : 0.0);
    if (axes & (1u << a))
      cover *= s < dx ? 1 - s / dx : 0.0;
    else if (s > kTieCells * dx)
      return 0;  // along the other axes a node outside the box is not covered at all, as before
    nearest[a] = x[a] < lo[a] ? lo[a] : (x[a] > hi[a] ? hi[a] : x[a]);
  }
  return cover;
}
template <int D, typename T>
FLUME_HD void subcell_drag(T* v, const T* v_held, double cover, double rate0, T dt) {
  if (!(cover > 0)) return;
  if (cover >= 1) {
    for (int a = 0; a < D; ++a) v[a] = v_held[a];
    return;
  }
  const T factor = T(1 / (1 + rate0 * cover / (1 - cover) * double(dt)));
  for (int a = 0; a < D; ++a) v[a] = v_held[a] + factor * (v[a] - v_held[a]);
}

// A box wall's action on a node it holds (wall_faces' faces n), near its surface (surface_faces): the velocity
// each subset S of the near faces alone gives (none: wall_faces' hold; one face: its projection; two or more:
// the edge's), collapsed face by face as a drag from the state with face f towards the state without it, at the
// cover 1 - s_f (subcell_drag): the drag form, because a partial hold applied outright every step blocks the flow
// as a full one does (docs/calibration.md, "Tried and rejected").
template <int D, typename T>
FLUME_HD void apply_box_wall(T* v, const double* x, const double* lo, const double* hi, double dx,
                             const double (*n)[D], int faces, const T* vb, Bc bc, T mu, double rate0, T dt) {
  double ns[D][D], s[D];
  const int near = surface_faces<D>(x, lo, hi, dx, ns, s);
  T state[1 << D][D];
  for (unsigned subset = 0; subset < (1u << near); ++subset) {
    double nsub[D][D];
    int k = 0;
    for (int f = 0; f < near; ++f)
      if (subset & (1u << f)) {
        for (int d = 0; d < D; ++d) nsub[k][d] = ns[f][d];
        ++k;
      }
    T* w = state[subset];
    for (int d = 0; d < D; ++d) w[d] = v[d];
    if (k == 0)
      apply_wall<D>(w, n, faces, vb, bc, mu);
    else if (k == 1)
      apply_wall<D>(w, nsub, 1, vb, bc, mu);
    else
      apply_convex_edge<D>(w, nsub, k, vb, bc, mu);
  }
  for (int f = near - 1; f >= 0; --f)
    for (unsigned subset = 0; subset < (1u << f); ++subset) {
      T* with = state[subset | (1u << f)];
      subcell_drag<D>(with, state[subset], 1 - s[f], rate0, dt);
      for (int d = 0; d < D; ++d) state[subset][d] = with[d];
    }
  for (int d = 0; d < D; ++d) v[d] = state[0][d];
}

}  // namespace flume::mpm
