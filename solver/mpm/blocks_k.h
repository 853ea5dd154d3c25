// Block keys of the sparse grid, for both backends: particles are sorted by the key of the grid block
// (kBlock^D nodes) holding their stencil's base node, and the active grid blocks are the 3^D neighbourhoods
// of those.
#pragma once
#include <cmath>
#include <cstdint>

#include "solver/mpm_kernels.h"

namespace flume::mpm {

// 21 bits per axis, the last axis least significant: blocks sort along the last axis first, so that a block's
// neighbours along it are adjacent in memory. Block indices are non-negative: the grid is padded below the
// domain.
template <int D>
FLUME_HD uint64_t pack_key(const int* b) {
  uint64_t k = 0;
  for (int d = 0; d < D; ++d) k = (k << 21) | static_cast<uint64_t>(b[d] & 0x1FFFFF);
  return k;
}
template <int D>
FLUME_HD void unpack_key(uint64_t k, int* b) {
  for (int d = D - 1; d >= 0; --d) {
    b[d] = static_cast<int>(k & 0x1FFFFF);
    k >>= 21;
  }
}

// The o-th of the 3^D neighbours of block b (offsets -1, 0, +1 per axis, last axis fastest).
template <int D>
FLUME_HD void neighbour_block(const int* b, int o, int* nb) {
  for (int d = D - 1; d >= 0; --d) {
    nb[d] = b[d] + (o % 3) - 1;
    o /= 3;
  }
}

// The key of the block holding the stencil's base node of a particle at x (x_grid = (x - grid_lo) / dx per
// axis).
template <int D, typename T>
FLUME_HD uint64_t particle_block_key(const T* x_grid) {
  int b[D];
  for (int d = 0; d < D; ++d) {
    const int node = static_cast<int>(std::floor(x_grid[d] - T(0.5)));
    b[d] = node >= 0 ? node / kBlock : 0;
  }
  return pack_key<D>(b);
}

// Storage index (block * kBlock^D + local node) of a node (global node coordinates) in a grid of `nblocks`
// blocks with sorted keys, found by binary search; -1 where no block holds it.
template <int D>
FLUME_HD int64_t node_index(const uint64_t* keys, size_t nblocks, const int* node) {
  int blk[D], local = 0;
  for (int d = 0; d < D; ++d) {
    if (node[d] < 0) return -1;
    blk[d] = node[d] / kBlock;
    local = local * kBlock + node[d] % kBlock;
  }
  const uint64_t key = pack_key<D>(blk);
  size_t lo = 0, hi = nblocks;
  while (lo < hi) {
    const size_t mid = (lo + hi) / 2;
    if (keys[mid] < key)
      lo = mid + 1;
    else
      hi = mid;
  }
  if (lo == nblocks || keys[lo] != key) return -1;
  return static_cast<int64_t>(lo * Pow<D>::of(kBlock) + local);
}

}  // namespace flume::mpm
