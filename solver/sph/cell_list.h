// Neighbour search by cell lists: cells about h wide, particles ordered by cell (x fastest), so the particles
// of a row of cells along x are one contiguous range and a neighbourhood of 2h is at most 5^(D-1) ranges,
// each trimmed to the cells the support reaches in its row. Rebuilt once per step by a counting sort; within
// the step particles drift less than the search radius' margin over 2h.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace flume::sph {

template <int D>
struct CellGrid {
  double lo[D] = {};
  double size = 0, inv_size = 0;
  int n[D] = {};
  std::size_t count = 0;

  // Cells of `size` covering [lo, hi]. Returns false when there would be more than max_cells.
  bool init(const double* box_lo, const double* box_hi, double cell_size, std::size_t max_cells) {
    size = cell_size;
    inv_size = 1.0 / cell_size;
    double total = 1;
    for (int d = 0; d < D; ++d) {
      lo[d] = box_lo[d];
      const double k = std::ceil((box_hi[d] - box_lo[d]) * inv_size) + 1;
      total *= k;
      n[d] = static_cast<int>(std::min(k, 2e9));
    }
    if (total > double(max_cells)) return false;
    count = static_cast<std::size_t>(total);
    return true;
  }
  // The cell of a point, or false outside the grid.
  template <typename T>
  bool cell_of(const T* x, int* c) const {
    for (int d = 0; d < D; ++d) {
      const double f = std::floor((double(x[d]) - lo[d]) * inv_size);
      if (!(f >= 0 && f < n[d])) return false;
      c[d] = static_cast<int>(f);
    }
    return true;
  }
  std::size_t index(const int* c) const {
    std::size_t k = 0;
    for (int d = D - 1; d >= 0; --d) k = k * n[d] + c[d];
    return k;
  }
};

// Particles of one kind ordered by cell: `start[k]` .. `start[k + 1]` are the particles of cell k.
struct CellList {
  std::vector<uint32_t> start;
  std::vector<uint32_t> cell;   // per particle, before ordering
  std::vector<uint32_t> order;  // sorted position -> original index

  // Counting sort of the particles by their cell (stable: the order within a cell is kept).
  void build(std::size_t cells) {
    start.assign(cells + 1, 0);
    for (uint32_t c : cell) ++start[c + 1];
    for (std::size_t k = 0; k < cells; ++k) start[k + 1] += start[k];
    order.resize(cell.size());
    std::vector<uint32_t> next(start.begin(), start.end() - 1);
    for (uint32_t i = 0; i < cell.size(); ++i) order[next[cell[i]]++] = i;
  }
};

// Calls f(begin, end) for the contiguous ranges of `list`'s particles whose cells come within `radius` of the
// point x: per row of cells along x, only the cells the sphere reaches there (the rows' distance across trims
// it). Rows numbered below `first_row` (row = cell index / n[0]) are skipped: a particle's pairs with the
// particles after it in cell order start at its own row.
template <int D, typename T, class F>
inline void for_each_neighbour_range(const CellGrid<D>& g, const CellList& list, const T* x, double radius,
                                     const F& f, std::size_t first_row = 0) {
  double p[D];
  int lo[D], hi[D];
  for (int d = 0; d < D; ++d) {
    p[d] = (double(x[d]) - g.lo[d]) * g.inv_size;  // in cells
    lo[d] = std::max(0, static_cast<int>(std::floor(p[d] - radius * g.inv_size)));
    hi[d] = std::min(g.n[d] - 1, static_cast<int>(std::floor(p[d] + radius * g.inv_size)));
  }
  const double r2 = radius * radius * g.inv_size * g.inv_size;  // in cells^2
  // The squared distance (cells) across axis d from p to cell k: 0 inside it.
  auto gap2 = [&](int d, int k) {
    const double s = p[d] < k ? k - p[d] : (p[d] > k + 1 ? p[d] - (k + 1) : 0.0);
    return s * s;
  };
  auto row = [&](std::size_t base, double across2) {
    const double rest = r2 - across2;
    if (rest < 0) return;
    const double reach = std::sqrt(rest);
    const int x0 = std::max(lo[0], static_cast<int>(std::floor(p[0] - reach)));
    const int x1 = std::min(hi[0], static_cast<int>(std::floor(p[0] + reach)));
    if (x0 > x1) return;
    const uint32_t b = list.start[base + x0], e = list.start[base + x1 + 1];
    if (b < e) f(b, e);
  };
  if constexpr (D == 2) {
    for (int z = std::max(lo[1], static_cast<int>(first_row)); z <= hi[1]; ++z)
      row(std::size_t(z) * g.n[0], gap2(1, z));
  } else {
    const int z_first = static_cast<int>(first_row / g.n[1]), y_first = static_cast<int>(first_row % g.n[1]);
    for (int z = std::max(lo[2], z_first); z <= hi[2]; ++z) {
      const double gz = gap2(2, z);
      for (int y = z == z_first ? std::max(lo[1], y_first) : lo[1]; y <= hi[1]; ++y)
        row((std::size_t(z) * g.n[1] + y) * g.n[0], gz + gap2(1, y));
    }
  }
}

// Calls f(begin, end) for the contiguous ranges of `list`'s particles in slab s: the cells whose coordinate
// along `axis` lies in [s w, (s + 1) w), row by row in cell order.
template <int D, class F>
inline void for_each_slab_range(const CellGrid<D>& g, const CellList& list, int axis, int w, int s,
                                const F& f) {
  const int c0 = s * w, c1 = std::min(g.n[axis], c0 + w);  // the slab's cells along the axis: [c0, c1)
  if (c0 >= c1) return;
  const int x0 = axis == 0 ? c0 : 0, x1 = axis == 0 ? c1 : g.n[0];
  auto row = [&](std::size_t base) {
    const uint32_t b = list.start[base + x0], e = list.start[base + x1];
    if (b < e) f(b, e);
  };
  if constexpr (D == 2) {
    const int z0 = axis == 1 ? c0 : 0, z1 = axis == 1 ? c1 : g.n[1];
    for (int z = z0; z < z1; ++z) row(std::size_t(z) * g.n[0]);
  } else {
    const int y0 = axis == 1 ? c0 : 0, y1 = axis == 1 ? c1 : g.n[1];
    const int z0 = axis == 2 ? c0 : 0, z1 = axis == 2 ? c1 : g.n[2];
    for (int z = z0; z < z1; ++z)
      for (int y = y0; y < y1; ++y) row((std::size_t(z) * g.n[1] + y) * g.n[0]);
  }
}

}  // namespace flume::sph
