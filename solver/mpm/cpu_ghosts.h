// The CPU backend's ghost nodes (mpm::ghost_pool_velocity): a node beside a wall that finds its reflection in
// the water exchanges tangential momentum with it, together with every other ghost reflecting onto the same
// mirror. The grid update lists the ghosts per thread; reflect() groups them by mirror, sums each group in
// ghost-node order and adds the loads in that order, so that the result does not depend on the thread count.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "solver/mpm/cpu_blocks.h"
#include "solver/mpm/probe_k.h"

namespace flume::mpm {

template <int D, typename T>
struct Ghost {
  size_t idx = 0;          // the ghost node
  int offset[D] = {};      // the reflection's offset in nodes, then (after the walls) the mirror node
  unsigned axes = 0;       // the normal axes: kept; the others are exchanged with the mirror
  T vpre[D] = {};          // the ghost's velocity from the particles alone (mpm::ghost_pool_terms)
  int wall = -1;           // the scene wall whose load takes the image's push (-1: the domain box)
  double load_weight = 1;  // 1/2 on a symmetry plane (the whole's load there is twice the half's)
  double x[D] = {};        // the ghost node's position: where the image's push counts for a pressure probe
};

template <int D, typename T>
class GhostReflection {
 public:
  // The wall normals that push with a ghost's image (mpm::image_push_axes).
  void set_push_axes(unsigned axes) { push_axes_ = axes; }
  // Before the grid update: one empty list per thread (each thread clears its own).
  void begin(int nthreads) { ghosts_.resize(nthreads); }
  std::vector<Ghost<D, T>>* thread_list(int thread) { return &ghosts_[thread].list; }
  // The exchanges. The normal part of each mirror's change (the image's push) is its wall's load, added to
  // load_impulse (D per wall) and to the pressure probes' pushes (mpm::add_probe_push); other than that no
  // load: the exchange is internal to the water.
  void reflect(GridNodes<D, T>& grid, const std::vector<uint64_t>& gkeys, std::vector<double>& load_impulse,
               const ProbeFaces& probes, std::vector<double>& probe_push);

 private:
  struct MirrorChange {
    size_t node;  // the mirror, kNoMirror where the ghost has none with water
    T dv[D];      // the ghost's share of the image's push on it
  };
  static constexpr size_t kNoMirror = ~size_t(0);
  unsigned push_axes_ = 0;
  struct alignas(64) ThreadList {
    std::vector<Ghost<D, T>> list;
  };
  std::vector<ThreadList> ghosts_;       // per thread: this step's ghost nodes
  std::vector<Ghost<D, T>> all_;         // all of them, in node order
  std::vector<MirrorChange> mirror_dv_;  // per ghost in all_'s order
  std::vector<uint64_t> by_mirror_;  // the ghosts with a mirror (indices into all_), by mirror, then ghost
  std::vector<size_t> group_start_;  // where each mirror's ghosts begin in by_mirror_
};

}  // namespace flume::mpm
