// One grid node's update against the boundaries, written once for both backends (MpmSolver::update_node on
// the CPU, GridUpdate in cuda/mpm_cuda.cu): the scene's walls in scene order (paper eq. 2, their faces, the
// sub-cell cover of a face between grid lines), the ghost search of free-slip walls and the domain box as a
// container. The backends differ only in where the node's mass and momentum come from and where the results
// are stored.
#pragma once
#include <cstdint>

#include "solver/mpm_kernels.h"

namespace flume::mpm {

// Adds v to *a: plain on the host (the CPU's buffers are per thread; the CUDA source's host emulation is
// sequential), an atomic on a device, where many threads add into one wall's load or one node (double atomics
// need sm_60+).
template <typename T>
FLUME_HD void accumulate(T* a, T v) {
#if defined(__CUDA_ARCH__)
  atomicAdd(a, v);
#else
  *a += v;
#endif
}

// apply_boundaries' mask with every axis held: a node of a moving box, which no ghost exchanges with.
template <int D>
constexpr unsigned all_axes() {
  return (1u << D) - 1;
}

// One scene boundary, as the node update reads it. Which nodes lie on a wall is decided in double
// (mpm::wall_faces).
template <int D, typename T>
struct Wall {
  int box = 1;
  double a[D] = {}, b[D] = {};  // box: lo, hi; half-space: point, normal
  T vb[D] = {};
  Bc bc = Bc::kSeparate;
  T mu = 0;
  unsigned subcell_axes = 0;  // mpm::subcell_cover
  T bed_k = 0;                // a rough wall's bed stress: rho C_f dx^(D-1) (mpm::bed_stress); 0: none
};

// The domain box: a container whose faces hold the nodes on or beyond them.
template <int D, typename T>
struct Container {
  double lo[D] = {}, hi[D] = {};
  Bc bc = Bc::kSeparate;
  T mu = 0;
};

// What the ghost search found for a node (mpm::ghost_half_space): the reflection's offset in nodes, its
// normal axes, whether it is undefined, and the scene wall whose load takes the image's push (-1: the domain
// box).
template <int D>
struct GhostSearch {
  int offset[D] = {};
  unsigned axes = 0;
  bool ambiguous = false;
  int wall = -1;
  FLUME_HD bool found() const { return axes && !ambiguous; }
};

// Whether a node `depth` inside a face (m; negative: outside, in the water) is in the face's bed row, the one
// the bed stress acts on: the first row of nodes that are not ghost nodes, from kGhostDepth - 1 to
// kGhostDepth cells in. That is one node on every grid line across the face wherever the face lies between
// grid lines (the quay's top at 0.255 m lies half a cell off a 0.03 m grid). It is the node on the face when
// the face is on a grid line; deeper nodes are ghosts, whose velocity the mirror's exchange sets
// (mpm::ghost_half_space).
FLUME_HD bool in_bed_row(double depth, double dx) {
  return depth >= (kGhostDepth - 1) * dx && depth < kGhostDepth * dx;
}

// The bed stress of a rough wall (bed_k > 0) on the node at xn: a half-space's when xn is in its bed row; a
// box's through each face whose bed row holds xn and whose extent along the other axes covers it (the apron's
// top, the quay's face). Returns whether it acted.
template <int D, typename T>
FLUME_HD bool apply_bed_stress(const Wall<D, T>& w, const double* xn, T m, T* v, T dt, double dx) {
  T nb[D];
  if (!w.box) {
    double depth = 0;
    for (int d = 0; d < D; ++d) depth += (w.a[d] - xn[d]) * w.b[d];
    if (!in_bed_row(depth, dx)) return false;
    for (int d = 0; d < D; ++d) nb[d] = T(w.b[d]);
    bed_stress<D>(v, nb, w.vb, w.bed_k, m, dt);
    return true;
  }
  const double tol = kTieCells * dx;
  bool acted = false;
  for (int ax = 0; ax < D; ++ax) {
    bool over = true;
    for (int d = 0; d < D; ++d)
      if (d != ax) over = over && xn[d] >= w.a[d] - tol && xn[d] <= w.b[d] + tol;
    if (!over) continue;
    for (int side = 0; side < 2; ++side) {
      if (!in_bed_row(side == 0 ? xn[ax] - w.a[ax] : w.b[ax] - xn[ax], dx)) continue;
      for (int d = 0; d < D; ++d) nb[d] = d == ax ? T(side == 0 ? -1 : 1) : T(0);
      bed_stress<D>(v, nb, w.vb, w.bed_k, m, dt);
      acted = true;
    }
  }
  return acted;
}

// The boundaries acting on the node at xn (double, m) with mass m and velocity v (after gravity): each scene
// wall in `ids[0..count)` (null ids: walls 0..count-1) projects v through its faces or, where the node lies
// partly under a face between grid lines, drags it (mpm::subcell_drag); each adds m (v_before - v) times
// `load_weight` (1/2 on a symmetry plane) to its load in impulse[wall * D + d] (null: no load cell reads
// them). Then the ghost search of the free-slip walls and the domain box, and the domain box as a container.
// Returns the axes along which a wall holds the node (bit a: a face normal with a component along axis a; the
// domain box's faces; 0: the node is free), for the ghosts' exchange with a mirror on a wall
// (mpm::ghost_pool_velocity).
template <int D, typename T>
FLUME_HD unsigned apply_boundaries(const double* xn, T m, T* v, T dt, double load_weight, double dx,
                                   double subcell_rate0, const Wall<D, T>* walls, const int32_t* ids,
                                   int count, const Container<D, T>& container, double* impulse,
                                   GhostSearch<D>& ghost) {
  unsigned held = 0;
  for (int q = 0; q < count; ++q) {
    const int k = ids ? ids[q] : q;
    const Wall<D, T>& w = walls[k];
    if (w.bc == Bc::kSymmetry) continue;  // not a wall: the grid is folded across it (mpm::SymmetryPlane)
    double n[2 * D][D];
    const int faces = wall_faces<D>(xn, w.box != 0, w.a, w.b, dx, n);
    T before[D];
    for (int d = 0; d < D; ++d) before[d] = v[d];
    bool acted = faces > 0;
    if (faces) {
      for (int f = 0; f < faces; ++f)
        for (int d = 0; d < D; ++d)
          if (n[f][d] != 0.0) held |= 1u << d;
      if (w.box)
        apply_box_wall<D>(v, xn, w.a, w.b, dx, n, faces, w.vb, w.bc, w.mu, subcell_rate0, dt);
      else
        apply_wall<D>(v, n, faces, w.vb, w.bc, w.mu);
    } else if (w.subcell_axes) {  // a node partly covered by a face between grid lines
      double nearest[D];
      const double cover = subcell_cover<D>(xn, w.a, w.b, dx, w.subcell_axes, nearest);
      if (cover > 0) {
        T covered[D];
        for (int d = 0; d < D; ++d) covered[d] = v[d];
        const int nf = wall_faces<D>(nearest, w.box != 0, w.a, w.b, dx, n);
        apply_box_wall<D>(covered, nearest, w.a, w.b, dx, n, nf, w.vb, w.bc, w.mu, subcell_rate0, dt);
        subcell_drag<D>(v, covered, cover, subcell_rate0, dt);
        acted = true;
      }
    }
    // The bed row may lie in the water, outside the wall (a face between grid lines).
    if (w.bed_k > T(0) && apply_bed_stress<D>(w, xn, m, v, dt, dx)) acted = true;
    if (impulse && acted)
      for (int d = 0; d < D; ++d)
        accumulate(&impulse[k * D + d], load_weight * double(m) * (before[d] - v[d]));
    if (!faces) continue;
    if (w.bc == Bc::kSticky) {
      ghost.ambiguous = true;
    } else {
      const unsigned axes_before = ghost.axes;
      if (w.box)
        ghost_box<D>(xn, w.a, w.b, dx, ghost.offset, ghost.axes, ghost.ambiguous);
      else
        ghost_half_space<D>(xn, w.a, w.b, dx, ghost.offset, ghost.axes, ghost.ambiguous);
      if (ghost.axes != axes_before) ghost.wall = k;
    }
  }
  if (container.bc == Bc::kSticky) {
    for (int d = 0; d < D; ++d)
      ghost.ambiguous = ghost.ambiguous || xn[d] < container.lo[d] - kGhostDepth * dx ||
                        xn[d] > container.hi[d] + kGhostDepth * dx;
  } else {
    ghost_domain<D>(xn, container.lo, container.hi, dx, ghost.offset, ghost.axes, ghost.ambiguous);
  }
  // The domain box is a container: nodes on or beyond its faces are walls.
  for (int d = 0; d < D; ++d) {
    T n[D] = {};
    if (xn[d] <= container.lo[d] + kTieCells * dx) {
      n[d] = T(1);
    } else if (xn[d] >= container.hi[d] - kTieCells * dx) {
      n[d] = T(-1);
    } else {
      continue;
    }
    const T zero[D] = {};
    project_velocity<D>(v, n, zero, container.bc, container.mu);
    held |= 1u << d;
  }
  return held;
}

}  // namespace flume::mpm
