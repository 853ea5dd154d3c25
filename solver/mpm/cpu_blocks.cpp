// BlockGrid (solver/mpm/cpu_blocks.h): the particles' sort by block and the sparse block lists.
#include "solver/mpm/cpu_blocks.h"

#include <algorithm>
#include <cmath>

#include "solver/mpm/blocks_k.h"
#include "solver/mpm/cpu_variants.h"
#include "solver/mpm/launch.h"

namespace flume::mpm {

template <int D, typename T>
void BlockGrid<D, T>::sort(const ParticleArrays<D, T>& particles, size_t n, const double* grid_lo, T inv_dx,
                           double dx, const std::vector<Wall<D, T>>& walls) {
  key.resize(n);
  const std::vector<T>* const* x = particles.x;
  parallel_for(n, [&](size_t i) {
    T xg[D];
    for (int d = 0; d < D; ++d) xg[d] = ((*x[d])[i] - T(grid_lo[d])) * inv_dx;
    key[i] = particle_block_key<D>(xg);
  });
  if (!std::is_sorted(key.begin(), key.end())) {
    std::vector<uint32_t>& order = order_;
    order.resize(n);
    stable_order_by_key(key, order, work_);  // std::stable_sort's order, in parallel (block_sort.h)
    auto permute = [&](std::vector<T>& a) {
      std::vector<T>& tmp = scratch_;
      tmp.resize(n);
#pragma omp parallel for schedule(static)
      for (size_t i = 0; i < n; ++i) tmp[i] = a[order[i]];
      a.swap(tmp);
    };
    for (int d = 0; d < D; ++d) {
      permute(*particles.x[d]);
      permute(*particles.v[d]);
    }
    for (int k = 0; k < D * D; ++k) permute(*particles.C[k]);
    permute(*particles.e);
    permute(*particles.vol);
    if (!particles.held->empty()) permute(*particles.held);
    if (!particles.tag->empty()) permute(*particles.tag);
    std::vector<uint64_t>& sorted = key_scratch_;
    sorted.resize(n);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i) sorted[i] = key[order[i]];
    key.swap(sorted);
  }
  build(n, grid_lo, dx, walls);
}

template <int D, typename T>
void BlockGrid<D, T>::build(size_t n, const double* grid_lo, double dx,
                            const std::vector<Wall<D, T>>& walls) {
  // Particle blocks and their particle ranges.
  pkeys.clear();
  pstart.clear();
  for (size_t i = 0; i < n; ++i)
    if (i == 0 || key[i] != key[i - 1]) {
      pkeys.push_back(key[i]);
      pstart.push_back(static_cast<uint32_t>(i));
    }
  pstart.push_back(static_cast<uint32_t>(n));
  // Grid blocks: the 3^D neighbourhood of every particle block.
  std::vector<uint64_t> g;
  g.reserve(pkeys.size() * kNbr);
  for (uint64_t k : pkeys) {
    int b[D];
    unpack_key<D>(k, b);
    for (int o = 0; o < kNbr; ++o) {
      int nb[D];
      neighbour_block<D>(b, o, nb);
      g.push_back(pack_key<D>(nb));
    }
  }
  std::sort(g.begin(), g.end());
  g.erase(std::unique(g.begin(), g.end()), g.end());
  gkeys.swap(g);
  auto find = [](const std::vector<uint64_t>& v, uint64_t k) -> int32_t {
    auto it = std::lower_bound(v.begin(), v.end(), k);
    return it != v.end() && *it == k ? static_cast<int32_t>(it - v.begin()) : -1;
  };
  // Each block's 3^D neighbours in the other list.
  const auto link = [&](const std::vector<uint64_t>& from, const std::vector<uint64_t>& to,
                        std::vector<int32_t>& nbr) {
    nbr.assign(from.size() * kNbr, -1);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < from.size(); ++i) {
      int b[D];
      unpack_key<D>(from[i], b);
      for (int o = 0; o < kNbr; ++o) {
        int nb[D];
        neighbour_block<D>(b, o, nb);
        nbr[i * kNbr + o] = find(to, pack_key<D>(nb));
      }
    }
  };
  link(pkeys, gkeys, p_nbr);
  link(gkeys, pkeys, g_nbr);
  // Walls that can reach each grid block (so the grid update tests only those): counted per block in
  // parallel, then listed at the blocks' offsets (why not one serial pass: docs/solver.md, "Measurements
  // behind the constants").
  const auto reaches = [&](size_t gi, size_t wi) {
    int b[D];
    unpack_key<D>(gkeys[gi], b);
    T centre[D];
    T half_diag = 0;
    for (int d = 0; d < D; ++d) {
      centre[d] = T(grid_lo[d] + (b[d] * kBlock + 0.5 * (kBlock - 1)) * dx);
      half_diag += T(0.25 * (kBlock * dx) * (kBlock * dx));
    }
    half_diag = std::sqrt(half_diag);
    const Wall<D, T>& w = walls[wi];
    T a[D], bb[D], normal[D];  // in T, as the node update's reach test always took them
    for (int d = 0; d < D; ++d) {
      a[d] = T(w.a[d]);
      bb[d] = T(w.b[d]);
    }
    const T dist =
        w.box ? box_distance<D>(centre, a, bb, normal) : half_space_distance<D>(centre, a, bb, normal);
    return dist <= half_diag + T(dx);
  };
  g_bnd_start.assign(gkeys.size() + 1, 0);
#pragma omp parallel for schedule(static)
  for (size_t gi = 0; gi < gkeys.size(); ++gi) {
    uint32_t count = 0;
    for (size_t w = 0; w < walls.size(); ++w) count += reaches(gi, w);
    g_bnd_start[gi + 1] = count;
  }
  for (size_t gi = 0; gi < gkeys.size(); ++gi) g_bnd_start[gi + 1] += g_bnd_start[gi];
  g_bnd.resize(g_bnd_start.back());
#pragma omp parallel for schedule(static)
  for (size_t gi = 0; gi < gkeys.size(); ++gi) {
    uint32_t q = g_bnd_start[gi];
    for (size_t w = 0; w < walls.size(); ++w)
      if (reaches(gi, w)) g_bnd[q++] = static_cast<int32_t>(w);
  }
}

template <int D, typename T>
size_t BlockGrid<D, T>::bytes() const {
  return (gkeys.capacity() + pkeys.capacity()) * sizeof(uint64_t) +
         (p_nbr.capacity() + g_nbr.capacity() + g_bnd.capacity()) * sizeof(int32_t);
}

#define FLUME_INSTANTIATE(D, T) template class BlockGrid<D, T>;
FLUME_MPM_CPU_VARIANTS(FLUME_INSTANTIATE)
#undef FLUME_INSTANTIATE

}  // namespace flume::mpm
