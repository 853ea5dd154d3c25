// MpmSolver::p2g (solver/mpm/cpu_solver.h): each particle block scatters into its private tile. The
// per-particle terms are mpm::p2g_particle (solver/mpm/particle_k.h), shared with the CUDA backend; here is
// the CPU's batching and vectorised scatter.
#include <algorithm>
#include <cmath>

#include "solver/mpm/cpu_solver.h"
#include "solver/mpm/particle_k.h"

namespace flume::mpm {

template <int D, typename T, bool Flip>
typename MpmSolver<D, T, Flip>::TileBox MpmSolver<D, T, Flip>::tile_box(long p, const T* lo_grid, T inv_dx) const {
  int blk[D];
  unpack_key<D>(blocks_.pkeys[p], blk);
  const T* x[D];
  for (int d = 0; d < D; ++d) x[d] = x_[d].data();
  return mpm::tile_box<D>(blk, x, blocks_.pstart[p], blocks_.pstart[p + 1], lo_grid, inv_dx);
}

// P2G: each particle block scatters mass, momentum (with the MLS-MPM stress term) and mass-weighted strain J
// - 1 into its private tile, node-major with kLanes channels per node.
template <int D, typename T, bool Flip>
void MpmSolver<D, T, Flip>::p2g(T dt) {
  const T dx = T(dx_);
  const T rho = T(rho_);
  const T stress_scale = -dt * T(4) * inv_dx_ * inv_dx_;  // times the particle's reference volume
  const mpm::TaitLaw<T> law = law_;  // locals: the tile stores could alias members, which are reloaded then
  const T mu = mu_, inv_dx = inv_dx_;
  T slope_h[D], lo_grid[D];
  for (int d = 0; d < D; ++d) {
    slope_h[d] = strain_slope_[d];
    lo_grid[d] = T(grid_lo_[d]);
  }
  const T lift =
      T(double(dt) * scene_.basin.forcing.hold(run_.time) * std::fabs(scene_.solver.gravity[D - 1]));
  Lane unit[kLanes];
  for (int c = 0; c < kLanes; ++c) unit[c] = Eigen::Matrix<T, kLanes, 1>::Unit(c).array();
  const int nshares = shares_.count();
#pragma omp parallel for schedule(static, 1)
  for (int s = 0; s < nshares; ++s)
    for (long p = shares_.pfirst[s]; p < shares_.pfirst[s + 1]; ++p) {
      T* tile = &tiles_[static_cast<size_t>(p) * kLanes * kTileNodes];
      // G2P left the box of the particles' present positions, unless they were sorted or moved since.
      if (!boxes_current_) tile_box_[p] = tile_box(p, lo_grid, inv_dx);
      const TileBox box = tile_box_[p];
      mpm::for_each_box_row<D>(box,
                               [&](int a, int len) { std::fill_n(tile + a * kLanes, len * kLanes, T(0)); });
      int blk[D], origin[D];
      unpack_key<D>(blocks_.pkeys[p], blk);
      for (int d = 0; d < D; ++d) origin[d] = blk[d] * kBlock - 1;
      // Two passes per batch of particles. The first computes each particle's weights and what its nodes
      // receive into plain arrays across the batch; the second builds the lane vectors and scatters. The
      // scalar set-up then runs back to back for 32 particles instead of queueing behind each one's 27-node
      // scatter (measurements: docs/solver.md, "Measurements behind the constants").
      // Plain pointers to the particle arrays: GCC does not vectorise a loop that loads a vector's data
      // pointer out of `this` in its body (x_[d][i]), and the set-up loop below then ran scalar.
      const T *xs[D], *vs[D], *Cs[D * D];
      for (int d = 0; d < D; ++d) {
        xs[d] = x_[d].data();
        vs[d] = v_[d].data();
      }
      for (int k = 0; k < D * D; ++k) Cs[k] = C_[k].data();
      const T* es = e_.data();
      const T* vols = vol_.data();
      for (uint32_t b0 = blocks_.pstart[p]; b0 < blocks_.pstart[p + 1]; b0 += kBatch) {
        const int nb = static_cast<int>(std::min<uint32_t>(kBatch, blocks_.pstart[p + 1] - b0));
        alignas(64) T bw[D][3][kBatch], bat0[kChannels][kBatch], bslope[D][D][kBatch], bp[kBatch];
        alignas(64) T bslope_t[kFlipChannels > 0 ? D : 1][D][kBatch];  // the transfer's: m C dx
        alignas(64) int brel[D][kBatch];
        const T *bx[D], *bv[D], *bC[D * D], *be = es + b0, *bvol = vols + b0;  // the batch's particles
        for (int d = 0; d < D; ++d) {
          bx[d] = xs[d] + b0;
          bv[d] = vs[d] + b0;
        }
        for (int k = 0; k < D * D; ++k) bC[k] = Cs[k] + b0;
#pragma omp simd
        for (int j = 0; j < nb; ++j) bp[j] = law.pressure_series(be[j]);
        for (int j = 0; j < nb; ++j)
          if (!law.in_series(be[j])) bp[j] = law.pressure_exact(be[j]);
        // The stencil weights in a loop of their own per axis (as G2P), then the particle's terms. Both loops
        // vectorise across the batch (-fno-trapping-math for the float-to-int base), without `omp simd`
        // (docs/solver.md).
        alignas(64) T bf[D][kBatch];
        for (int d = 0; d < D; ++d) {
          for (int j = 0; j < nb; ++j) {
            T w[3];
            brel[d][j] = mpm::stencil_base((bx[d][j] - lo_grid[d]) * inv_dx, bf[d][j]) - origin[d];
            mpm::bspline_weights(bf[d][j], w);
            for (int c = 0; c < 3; ++c) bw[d][c][j] = w[c];
          }
        }
        for (int j = 0; j < nb; ++j) {
          T f[D], xp[D];
          for (int d = 0; d < D; ++d) {
            xp[d] = bx[d][j];
            f[d] = bf[d][j];
          }
          T Cp[D * D], vp[D], A[D * D], mom0[D], strain, volume;
          for (int k = 0; k < D * D; ++k) Cp[k] = bC[k][j];
          for (int a = 0; a < D; ++a) vp[a] = bv[a][j];
          const T V = bvol[j], m = rho * V;
          mpm::p2g_particle<D>(bp[j], Cp, be[j], V, m, vp, f, xp, dx, mu, stress_scale, slope_h, A, mom0,
                               strain, volume);
          // What node (base + i) receives, before its weight: the channels at i = 0 plus i_b times slope[b].
          for (int a = 0; a < D; ++a) {
            bat0[1 + a][j] = mom0[a];
            for (int b = 0; b < D; ++b) bslope[b][a][j] = A[a * D + b] * dx;
          }
          bat0[0][j] = m;
          if constexpr (kFlipChannels > 0) {
            T tmom0[D];
            mpm::p2g_transfer_momentum<D>(m, vp, Cp, f, dx, tmom0);
            for (int a = 0; a < D; ++a) {
              bat0[D + 3 + a][j] = tmom0[a];
              for (int b = 0; b < D; ++b) bslope_t[b][a][j] = m * Cp[a * D + b] * dx;
            }
          }
          bat0[1 + D][j] = strain;
          bat0[2 + D][j] = volume;
        }
        // The vacuum's hold: an upward force f(t) m |g| on the held water.
        if (!held_.empty())
          for (int j = 0; j < nb; ++j) bat0[D][j] += held_[b0 + j] * lift * bat0[0][j];
        for (int j = 0; j < nb; ++j) {
          // The lane vectors are summed from the unit vectors rather than written lane by lane: a vector load
          // right after scalar stores to the same place stalls (store forwarding fails).
          Lane at0 = bat0[0][j] * unit[0], slope[D];
          for (int c = 1; c < kChannels; ++c) at0 += bat0[c][j] * unit[c];
          for (int b = 0; b < D; ++b) {
            slope[b] = bslope[b][0][j] * unit[1];
            for (int a = 1; a < D; ++a) slope[b] += bslope[b][a][j] * unit[1 + a];
            if constexpr (kFlipChannels > 0)
              for (int a = 0; a < D; ++a) slope[b] += bslope_t[b][a][j] * unit[D + 3 + a];
          }
          if constexpr (D == 2) {
#pragma GCC unroll 3
            for (int i0 = 0; i0 < 3; ++i0) {  // offset-0 terms left out, as in 3D below
              const Lane r0 = i0 == 0 ? at0 : Lane(at0 + T(i0) * slope[0]);
              const int row = (brel[0][j] + i0) * kTile + brel[1][j];
#pragma GCC unroll 3
              for (int i1 = 0; i1 < 3; ++i1)
                LaneMap(tile + (row + i1) * kLanes) +=
                    (bw[0][i0][j] * bw[1][i1][j]) * (i1 == 0 ? r0 : Lane(r0 + T(i1) * slope[1]));
            }
          } else {
            // Node (i0, i1, i2) receives w0 w1 w2 (at0 + i0 s0 + i1 s1 + i2 s2). The last axis' weight goes
            // into the vectors once per particle (P, Q0, Q1 below), so that a node costs one vector
            // multiply-add to form its value and one to add it, with no scalar weight product and broadcast
            // per node. The offset-0 terms are left out rather than multiplied by zero (the compiler may not
            // drop x * 0): the loops are unrolled, so `i == 0` is decided at compile time.
            Lane P[3], Q0[3], Q1[3];
#pragma GCC unroll 3
            for (int i2 = 0; i2 < 3; ++i2) {
              const T w2 = bw[2][i2][j];
              P[i2] = w2 * (i2 == 0 ? at0 : Lane(at0 + T(i2) * slope[2]));
              Q0[i2] = w2 * slope[0];
              Q1[i2] = w2 * slope[1];
            }
#pragma GCC unroll 3
            for (int i0 = 0; i0 < 3; ++i0) {
              Lane R0[3];
#pragma GCC unroll 3
              for (int i2 = 0; i2 < 3; ++i2) R0[i2] = i0 == 0 ? P[i2] : Lane(P[i2] + T(i0) * Q0[i2]);
#pragma GCC unroll 3
              for (int i1 = 0; i1 < 3; ++i1) {
                const T w01 = bw[0][i0][j] * bw[1][i1][j];
                const int row = ((brel[0][j] + i0) * kTile + brel[1][j] + i1) * kTile + brel[2][j];
#pragma GCC unroll 3
                for (int i2 = 0; i2 < 3; ++i2)
                  LaneMap(tile + (row + i2) * kLanes) +=
                      w01 * (i1 == 0 ? R0[i2] : Lane(R0[i2] + T(i1) * Q1[i2]));
              }
            }
          }
        }
      }
    }
}

#define FLUME_INSTANTIATE(D, T, Flip)                                                         \
  template MpmSolver<D, T, Flip>::TileBox MpmSolver<D, T, Flip>::tile_box(long, const T*, T) const; \
  template void MpmSolver<D, T, Flip>::p2g(T);
FLUME_MPM_SOLVER_VARIANTS(FLUME_INSTANTIATE)
#undef FLUME_INSTANTIATE

}  // namespace flume::mpm
