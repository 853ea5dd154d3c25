// The CPU backend's sparse block grid. Particles are kept sorted by the grid block that holds their stencil's
// base node; only grid blocks within one block of a particle block exist, so memory and work follow the
// water, not the domain box. A particle may drift up to one cell from the block it was sorted into before a
// re-sort is needed, which is what a tile's margin allows for (solver/mpm/tiles.h).
//
// BlockGrid holds the block each particle was last sorted into, the particle blocks with their particle
// ranges, the grid blocks, each block's neighbours in the other list, and the walls that can reach each grid
// block. GridNodes: the grid blocks' node arrays, kBlock^D nodes per block in gkeys' order.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "solver/block_sort.h"
#include "solver/inflow.h"
#include "solver/mpm/node_k.h"
#include "solver/mpm_kernels.h"

namespace flume::mpm {

template <int D, typename T>
class BlockGrid {
 public:
  static constexpr int kNbr = Pow<D>::of(3);  // a block's neighbourhood, itself included

  // Bins the particles by the block of their stencil's base node (a stable sort: particles of one block keep
  // their order), permuting every particle array, then rebuilds the lists (build).
  void sort(const ParticleArrays<D, T>& particles, size_t n, const double* grid_lo, T inv_dx, double dx,
            const std::vector<Wall<D, T>>& walls);
  // The lists from the particles' block keys (key, in particle order) as the last sort assigned them: also
  // after a checkpoint is loaded, which restores the keys.
  void build(size_t n, const double* grid_lo, double dx, const std::vector<Wall<D, T>>& walls);
  size_t bytes() const;

  // Per particle: the block it was last sorted into. Between sorts a particle may drift into the next block's
  // tile margin, so its block is not a function of its position (checkpointed).
  std::vector<uint64_t> key;
  std::vector<uint64_t> pkeys, gkeys;  // particle blocks, grid blocks (sorted keys)
  std::vector<uint32_t> pstart;        // particle block p holds particles [pstart[p], pstart[p + 1])
  std::vector<int32_t> p_nbr,
      g_nbr;  // per block, kNbr entries: the neighbour's index in the other list, or -1
  std::vector<uint32_t>
      g_bnd_start;  // grid block g may meet the walls g_bnd[g_bnd_start[g] .. g_bnd_start[g + 1])
  std::vector<int32_t> g_bnd;

 private:
  // The sort's work arrays persist between sorts: fresh ones each time cost a page fault per 4 kB touched.
  std::vector<uint64_t> key_scratch_;
  std::vector<uint32_t> order_;
  BlockSortWork work_;
  std::vector<T> scratch_;
};

template <int D, typename T>
struct GridNodes {
  std::vector<T> m, v[D], vold[D], e,
      fill;  // e: mass-weighted strain J - 1 over mass; fill: particle volume per cell volume; vold: FLIP's
             // old velocity (empty where the solver's lanes do not carry it)
  std::vector<uint8_t> wall;  // the axes along which a wall or a box holds the node (mpm::apply_boundaries)
  void resize(size_t nodes, bool old_velocity = false) {
    m.resize(nodes);
    e.resize(nodes);
    fill.resize(nodes);
    wall.resize(nodes);
    for (int d = 0; d < D; ++d) v[d].resize(nodes);
    if (old_velocity)
      for (int d = 0; d < D; ++d) vold[d].resize(nodes);
  }
  void clear(size_t i) {  // a node without water
    m[i] = e[i] = fill[i] = T(0);
    wall[i] = 0;
    for (int d = 0; d < D; ++d) v[d][i] = T(0);
    if (!vold[0].empty())
      for (int d = 0; d < D; ++d) vold[d][i] = T(0);
  }
  size_t bytes() const {  // the value arrays (the wall flags are not counted)
    size_t b = (m.capacity() + e.capacity() + fill.capacity()) * sizeof(T);
    for (int d = 0; d < D; ++d) b += (v[d].capacity() + vold[d].capacity()) * sizeof(T);
    return b;
  }
};

}  // namespace flume::mpm
