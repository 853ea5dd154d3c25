// GhostReflection::reflect (solver/mpm/cpu_ghosts.h).
#include "solver/mpm/cpu_ghosts.h"

#include <algorithm>

#include "solver/mpm/cpu_variants.h"
#include "solver/mpm/symmetry_zone.h"
#include "solver/mpm_kernels.h"

namespace flume::mpm {

template <int D, typename T>
void GhostReflection<D, T>::reflect(GridNodes<D, T>& grid, const std::vector<uint64_t>& gkeys,
                                    std::vector<double>& load_impulse, const ProbeFaces& probes,
                                    std::vector<double>& probe_push) {
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
  // Each ghost's mirror; a mirror without water, or held along every axis, takes no exchange.
  const long count = static_cast<long>(all_.size());
  mirror_dv_.resize(all_.size());
#pragma omp parallel for schedule(static)
  for (long q = 0; q < count; ++q) {
    MirrorChange& c = mirror_dv_[q];
    c.node = kNoMirror;
    for (int d = 0; d < D; ++d) c.dv[d] = T(0);
    const long gi = grid_index<D>(gkeys, all_[q].offset);
    if (gi < 0) continue;
    const size_t mi = static_cast<size_t>(gi);
    if (grid.m[mi] > T(0) && grid.wall[mi] != all_axes<D>()) c.node = mi;
  }
  // The ghosts grouped by mirror, each group in ghost order (its sums then do not depend on the threads).
  by_mirror_.clear();
  for (long q = 0; q < count; ++q)
    if (mirror_dv_[q].node != kNoMirror) by_mirror_.push_back(static_cast<uint64_t>(q));
  std::sort(by_mirror_.begin(), by_mirror_.end(), [&](uint64_t a, uint64_t b) {
    return mirror_dv_[a].node != mirror_dv_[b].node ? mirror_dv_[a].node < mirror_dv_[b].node : a < b;
  });
  group_start_.clear();
  for (size_t k = 0; k < by_mirror_.size(); ++k)
    if (k == 0 || mirror_dv_[by_mirror_[k]].node != mirror_dv_[by_mirror_[k - 1]].node)
      group_start_.push_back(k);
  group_start_.push_back(by_mirror_.size());
  // Each group exchanges at once (mpm::ghost_pool_velocity); groups share no node, so they run in parallel.
  const long groups = static_cast<long>(group_start_.size()) - 1;
#pragma omp parallel for schedule(static)
  for (long k = 0; k < groups; ++k) {
    const size_t mi = mirror_dv_[by_mirror_[group_start_[k]]].node;
    T pool[kGhostPoolLanes * D] = {}, terms[kGhostPoolLanes * D], vm[D], u[D], push_dv[D];
    for (size_t j = group_start_[k]; j < group_start_[k + 1]; ++j) {
      const Ghost<D, T>& gh = all_[by_mirror_[j]];
      T vg[D];
      for (int d = 0; d < D; ++d) vg[d] = grid.v[d][gh.idx];
      ghost_pool_terms<D>(vg, gh.vpre, grid.m[gh.idx], gh.axes, push_axes_, terms);
      for (int c = 0; c < kGhostPoolLanes * D; ++c) pool[c] += terms[c];
    }
    for (int d = 0; d < D; ++d) vm[d] = grid.v[d][mi];
    const unsigned held = grid.wall[mi];
    ghost_pool_velocity<D>(pool, vm, grid.m[mi], held, u, push_dv);
    for (size_t j = group_start_[k]; j < group_start_[k + 1]; ++j) {
      const size_t q = by_mirror_[j];
      const Ghost<D, T>& gh = all_[q];
      for (int d = 0; d < D; ++d) {
        if (ghost_takes_mean(gh.axes, held, d)) {
          grid.v[d][gh.idx] = u[d];  // ghosts are never mirrors: no other group reads it
        } else if ((gh.axes & (1u << d)) && pool[2 * D + d] > T(0)) {
          mirror_dv_[q].dv[d] =
              push_dv[d] * (grid.m[gh.idx] / pool[2 * D + d]);  // the push by its share of mass
        }
      }
    }
    for (int d = 0; d < D; ++d) grid.v[d][mi] = u[d];
  }
  // The image's push is the walls' load, in ghost order; the domain box's counts for the probes only.
  for (size_t q = 0; q < mirror_dv_.size(); ++q) {
    const MirrorChange& c = mirror_dv_[q];
    if (c.node == kNoMirror) continue;
    const Ghost<D, T>& gh = all_[q];
    double push[D] = {};
    for (int d = 0; d < D; ++d)
      if (gh.axes & (1u << d)) push[d] = gh.load_weight * double(grid.m[c.node]) * double(c.dv[d]);
    if (probes.count > 0) add_probe_push<D>(probes, gh.x, push, probe_push.data());
    if (gh.wall < 0) continue;
    for (int d = 0; d < D; ++d) load_impulse[static_cast<size_t>(gh.wall) * D + d] -= push[d];
  }
}

#define FLUME_INSTANTIATE(D, T) template class GhostReflection<D, T>;
FLUME_MPM_CPU_VARIANTS(FLUME_INSTANTIATE)
#undef FLUME_INSTANTIATE

}  // namespace flume::mpm
