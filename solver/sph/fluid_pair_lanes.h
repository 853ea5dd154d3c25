// The fluid-fluid pairs of one particle with the particles after it in cell order, each pair once for both
// particles, written for the CPU's vector units: the neighbours within the support are listed first
// (lanes.h), then one branch-free loop evaluates sph_kernels.h's pair functions for all of them (GCC
// vectorises it, gathering the neighbours' values; -fno-math-errno lets it take the square root), so the
// physics is the scalar path's. A's side is summed in a fixed order (lanes.h), each neighbour's added to its
// own sums, so results do not depend on the number of threads.
#pragma once
#include <algorithm>
#include <cstdint>

#include "solver/sph/lanes.h"
#include "solver/sph/sph_kernels.h"

namespace flume::sph {

// The fluid particles' arrays in cell order, and their sums.
template <int D, typename T>
struct FluidView : NeighbourView<D, T> {
  static constexpr int kS = Sym<D>::kSize;
  const T* k = nullptr;  // d rho / d p
  const T* tau[kS] = {};
  Accum<D, T>* sums = nullptr;  // per particle, one struct: a neighbour's terms land in a cache line or two
};

// The sums one side of each pair leaves, one slot per neighbour in the list.
template <int D, typename T, int N>
struct LaneSums {
  static constexpr int kFields = D + 1 + D * D + D + 1;  // acc, drho, gradv, gradc, divr
  T f[kFields][N];
  T visc_dt[N];
};

// Particle a against its neighbours nb[0 .. n) (all within the support, after a in cell order): each pair's
// two sides into per-neighbour slots by one branch-free vector loop, then a's summed into A and each
// neighbour's added to its own particle.
template <int D, typename T, bool kSps, bool kShift, int N>
void evaluate_pairs(const Params<T>& params, const FluidView<D, T>& view, uint32_t a, const T* xa,
                    const T* va, const uint32_t* nb, int n, Accum<D, T>& A) {
  // Local copies: loads the compiler sees are neither written in the loop nor guarded by a condition.
  const Params<T> P = params;
  const FluidView<D, T> V = view;
  constexpr int kS = Sym<D>::kSize;
  constexpr int kAcc = 0, kDrho = D, kGradv = D + 1, kGradc = D + 1 + D * D, kDivr = kGradc + D;
  const T rho_a = V.rho[a], ira = V.inv_rho[a], p_a = V.p[a], m_a = V.mass[a], k_a = V.k[a];
  T tau_a[kS];
  for (int k = 0; k < kS; ++k) tau_a[k] = V.tau[k][a];
  LaneSums<D, T, N> SA, SB;
  for (int l = 0; l < n; ++l) {
    const int b = static_cast<int>(nb[l]);
    T rab[D], vab[D];
    const T r2 = separation<D, T>(V, b, xa, va, rab, vab);
    const T F = wendland_gradient_factor(r2, P);
    Accum<D, T> Ap, Bp;
    const T rho_b = V.rho[b], irb = V.inv_rho[b], m_b = V.mass[b];
    pair_common<D, T>(P, rab, r2, F, vab, rho_a, ira, p_a, rho_b, irb, V.p[b], m_b, Ap, m_a, &Bp);
    pair_density_diffusion<D, T>(P, rab, r2, F, rho_a, k_a, rho_b, irb, m_b, Ap, V.k[b], m_a, ira, &Bp);
    if constexpr (kSps) {
      T tau_b[kS];
      for (int k = 0; k < kS; ++k) tau_b[k] = V.tau[k][b];
      pair_sps<D, T>(rab, F, vab, irb, m_b, tau_a, tau_b, Ap, m_a, ira, &Bp);
    }
    if constexpr (kShift) pair_shift<D, T>(rab, r2, F, m_b * irb, Ap, m_a * ira, &Bp);
    auto keep = [&](const Accum<D, T>& S, LaneSums<D, T, N>& L) {
      for (int d = 0; d < D; ++d) L.f[kAcc + d][l] = S.acc[d];
      L.f[kDrho][l] = S.drho;
      if constexpr (kSps)
        for (int k = 0; k < D * D; ++k) L.f[kGradv + k][l] = S.gradv[k];
      if constexpr (kShift) {
        for (int d = 0; d < D; ++d) L.f[kGradc + d][l] = S.gradc[d];
        L.f[kDivr][l] = S.divr;
      }
      L.visc_dt[l] = S.visc_dt;
    };
    keep(Ap, SA);
    keep(Bp, SB);
  }
  // a's side, summed.
  for (int d = 0; d < D; ++d) A.acc[d] += lane_sum(SA.f[kAcc + d], n);
  A.drho += lane_sum(SA.f[kDrho], n);
  if constexpr (kSps)
    for (int k = 0; k < D * D; ++k) A.gradv[k] += lane_sum(SA.f[kGradv + k], n);
  if constexpr (kShift) {
    for (int d = 0; d < D; ++d) A.gradc[d] += lane_sum(SA.f[kGradc + d], n);
    A.divr += lane_sum(SA.f[kDivr], n);
  }
  const T vdt = lane_max(SA.visc_dt, n);
  A.visc_dt = vdt > A.visc_dt ? vdt : A.visc_dt;
  A.pairs += n;
  // The neighbours' sides, each into its own particle.
  for (int l = 0; l < n; ++l) {
    Accum<D, T>& S = V.sums[nb[l]];
    for (int d = 0; d < D; ++d) S.acc[d] += SB.f[kAcc + d][l];
    S.drho += SB.f[kDrho][l];
    if constexpr (kSps)
      for (int k = 0; k < D * D; ++k) S.gradv[k] += SB.f[kGradv + k][l];
    if constexpr (kShift) {
      for (int d = 0; d < D; ++d) S.gradc[d] += SB.f[kGradc + d][l];
      S.divr += SB.f[kDivr][l];
    }
    S.visc_dt = SB.visc_dt[l] > S.visc_dt ? SB.visc_dt[l] : S.visc_dt;
    ++S.pairs;
  }
}

// Particle a (position xa, velocity va, its other values from V) against the particles after it that
// `ranges(f)` offers as contiguous ranges f(b0, b1): a's side into A, each neighbour's into its own sums in
// V. The candidates within the support are collected first (a vector loop over each range's distances, then
// their indices), up to kList at once, and evaluated together: rows of cells hold a few particles each, too
// few for a vector loop of their own. kSps: the laminar viscosity's sub-particle stress (P.alpha = 0);
// kShift: the shifting's sums.
template <int D, typename T, bool kSps, bool kShift, class Ranges>
void fluid_pairs_after(const Params<T>& params, const FluidView<D, T>& view, uint32_t a, const T* xa,
                       const T* va, const Ranges& ranges, Accum<D, T>& A) {
  constexpr int kList = 128;
  const Params<T> P = params;
  const FluidView<D, T> V = view;
  uint32_t nb[kList];
  int n = 0;
  auto flush = [&] {
    evaluate_pairs<D, T, kSps, kShift, kList>(P, V, a, xa, va, nb, n, A);
    n = 0;
  };
  ranges([&](uint32_t b0, uint32_t b1) {
    collect_within<D, T, true>(V.x, xa, P.support2, b0, b1, nb, n, flush);
  });
  if (n > 0) flush();
}

}  // namespace flume::sph
