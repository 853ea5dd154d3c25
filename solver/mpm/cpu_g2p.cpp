// MpmSolver::g2p (solver/mpm/cpu_solver.h): each particle block gathers its tile of nodes once, then updates
// its particles (mpm::g2p_particle, solver/mpm/particle_k.h, shared with the CUDA backend) with separable
// stencil sums; pushes particles out of debris boxes; sums the energy audit and checks for blow-up.
#include <algorithm>
#include <cmath>
#include <limits>

#include "solver/mpm/audit.h"
#include "solver/mpm/cpu_solver.h"
#include "solver/mpm/particle_k.h"

namespace flume::mpm {

// Copies n <= N values: a full batch (all but a block's last) by a copy of constant size, which the compiler
// does in a few vector moves instead of a library call.
template <int N, typename T>
inline void copy_batch(const T* from, int n, T* to) {
  if (n == N)
    std::copy_n(from, N, to);
  else
    std::copy_n(from, n, to);
}

// G2P: new velocity, affine matrix, J (with J-bar mixing) and position; checks for blow-up.
template <int D, typename T, bool Flip>
void MpmSolver<D, T, Flip>::g2p(T dt) {
  const T dx = T(dx_);
  const T cscale = T(4) * inv_dx_ * inv_dx_;
  const T fill_rate = T(mpm::fill_rate(double(dt), c_, dx_));
  // Locals of the members the particle loop reads: its stores to the particle arrays could alias a member
  // of type T, which the compiler would then reload (and the Tait law's set-up redo) for every particle.
  const mpm::TaitLaw<T> law = law_;
  const T inv_dx = inv_dx_;
  const T flip = T(mpm::flip_for_step(double(flip_), double(dt), dx_, c_));
  mpm::G2pConstants<D, T> g2p_k;
  g2p_k.dt = dt;
  g2p_k.psi = psi_;
  g2p_k.fill_rate = fill_rate;
  g2p_k.fill_tol = fill_tolerance_;
  g2p_k.law_d = law_d_;
  g2p_k.has_sym = has_sym_;
  g2p_k.sym = sym_;
  T lo_grid[D], grav[D];
  for (int d = 0; d < D; ++d) {
    g2p_k.slope[d] = strain_slope_[d];
    lo_grid[d] = T(grid_lo_[d]);
    grav[d] = gravity_[d];
  }
  const double rho = rho_;
  const long nblocks = static_cast<long>(blocks_.pkeys.size());
  double vmax2 = 0, ke = 0, pe = 0, el = 0, fill_work = 0;
  long bad = std::numeric_limits<long>::max();
  int bad_kind = 0;
  bool resort = false;
  double lo_ok[D], hi_ok[D];
  for (int d = 0; d < D; ++d) {
    lo_ok[d] = scene_.domain_lo[d] - dx_;
    hi_ok[d] = scene_.domain_hi[d] + dx_;
  }
  if (debris_) debris_->begin_g2p(nblocks);
  static const std::vector<mpm::TileNode> tile_map = mpm::make_tile_map<D>();
  const int nshares = shares_.count();
#pragma omp parallel for schedule(static, 1) reduction(max : vmax2) reduction(+ : ke, pe, el, fill_work) reduction(|| : resort)
  for (int s = 0; s < nshares; ++s)
    for (long p = shares_.pfirst[s]; p < shares_.pfirst[s + 1]; ++p) {
      const bool near_debris =
          debris_ && debris_->near_particle_block(blocks_.pkeys[p], 2 * dx_, grid_lo_, dx_);
      double* push_slots = near_debris ? debris_->block_slots(p) : nullptr;
      // The audit's sums per batch position (summed over the block at its end): a sum across the batch would
      // be a floating-point reduction, which the compiler keeps in order and does not vectorise.
      alignas(64) T vmax2_l[kBatch] = {}, ke_l[kBatch] = {}, pe_l[kBatch] = {}, el_l[kBatch] = {};
      // And the block's lowest and highest new position per axis, for the re-sort check at its end.
      alignas(64) T xlo_l[D][kBatch], xhi_l[D][kBatch];
      for (int d = 0; d < D; ++d) {
        std::fill_n(xlo_l[d], kBatch, std::numeric_limits<T>::max());
        std::fill_n(xhi_l[d], kBatch, std::numeric_limits<T>::lowest());
      }
      // Gather the tile around this block: per node the velocity, then (free nodes only) strain, fill and
      // weight.
      alignas(64) T tg[kTileNodes * kLanes];
      int blk[D], origin[D];
      unpack_key<D>(blocks_.pkeys[p], blk);
      for (int d = 0; d < D; ++d) origin[d] = blk[d] * kBlock - 1;
      // Only the tile box P2G found (the particles have not moved since): the rest of tg is never read.
      const auto fetch = [&](int a) {
        const int32_t g = blocks_.p_nbr[p * kNbr + tile_map[a].block];
        const size_t idx = static_cast<size_t>(g) * kNodes + tile_map[a].local;
        T* t = tg + a * kLanes;
        for (int d = 0; d < D; ++d) t[d] = grid_.v[d][idx];
        const T free = grid_.wall[idx] ? T(0) : T(1);
        t[D] = free * grid_.e[idx];
        t[D + 1] = free * grid_.fill[idx];
        t[D + 2] = free;
        for (int c = D + 3; c < kLanes; ++c) t[c] = T(0);
        if constexpr (kFlipChannels > 0)
          for (int d = 0; d < D; ++d) t[D + 3 + d] = grid_.vold[d][idx];
      };
      mpm::for_each_box_row<D>(tile_box_[p], [&](int a, int len) {
        for (int k = 0; k < len; ++k) fetch(a + k);
      });
      // Per batch of particles, five passes: the stencil weights; the gather, one particle at a time (vector
      // lanes are a node's channels); the strain update and the move across the batch (lanes are particles);
      // the rare branches (the constraint's work, the symmetry image, the debris push-out), one particle at a
      // time; the checks and the audit's sums across the batch. The batch lives in local arrays, which the
      // compiler knows alias nothing, so the passes across the batch vectorise.
      for (uint32_t b0 = blocks_.pstart[p]; b0 < blocks_.pstart[p + 1]; b0 += kBatch) {
        const int nb = static_cast<int>(std::min<uint32_t>(kBatch, blocks_.pstart[p + 1] - b0));
        alignas(64) T bw[D][3][kBatch], bf[D][kBatch];
        alignas(64) int brel[D][kBatch];
        for (int d = 0; d < D; ++d) {
          const T* xd = x_[d].data() + b0;
          for (int j = 0; j < nb; ++j) {
            T fj, w[3];
            brel[d][j] = mpm::stencil_base((xd[j] - lo_grid[d]) * inv_dx, fj) - origin[d];
            mpm::bspline_weights(fj, w);
            bf[d][j] = fj;
            for (int c = 0; c < 3; ++c) bw[d][c][j] = w[c];
          }
        }
        alignas(64) T bv[D][kBatch], bC[D * D][kBatch], bJg[kBatch], bFg[kBatch], bws[kBatch];
        for (int j = 0; j < nb; ++j) {
          T w[D][3], f[D];
          int rel[D];
          for (int d = 0; d < D; ++d) {
            rel[d] = brel[d][j];
            f[d] = bf[d][j];
            for (int c = 0; c < 3; ++c) w[d][c] = bw[d][c][j];
          }
          // Separable sums over the stencil: S = sum w n, and M[b] = sum w i_b n (i_b the node's offset 0, 1,
          // 2 on axis b), n the node's lanes. Then v = S[0..D), the APIC matrix C_ab = sum w v_a (i_b - f_b)
          // dx = (M[b][a] - f_b S[a]) dx, and the free-node sums of strain, fill and weight are S[D..D+3).
          Lane S = Lane::Zero(), M[D];
          for (int b = 0; b < D; ++b) M[b] = Lane::Zero();
          if constexpr (D == 2) {
#pragma GCC unroll 3
            for (int i0 = 0; i0 < 3; ++i0) {
              const T* n = tg + ((rel[0] + i0) * kTile + rel[1]) * kLanes;
              const Lane n1 = ConstLaneMap(n + kLanes), n2 = ConstLaneMap(n + 2 * kLanes);
              const Lane r = w[1][0] * ConstLaneMap(n) + w[1][1] * n1 + w[1][2] * n2;
              const Lane r1 = w[1][1] * n1 + (T(2) * w[1][2]) * n2;
              S += w[0][i0] * r;
              if (i0 > 0) M[0] += (T(i0) * w[0][i0]) * r;
              M[1] += w[0][i0] * r1;
            }
          } else {
            // Terms at offset 0 are left out rather than multiplied by zero (the loops are unrolled, so the
            // test is decided at compile time).
#pragma GCC unroll 3
            for (int i0 = 0; i0 < 3; ++i0) {
              Lane S1 = Lane::Zero(), M1 = Lane::Zero(), M2 = Lane::Zero();
#pragma GCC unroll 3
              for (int i1 = 0; i1 < 3; ++i1) {
                const T* n = tg + (((rel[0] + i0) * kTile + rel[1] + i1) * kTile + rel[2]) * kLanes;
                const Lane n1 = ConstLaneMap(n + kLanes), n2 = ConstLaneMap(n + 2 * kLanes);
                const Lane r = w[2][0] * ConstLaneMap(n) + w[2][1] * n1 + w[2][2] * n2;
                const Lane r2 = w[2][1] * n1 + (T(2) * w[2][2]) * n2;
                S1 += w[1][i1] * r;
                if (i1 > 0) M1 += (T(i1) * w[1][i1]) * r;
                M2 += w[1][i1] * r2;
              }
              S += w[0][i0] * S1;
              if (i0 > 0) M[0] += (T(i0) * w[0][i0]) * S1;
              M[1] += w[0][i0] * M1;
              M[2] += w[0][i0] * M2;
            }
          }
          for (int b = 0; b < D; ++b) {  // column b of C, as a lane vector
            const Lane Cb = ((M[b] - f[b] * S) * dx) * cscale;
            for (int a = 0; a < D; ++a) bC[a * D + b][j] = Cb[a];
          }
          for (int a = 0; a < D; ++a) bv[a][j] = S[a];
          if constexpr (kFlipChannels > 0)
            for (int a = 0; a < D; ++a) bv[a][j] = mpm::flip_velocity(S[a], v_[a][b0 + j], S[D + 3 + a], flip);
          bJg[j] = S[D];
          bFg[j] = S[D + 1];
          bws[j] = S[D + 2];
        }
        // The strain update and the move (mpm::g2p_particle's first steps), across the batch.
        alignas(64) T bx[D][kBatch], be[kBatch], bej[kBatch], bvol[kBatch];
        for (int d = 0; d < D; ++d) copy_batch<kBatch>(x_[d].data() + b0, nb, bx[d]);
        copy_batch<kBatch>(e_.data() + b0, nb, be);
        copy_batch<kBatch>(vol_.data() + b0, nb, bvol);
        for (int j = 0; j < nb; ++j) {
          T xp[D], Cn[D * D];
          for (int d = 0; d < D; ++d) xp[d] = bx[d][j];
          for (int k = 0; k < D * D; ++k) Cn[k] = bC[k][j];
          be[j] = mpm::g2p_strain<D>(g2p_k, bJg[j], bFg[j], bws[j], be[j], xp, Cn, bej[j]);
          for (int d = 0; d < D; ++d) bx[d][j] = xp[d] + dt * bv[d][j];
        }
        // The rare branches, one particle at a time.
        for (int j = 0; j < nb; ++j)
          if (be[j] != bej[j]) fill_work += mpm::constraint_work<D>(g2p_k, bvol[j], bej[j], be[j]);
        if (has_sym_)
          for (int j = 0; j < nb; ++j) {
            if (!mpm::symmetry_beyond(sym_, bx[sym_.axis][j])) continue;  // most particles: nothing to copy
            T xp[D], vn[D], Cn[D * D];
            for (int d = 0; d < D; ++d) {
              xp[d] = bx[d][j];
              vn[d] = bv[d][j];
            }
            for (int k = 0; k < D * D; ++k) Cn[k] = bC[k][j];
            mpm::symmetry_reflect_particle<D>(sym_, xp, vn, Cn);  // carried across: its image instead
            for (int d = 0; d < D; ++d) {
              bx[d][j] = xp[d];
              bv[d][j] = vn[d];
            }
            for (int k = 0; k < D * D; ++k) bC[k][j] = Cn[k];
          }
        for (int d = 0; d < D; ++d) {
          copy_batch<kBatch>(bx[d], nb, x_[d].data() + b0);
          copy_batch<kBatch>(bv[d], nb, v_[d].data() + b0);
        }
        for (int k = 0; k < D * D; ++k) copy_batch<kBatch>(bC[k], nb, C_[k].data() + b0);
        copy_batch<kBatch>(be, nb, e_.data() + b0);
        if (near_debris) {
          for (int j = 0; j < nb; ++j) debris_->push_out(x_, v_, rho_ * double(bvol[j]), b0 + j, push_slots);
          for (int d = 0; d < D; ++d) {
            copy_batch<kBatch>(x_[d].data() + b0, nb, bx[d]);
            copy_batch<kBatch>(v_[d].data() + b0, nb, bv[d]);
          }
        }
        // The checks and the audit's sums, across the batch: per block in T (the audit's slack is 1 % of the
        // energy scale; a float block sum is good to 1e-6 of it), then in double across blocks. A particle
        // that fails a check stops the run, so the sums need not leave it out.
        alignas(64) int flags[kBatch];  // 1: the particle failed a check; 2: its strain is beyond the series
        for (int j = 0; j < nb; ++j) {
          T v2 = 0, gx = 0;
          // `&` rather than `&&`: short-circuit branches would keep the loop scalar.
          bool ok = std::isfinite(be[j]) & (be[j] > T(-1));
          for (int d = 0; d < D; ++d) {
            const T xn = bx[d][j], vd = bv[d][j];
            ok &= std::isfinite(xn) & std::isfinite(vd) & (xn >= T(lo_ok[d])) & (xn <= T(hi_ok[d]));
            v2 += vd * vd;
            gx += grav[d] * xn;
            xlo_l[d][j] = std::min(xlo_l[d][j], xn);
            xhi_l[d][j] = std::max(xhi_l[d][j], xn);
          }
          const bool series = law.in_series(be[j]);
          flags[j] = (ok ? 0 : 1) | (series ? 0 : 2);
          const T V = bvol[j];
          vmax2_l[j] = std::max(vmax2_l[j], v2);
          ke_l[j] += V * v2;
          pe_l[j] -= V * gx;
          const T w = law.energy_series(be[j]);  // formed for every particle, kept where it holds
          el_l[j] += V * (series ? w : T(0));
        }
        int any = 0;
        for (int j = 0; j < nb; ++j) any |= flags[j];
        if (any & 2)  // strains beyond the series' reach: the exact law
          for (int j = 0; j < nb; ++j)
            if (!law.in_series(be[j])) el_l[j] += bvol[j] * law.energy_exact(be[j]);
        if (any & 1)
          for (int j = 0; j < nb; ++j) {
            bool finite = std::isfinite(be[j]) && be[j] > T(-1), inside = true;
            for (int d = 0; d < D; ++d) {
              finite &= std::isfinite(bx[d][j]) && std::isfinite(bv[d][j]);
              inside &= bx[d][j] >= T(lo_ok[d]) && bx[d][j] <= T(hi_ok[d]);
            }
            if (finite && inside) continue;
            const long i = static_cast<long>(b0) + j;
#pragma omp critical(flume_bad_particle)
            if (i < bad) {
              bad = i;
              bad_kind = finite ? 2 : 1;
            }
            break;
          }
      }
      // The block's stencil bases: the stencil base is a non-decreasing function of the position, so the
      // extreme positions give the extreme bases. A particle drifted out of the tile margin: re-sort before
      // the next scatter. Otherwise they give the next P2G its tile box.
      int base_lo[D], base_hi[D];
      for (int d = 0; d < D; ++d) {
        T xlo = std::numeric_limits<T>::max(), xhi = std::numeric_limits<T>::lowest(), f;
        for (int j = 0; j < kBatch; ++j) {
          xlo = std::min(xlo, xlo_l[d][j]);
          xhi = std::max(xhi, xhi_l[d][j]);
        }
        base_lo[d] = mpm::stencil_base((xlo - lo_grid[d]) * inv_dx, f);
        base_hi[d] = mpm::stencil_base((xhi - lo_grid[d]) * inv_dx, f);
        resort |= base_lo[d] - origin[d] < 0 || base_hi[d] - origin[d] > kBlock + 1;
      }
      tile_box_[p] = mpm::tile_box_of_bases<D>(blk, base_lo, base_hi);  // this block's fetch is done
      T vmax2_b = 0, ke_b = 0, pe_b = 0, el_b = 0;
      for (int j = 0; j < kBatch; ++j) {
        vmax2_b = std::max(vmax2_b, vmax2_l[j]);
        ke_b += ke_l[j];
        pe_b += pe_l[j];
        el_b += el_l[j];
      }
      vmax2 = std::max(vmax2, double(vmax2_b));
      ke += 0.5 * rho * double(ke_b);
      pe += rho * double(pe_b);
      el += double(el_b);
    }
  if (debris_) debris_->end_g2p(nblocks);  // the pushed-out particles' momentum to the boxes
  run_.max_speed = std::sqrt(vmax2);
  needs_sort_ = resort;
  boxes_current_ = true;  // a sort (resort) resets it
  // The volume constraint (mpm::fill_correction) does work on the water that the audit cannot otherwise
  // see: it restores the elastic energy of water that crowded without compressing. What it adds is counted
  // as supplied energy; what it removes (lowering J of water in tension) is dissipation and is not
  // (crediting it hid an energy rise at a dam-break front: docs/solver.md).
  run_.energy0 += fill_work;
  const double t_new = run_.time + double(dt);
  if (bad != std::numeric_limits<long>::max()) {
    double xp[D];
    for (int d = 0; d < D; ++d) xp[d] = x_[d][bad];
    fail(mpm::bad_particle_message(bad_kind, t_new, run_.steps + 1, double(dt), bad, xp, D));
    return;
  }
  const double e_debris = debris_ ? debris_->bodies().energy() : 0.0;
  const double e = ke + pe + el + e_debris;
  if (e > run_.energy0 + run_.energy_slack)
    fail(mpm::energy_growth_message<D>(t_new, run_.steps + 1, e, run_.energy0, run_.max_speed, x_, v_, n_));
  run_.last_energy = {ke, pe, el, e_debris};
}

#define FLUME_INSTANTIATE(D, T, Flip) template void MpmSolver<D, T, Flip>::g2p(T);
FLUME_MPM_SOLVER_VARIANTS(FLUME_INSTANTIATE)
#undef FLUME_INSTANTIATE

}  // namespace flume::mpm
