// GhostReflection::reflect (solver/mpm/cpu_ghosts.h).
#include "solver/mpm/cpu_ghosts.h"

#include <algorithm>

#include "solver/mpm/cpu_variants.h"
#include "solver/mpm/symmetry_zone.h"
#include "solver/mpm_kernels.h"

namespace flume::mpm {

template <int D, typename T>
void GhostReflection<D, T>::reflect(GridNodes<D, T>& grid, const std::vector<uint64_t>& gkeys,
                                    std::vector<double>& load_impulse) {
  // Each thread's list is in node order already (a thread works through its shares of the grid blocks in
  // increasing order), so merging the lists suffices.
  all_.clear();
  const auto by_node = [](const Ghost<D, T>& a, const Ghost<D, T>& b) { return a.idx < b.idx; };
  for (const auto& tl : ghosts_) {
    const auto& list = tl.list;
    const auto mid = static_cast<std::ptrdiff_t>(all_.size());
    all_.insert(all_.end(), list.begin(), list.end());
    std::inplace_merge(all_.begin(), all_.begin() + mid, all_.end(), by_node);
  }
  if (!std::is_sorted(all_.begin(), all_.end(), by_node))  // a schedule that does not keep the order
    std::sort(all_.begin(), all_.end(), by_node);
  // The exchanges in parallel (each writes its own ghost and its own entry), the mirrors' changes in order.
  const long count = static_cast<long>(all_.size());
  mirror_dv_.resize(all_.size());
#pragma omp parallel for schedule(static)
  for (long q = 0; q < count; ++q) {
    const Ghost<D, T>& gh = all_[q];
    MirrorChange& c = mirror_dv_[q];
    c.node = kNoMirror;
    const long gi = grid_index<D>(gkeys, gh.offset);
    if (gi < 0) continue;
    const size_t mi = static_cast<size_t>(gi);
    if (grid.m[mi] <= T(0) || grid.wall[mi]) continue;
    T vg[D], vm[D], dvg[D];
    for (int d = 0; d < D; ++d) {
      vg[d] = grid.v[d][gh.idx];
      vm[d] = grid.v[d][mi];
    }
    ghost_exchange<D>(vg, gh.vpre, grid.m[gh.idx], vm, grid.m[mi], gh.axes, push_axes_, dvg, c.dv);
    for (int d = 0; d < D; ++d)
      grid.v[d][gh.idx] += dvg[d];  // ghosts are never mirrors: no exchange reads it
    c.node = mi;
  }
  // The mirrors' changes in ghost order; the normal part of each (the image's push) is the wall's load.
  for (size_t q = 0; q < mirror_dv_.size(); ++q) {
    const MirrorChange& c = mirror_dv_[q];
    if (c.node == kNoMirror) continue;
    const Ghost<D, T>& gh = all_[q];
    for (int d = 0; d < D; ++d) {
      grid.v[d][c.node] += c.dv[d];
      if (gh.wall >= 0 && (gh.axes & (1u << d)))
        load_impulse[static_cast<size_t>(gh.wall) * D + d] -=
            gh.load_weight * double(grid.m[c.node]) * double(c.dv[d]);
    }
  }
}

#define FLUME_INSTANTIATE(D, T) template class GhostReflection<D, T>;
FLUME_MPM_CPU_VARIANTS(FLUME_INSTANTIATE)
#undef FLUME_INSTANTIATE

}  // namespace flume::mpm
