// MpmSolver (solver/mpm/cpu_solver.h): the boundaries' set-up and the symmetry plane's mirror. The walls and
// the domain box act node by node in the grid update (mpm::apply_boundaries), the ghosts after it
// (GhostReflection), the symmetry fold inside it (cpu_grid_update.cpp).
#include <algorithm>

#include "common/errors.h"
#include "solver/mpm/boundaries.h"
#include "solver/mpm/cpu_solver.h"

namespace flume::mpm {

template <int D, typename T, bool Flip>
void MpmSolver<D, T, Flip>::setup_boundaries() {
  walls_ = scene_walls<D, T>(scene_);
  has_sym_ = scene_symmetry_plane<D>(scene_, grid_lo_, dx_, sym_);
  zone_ = SymmetryZone<D>(sym_);
  if (has_sym_ && debris_)
    throw InputError(scene_.file, "boundaries",
                     "a symmetry plane cannot be used with debris (the bodies would "
                     "need their mirror images): model the full span");
  container_ = scene_container<D, T>(scene_);
  subcell_rate0_ = subcell_rate0(c_, dx_);
  load_impulse_.assign(walls_.size() * D, 0.0);
  probe_geometry_ = probe_geometry(scene_);
  probe_faces_ = probe_faces(probe_geometry_, dx_, has_sym_ ? &sym_ : nullptr);
  probe_push_.assign(static_cast<size_t>(probe_faces_.count), 0.0);
}

// After the walls and the ghosts: every node beyond the plane is the reflection of its mirror; one whose
// mirror lies outside the zone (more than SymmetryZone::kZone cells beyond, no mass) is emptied.
template <int D, typename T, bool Flip>
void MpmSolver<D, T, Flip>::mirror_beyond_symmetry() {
  const long nq = static_cast<long>(zone_.entries());
  const std::vector<uint64_t>& gkeys = blocks_.gkeys;
#pragma omp parallel for schedule(static)
  for (long q = 0; q < nq; ++q) {
    int node[D];
    const long g = zone_.node(q, gkeys, node);
    const int k = static_cast<int>(q % kNodes);
    if (symmetry_side(sym_, node[sym_.axis]) <= 0) continue;
    const size_t idx = static_cast<size_t>(g) * kNodes + k;
    const long m = zone_.mirror_entry(node, gkeys);
    if (m < 0) {  // nothing on the modelled side within reach: no water here either
      grid_.clear(idx);
      continue;
    }
    const size_t mi = static_cast<size_t>(zone_.block(m)) * kNodes + m % kNodes;
    grid_.m[idx] = grid_.m[mi];
    grid_.e[idx] = grid_.e[mi];
    grid_.fill[idx] = grid_.fill[mi];
    grid_.wall[idx] = grid_.wall[mi];
    for (int d = 0; d < D; ++d) grid_.v[d][idx] = T(symmetry_channel_sign<D>(sym_, 1 + d)) * grid_.v[d][mi];
    if constexpr (kFlipChannels > 0)
      for (int d = 0; d < D; ++d)
        grid_.vold[d][idx] = T(symmetry_channel_sign<D>(sym_, 1 + d)) * grid_.vold[d][mi];
  }
}

#define FLUME_INSTANTIATE(D, T, Flip)                      \
  template void MpmSolver<D, T, Flip>::setup_boundaries(); \
  template void MpmSolver<D, T, Flip>::mirror_beyond_symmetry();
FLUME_MPM_SOLVER_VARIANTS(FLUME_INSTANTIATE)
#undef FLUME_INSTANTIATE

}  // namespace flume::mpm
