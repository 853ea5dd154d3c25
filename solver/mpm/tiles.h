// The CPU backend's race-free scatter: each particle block scatters (P2G) into its own tile of kTile^D nodes,
// a private buffer no other thread touches; each grid block then gathers the overlapping parts of the tiles
// of its 3^D neighbouring particle blocks in a fixed order. No atomics, and the result does not depend on the
// number of threads. Here: where a tile node lies in the grid, and which part of a tile a block's particles
// reach.
#pragma once
#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#include "solver/mpm_kernels.h"

namespace flume::mpm {

// For each node of a particle block's tile: which of the 3^D neighbouring grid blocks holds it, and where.
struct TileNode {
  int block, local;
};

// A particle block's tile box: the tile nodes its particles' stencils reach, [lo, hi) per axis (tile_box).
template <int D>
struct TileBox {
  int lo[D], hi[D];
};

template <int D>
std::vector<TileNode> make_tile_map() {
  constexpr int kTileNodes = Pow<D>::of(kTile);
  std::vector<TileNode> map(kTileNodes);
  for (int a = 0; a < kTileNodes; ++a) {
    int o = 0, local = 0;
    for (int d = D - 1, r = a, stride = 1, lstride = 1; d >= 0; --d, r /= kTile) {
      const int ad = r % kTile;
      const int bo = ad == 0 ? -1 : (ad <= kBlock ? 0 : 1);  // tile index 0 lies in the block below
      o += (bo + 1) * stride;
      local += (ad - 1 - kBlock * bo) * lstride;
      stride *= 3;
      lstride *= kBlock;
    }
    map[a] = {o, local};
  }
  return map;
}

// The lowest and highest stencil base node, per axis, of the particles [begin, end) (x: D arrays of
// positions): the base is a non-decreasing function of the position (every rounding in stencil_base is), so
// those of the extreme positions are the extremes, found by a min/max reduction that vectorises instead of
// a floor per particle and axis. An empty range gives lo > hi.
template <int D, typename T>
void stencil_base_range(const T* const* x, uint32_t begin, uint32_t end, const T* lo_grid, T inv_dx, int* lo,
                        int* hi) {
  for (int d = 0; d < D; ++d) {
    const T* xd = x[d];
    T xmin = std::numeric_limits<T>::max(), xmax = std::numeric_limits<T>::lowest();
#pragma omp simd reduction(min : xmin) reduction(max : xmax)
    for (uint32_t i = begin; i < end; ++i) {
      xmin = std::min(xmin, xd[i]);
      xmax = std::max(xmax, xd[i]);
    }
    if (begin >= end) {
      lo[d] = 1;
      hi[d] = 0;
      continue;
    }
    T f;
    lo[d] = stencil_base((xmin - lo_grid[d]) * inv_dx, f);
    hi[d] = stencil_base((xmax - lo_grid[d]) * inv_dx, f);
  }
}

// The tile nodes reached by the stencils of particles in block `blk` whose base nodes lie in [lo, hi] per
// axis (lo > hi on an axis: none).
template <int D>
TileBox<D> tile_box_of_bases(const int* blk, const int* lo, const int* hi) {
  TileBox<D> box;
  bool empty = false;
  for (int d = 0; d < D; ++d) empty |= lo[d] > hi[d];
  for (int d = 0; d < D; ++d) {
    const int origin = blk[d] * kBlock - 1;
    const int first = empty ? kTile : lo[d] - origin, last = empty ? 0 : hi[d] - origin + 3;
    box.lo[d] = std::max(0, first);
    box.hi[d] = std::min(kTile, std::max(last, box.lo[d]));
  }
  return box;
}

// The tile nodes that the particles [begin, end) of block `blk` reach: the union of their 3^D stencils, [lo,
// hi) per axis in tile coordinates. P2G zeroes and fills only these, the grid gather adds only these (the
// rest of the tile would add exact zeros) and G2P fetches only these from the grid: a block of a thin sheet
// (a flow one or two cells deep) reaches a third of its tile, a full block two thirds of it (a particle sits
// up to a cell outside its block, so the tile is kBlock + 4 wide). x: D arrays of positions.
template <int D, typename T>
TileBox<D> tile_box(const int* blk, const T* const* x, uint32_t begin, uint32_t end, const T* lo_grid,
                    T inv_dx) {
  int lo[D], hi[D];
  stencil_base_range<D>(x, begin, end, lo_grid, inv_dx, lo, hi);
  return tile_box_of_bases<D>(blk, lo, hi);
}

// Calls row(a, len) for each row of the box along the last axis: its first tile node and its length.
template <int D, typename Row>
void for_each_box_row(const TileBox<D>& box, Row&& row) {
  const int len = box.hi[D - 1] - box.lo[D - 1];
  if constexpr (D == 2) {
    for (int a0 = box.lo[0]; a0 < box.hi[0]; ++a0) row(a0 * kTile + box.lo[1], len);
  } else {
    for (int a0 = box.lo[0]; a0 < box.hi[0]; ++a0)
      for (int a1 = box.lo[1]; a1 < box.hi[1]; ++a1) row((a0 * kTile + a1) * kTile + box.lo[2], len);
  }
}

}  // namespace flume::mpm
