// MpmSolver::grid_update (solver/mpm/cpu_solver.h): each grid block gathers its neighbours' tiles in a fixed
// order, then every node is updated (mpm::apply_boundaries, solver/mpm/node_k.h, shared with the CUDA
// backend); nodes near a symmetry plane are stored raw and folded first. Then the ghosts, the symmetry mirror
// and the debris exchange.
#include <omp.h>

#include <algorithm>
#include <cmath>

#include "solver/mpm/cpu_solver.h"

namespace flume::mpm {

// One grid node from what the particles gave it (its lanes `acc`): momentum to velocity, gravity, the walls
// (their loads weighted by `load_weight`), its ghost pairing and the debris coupling.
template <int D, typename T, bool Flip>
void MpmSolver<D, T, Flip>::update_node(const Lane& acc, long g, size_t idx, const int* node,
                                        bool near_debris, double load_weight, T dt, T inv_cell_volume,
                                        double* my_impulse, std::vector<ProbeHit>* my_probe_hits,
                                        std::vector<CouplingNode>* my_coupling,
                                        std::vector<Ghost<D, T>>* my_ghosts) {
  const T m = acc[0];
  if (m <= T(0)) {
    grid_.clear(idx);
    return;
  }
  T v[D];
  for (int d = 0; d < D; ++d) v[d] = acc[1 + d] / m + dt * gravity_[d];
  // The ghost's image reflects the particles' momentum only, not gravity's (mpm::ghost_exchange).
  Ghost<D, T> ghost;
  for (int d = 0; d < D; ++d) ghost.vpre[d] = acc[1 + d] / m;
  double xn[D];
  for (int d = 0; d < D; ++d) xn[d] = mpm::node_coordinate(grid_lo_[d], node[d], dx_);
  mpm::GhostSearch<D> found;
  T v_free[D];
  for (int d = 0; d < D; ++d) v_free[d] = v[d];
  uint8_t held = mpm::apply_boundaries<D>(
      xn, m, v, dt, load_weight, dx_, subcell_rate0_, walls_.data(),
      blocks_.g_bnd.data() + blocks_.g_bnd_start[g],
      static_cast<int>(blocks_.g_bnd_start[g + 1] - blocks_.g_bnd_start[g]), container_, my_impulse, found);
  if (probe_faces_.count > 0) {  // only nodes a wall acted on push
    ProbeHit hit{idx, {}, {}};
    for (int d = 0; d < D; ++d) hit.x[d] = xn[d];
    if (mpm::node_wall_push<D>(load_weight, m, v, v_free, hit.push) && within_probe_reach(xn))
      my_probe_hits->push_back(hit);
  }
  if (found.found()) {
    ghost.idx = idx;
    ghost.load_weight = load_weight;
    ghost.axes = found.axes;
    ghost.wall = found.wall;
    for (int d = 0; d < D; ++d) ghost.x[d] = xn[d];
    for (int d = 0; d < D; ++d) ghost.offset[d] = found.offset[d] + node[d];  // the mirror node itself
    my_ghosts->push_back(ghost);
  }
  // Debris: the node is a moving-wall node of the box it lies in (CpuDebris::add_node).
  if (near_debris &&
      debris_->add_node(xn, dx_, idx, m, acc[1 + D] / m, v, law_d_, strain_slope_, my_coupling))
    held = mpm::all_axes<D>();
  grid_.m[idx] = m;
  grid_.e[idx] = acc[1 + D] / m;
  grid_.fill[idx] = acc[2 + D] * inv_cell_volume;
  grid_.wall[idx] = held;
  for (int d = 0; d < D; ++d) grid_.v[d][idx] = v[d];
  if constexpr (kFlipChannels > 0)
    for (int d = 0; d < D; ++d) grid_.vold[d][idx] = acc[D + 3 + d] / m;
}

// Gathers the tiles into the grid blocks, then turns momentum into velocity, adds gravity and applies the
// boundary conditions. Load cells sum the impulse the boundary gives the water at its nodes.
template <int D, typename T, bool Flip>
void MpmSolver<D, T, Flip>::grid_update(T dt) {
  const T inv_cell_volume = T(1) / T(std::pow(dx_, D));
  const int nthreads = omp_get_max_threads();
  // A cache line (8 doubles) between one thread's load sums and the next's, wherever the buffer starts: a
  // shared line costs a transfer per wall node.
  const size_t stride = walls_.size() * D + 8;
  std::vector<double> impulse(static_cast<size_t>(nthreads) * stride, 0.0);
  probe_hits_.resize(static_cast<size_t>(nthreads));
  if (debris_) debris_->begin_grid(nthreads);
  ghosts_.begin(nthreads);
#pragma omp parallel
  {
    double* my_impulse = impulse.data() + static_cast<size_t>(omp_get_thread_num()) * stride;
    std::vector<ProbeHit>* my_probe_hits = &probe_hits_[omp_get_thread_num()];
    my_probe_hits->clear();
    std::vector<CouplingNode>* my_coupling = debris_ ? debris_->thread_nodes(omp_get_thread_num()) : nullptr;
    std::vector<Ghost<D, T>>* my_ghosts = ghosts_.thread_list(omp_get_thread_num());
    my_ghosts->clear();
    const int nshares = shares_.count();
#pragma omp for schedule(static, 1)
    for (int s = 0; s < nshares; ++s)
      for (long g = shares_.gfirst[s]; g < shares_.gfirst[s + 1]; ++g) {
        Lane acc[kNodes];
        for (int k = 0; k < kNodes; ++k) acc[k] = Lane::Zero();
        for (int o = 0; o < kNbr; ++o) {
          const int32_t p = blocks_.g_nbr[g * kNbr + o];
          if (p < 0) continue;
          // Block offset of the particle block relative to this grid block, per axis.
          int off[D];
          for (int d = D - 1, r = o; d >= 0; --d, r /= 3) off[d] = -((r % 3) - 1);
          // Local node l of this block is tile node a = l + 1 + kBlock * off on each axis.
          int lo[D], hi[D];
          const TileBox& box = tile_box_[p];
          bool empty = false;
          for (int d = 0; d < D; ++d) {
            const int shift = 1 + kBlock * off[d];
            lo[d] = std::max(0, box.lo[d] - shift);
            hi[d] = std::min(kBlock, box.hi[d] - shift);
            empty |= lo[d] >= hi[d];
          }
          if (empty) continue;
          const T* tile = &tiles_[static_cast<size_t>(p) * kLanes * kTileNodes];
          if constexpr (D == 2) {
            for (int l0 = lo[0]; l0 < hi[0]; ++l0)
              for (int l1 = lo[1]; l1 < hi[1]; ++l1) {
                const int a = (l0 + 1 + kBlock * off[0]) * kTile + l1 + 1 + kBlock * off[1];
                acc[l0 * kBlock + l1] += ConstLaneMap(tile + a * kLanes);
              }
          } else {
            for (int l0 = lo[0]; l0 < hi[0]; ++l0)
              for (int l1 = lo[1]; l1 < hi[1]; ++l1)
                for (int l2 = lo[2]; l2 < hi[2]; ++l2) {
                  const int a = ((l0 + 1 + kBlock * off[0]) * kTile + l1 + 1 + kBlock * off[1]) * kTile + l2 +
                                1 + kBlock * off[2];
                  acc[(l0 * kBlock + l1) * kBlock + l2] += ConstLaneMap(tile + a * kLanes);
                }
          }
        }
        int blk[D];
        unpack_key<D>(blocks_.gkeys[g], blk);
        const size_t base = static_cast<size_t>(g) * kNodes;
        const bool near_debris = debris_ && debris_->near_grid_block(blk, grid_lo_, dx_);
        const int slot = has_sym_ ? zone_.slot(g) : -1;
        for (int k = 0; k < kNodes; ++k) {
          int node[D];
          for (int d = D - 1, r = k; d >= 0; --d, r /= kBlock) node[d] = blk[d] * kBlock + r % kBlock;
          if (slot >= 0 && zone_.in_zone(node[sym_.axis])) {  // folded across the plane first, updated after
            sym_acc_[static_cast<size_t>(slot) * kNodes + k] = acc[k];
            continue;
          }
          update_node(acc[k], g, base + k, node, near_debris, 1.0, dt, inv_cell_volume, my_impulse,
                      my_probe_hits, my_coupling, my_ghosts);
        }
      }
    if (has_sym_) {
      // After the barrier every raw node near the plane is stored. The nodes on the modelled side and on the
      // plane take their fold (what the whole would give them) and are updated; a load on the plane is half
      // the whole's. Each reads its own entry and its mirror's beyond the plane, which nobody writes.
      Lane sign;
      for (int c = 0; c < kLanes; ++c) sign[c] = T(mpm::symmetry_channel_sign<D>(sym_, c));
      const long nq = static_cast<long>(zone_.entries());
#pragma omp for schedule(static)
      for (long q = 0; q < nq; ++q) {
        int node[D];
        const long g = zone_.node(q, blocks_.gkeys, node);
        const int k = static_cast<int>(q % kNodes);
        if (!zone_.in_zone(node[sym_.axis])) continue;  // updated in the loop above
        const int side = mpm::symmetry_side(sym_, node[sym_.axis]);
        if (side > 0) continue;  // beyond: mirrored after the walls (mirror_beyond_symmetry)
        Lane a = sym_acc_[q];
        if (side == 0) {
          a += sign * a;
        } else {
          const long m = zone_.mirror_entry(node, blocks_.gkeys);
          if (m >= 0) a += sign * sym_acc_[m];
        }
        // No debris near: a scene with a symmetry plane has none (setup_boundaries).
        update_node(a, g, static_cast<size_t>(g) * kNodes + k, node, false, side == 0 ? 0.5 : 1.0, dt,
                    inv_cell_volume, my_impulse, my_probe_hits, my_coupling, my_ghosts);
      }
    }
  }
  std::fill(load_impulse_.begin(), load_impulse_.end(), 0.0);
  for (int t = 0; t < nthreads; ++t)
    for (size_t k = 0; k < load_impulse_.size(); ++k) load_impulse_[k] += impulse[t * stride + k];
  std::fill(probe_push_.begin(), probe_push_.end(), 0.0);
  if (!probe_push_.empty()) {
    std::vector<ProbeHit> hits;
    for (const auto& list : probe_hits_) hits.insert(hits.end(), list.begin(), list.end());
    std::sort(hits.begin(), hits.end(), [](const ProbeHit& a, const ProbeHit& b) { return a.idx < b.idx; });
    for (const ProbeHit& h : hits) mpm::add_probe_push<D>(probe_faces_, h.x, h.push, probe_push_.data());
  }
  ghosts_.reflect(grid_, blocks_.gkeys, load_impulse_, probe_faces_, probe_push_);
  if (has_sym_) mirror_beyond_symmetry();
  if (debris_) debris_->couple(grid_.v, double(dt));
}

#define FLUME_INSTANTIATE(D, T, Flip)                                                                      \
  template void MpmSolver<D, T, Flip>::update_node(const Lane&, long, size_t, const int*, bool, double, T, \
                                                   T, double*,                                             \
                                                   std::vector<typename MpmSolver<D, T, Flip>::ProbeHit>*, \
                                                   std::vector<CouplingNode>*, std::vector<Ghost<D, T>>*); \
  template void MpmSolver<D, T, Flip>::grid_update(T);
FLUME_MPM_SOLVER_VARIANTS(FLUME_INSTANTIATE)
#undef FLUME_INSTANTIATE

}  // namespace flume::mpm
