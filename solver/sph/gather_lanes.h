// One point's sums over its neighbours of one kind, written for the CPU's vector units as fluid_pair_lanes.h
// is: the neighbours within the support are listed first (lanes.h), then one branch-free loop evaluates
// sph_kernels.h's pair functions into per-neighbour slots, summed in a fixed order. Used for a fluid
// particle's boxes (and, at its mirror image, its walls), a wall particle's water (its density rate and load,
// and the water's side of the same pairs), a box particle's water, and mDBC's ghost nodes.
#pragma once
#include <cstdint>

#include "solver/sph/lanes.h"
#include "solver/sph/sph_kernels.h"

namespace flume::sph {

// The point (position x, velocity v, density rho, 1/rho ir, pressure p) against the particles of `B` that
// `ranges(f)` offers as contiguous ranges f(b0, b1): pair_common's terms (and the shifting's with kShift)
// added to A. With kScatter each pair is evaluated for both sides at once: the point is a particle of mass m,
// and each neighbour's terms are added to its own sums, b_sums[b] (a wall particle's pairs with the water,
// which then needs no gather over the walls of its own).
template <int D, typename T, bool kShift, bool kScatter = false, class Ranges>
void gather_pairs(const Params<T>& params, const NeighbourView<D, T>& view, const T* x, const T* v, T rho,
                  T ir, T p, const Ranges& ranges, Accum<D, T>& A, T m = T(0), Accum<D, T>* b_sums = nullptr) {
  constexpr int N = 128;
  [[maybe_unused]] constexpr int kAcc = 0, kDrho = D, kGradc = D + 1, kDivr = 2 * D + 1, kFields = 2 * D + 2;
  // Local copies: loads the compiler sees are neither written in the loop nor guarded by a condition.
  const Params<T> P = params;
  const NeighbourView<D, T> B = view;
  uint32_t nb[N];
  int n = 0;
  // The terms of one side of each pair, one slot per neighbour.
  struct Side {
    T f[kFields][N], visc[N];
    void keep(int l, const Accum<D, T>& S) {
      for (int d = 0; d < D; ++d) f[kAcc + d][l] = S.acc[d];
      f[kDrho][l] = S.drho;
      if constexpr (kShift) {
        for (int d = 0; d < D; ++d) f[kGradc + d][l] = S.gradc[d];
        f[kDivr][l] = S.divr;
      }
      visc[l] = S.visc_dt;
    }
    void add_to(int l, Accum<D, T>& S) const {
      for (int d = 0; d < D; ++d) S.acc[d] += f[kAcc + d][l];
      S.drho += f[kDrho][l];
      if constexpr (kShift) {
        for (int d = 0; d < D; ++d) S.gradc[d] += f[kGradc + d][l];
        S.divr += f[kDivr][l];
      }
      S.visc_dt = visc[l] > S.visc_dt ? visc[l] : S.visc_dt;
      ++S.pairs;
    }
  };
  auto flush = [&] {
    Side a;
    [[maybe_unused]] Side b;
    for (int l = 0; l < n; ++l) {
      const int k = static_cast<int>(nb[l]);
      T rab[D], vab[D];
      const T r2 = separation<D, T>(B, k, x, v, rab, vab);
      const T F = wendland_gradient_factor(r2, P);
      Accum<D, T> S, Sb;
      pair_common<D, T>(P, rab, r2, F, vab, rho, ir, p, B.rho[k], B.inv_rho[k], B.p[k], B.mass[k], S, m,
                        kScatter ? &Sb : nullptr);
      if constexpr (kShift)
        pair_shift<D, T>(rab, r2, F, B.mass[k] * B.inv_rho[k], S, m * ir, kScatter ? &Sb : nullptr);
      a.keep(l, S);
      if constexpr (kScatter) b.keep(l, Sb);
    }
    for (int d = 0; d < D; ++d) A.acc[d] += lane_sum(a.f[kAcc + d], n);
    A.drho += lane_sum(a.f[kDrho], n);
    if constexpr (kShift) {
      for (int d = 0; d < D; ++d) A.gradc[d] += lane_sum(a.f[kGradc + d], n);
      A.divr += lane_sum(a.f[kDivr], n);
    }
    const T vdt = lane_max(a.visc, n);
    A.visc_dt = vdt > A.visc_dt ? vdt : A.visc_dt;
    A.pairs += n;
    if constexpr (kScatter)
      for (int l = 0; l < n; ++l) b.add_to(l, b_sums[nb[l]]);
    n = 0;
  };
  ranges([&](uint32_t b0, uint32_t b1) {
    collect_within<D, T, true>(B.x, x, P.support2, b0, b1, nb, n, flush);
  });
  if (n > 0) flush();
}

// mDBC: the moment sums (pair_ghost) at the point g over the particles of `B` that `ranges(f)` offers, added
// to S, with kVel the velocity sum too. A particle at g itself counts (its kernel value).
template <int D, typename T, bool kVel, class Ranges>
void gather_ghost(const Params<T>& params, const NeighbourView<D, T>& view, const T* g, const Ranges& ranges,
                  GhostSums<D, T>& S) {
  constexpr int N = 128;
  constexpr int K = D + 1;
  const Params<T> P = params;
  const NeighbourView<D, T> B = view;
  uint32_t nb[N];
  int n = 0;
  auto flush = [&] {
    T rhs[K][N], mom[K * K][N], vel[D][kVel ? N : 1];
    for (int l = 0; l < n; ++l) {
      const int b = static_cast<int>(nb[l]);
      T r[D], r2 = 0, vb[D];
      for (int d = 0; d < D; ++d) {
        r[d] = g[d] - B.x[d][b];
        r2 += r[d] * r[d];
        if constexpr (kVel) vb[d] = B.v[d][b];
      }
      GhostSums<D, T> s;
      pair_ghost<D, T>(P, r, r2, wendland_gradient_factor(r2, P), B.mass[b], B.mass[b] * B.inv_rho[b], s,
                       kVel ? vb : nullptr);
      for (int i = 0; i < K; ++i) rhs[i][l] = s.rhs[i];
      for (int i = 0; i < K * K; ++i) mom[i][l] = s.A[i];
      if constexpr (kVel)
        for (int d = 0; d < D; ++d) vel[d][l] = s.vel[d];
    }
    for (int i = 0; i < K; ++i) S.rhs[i] += lane_sum(rhs[i], n);
    for (int i = 0; i < K * K; ++i) S.A[i] += lane_sum(mom[i], n);
    if constexpr (kVel)
      for (int d = 0; d < D; ++d) S.vel[d] += lane_sum(vel[d], n);
    n = 0;
  };
  ranges([&](uint32_t b0, uint32_t b1) {
    collect_within<D, T, false>(B.x, g, P.support2, b0, b1, nb, n, flush);
  });
  if (n > 0) flush();
}

}  // namespace flume::sph
