// Pressure probes read from the grid (solver/pressure_probes.h), written once for both backends: the push the
// walls give the water at the nodes near a probe, weighted along the face by the grid's kernel. In MPM a wall
// acts on the water at its nodes (mpm::apply_boundaries, and the image's push of the free-slip mirror), so
// that is where its force is; the particles' pressure next to it misses the part that stops the water
// arriving at the face in the step, which in an impact is most of it (docs/results.md, "Pressure probes").
#pragma once
#include "solver/bspline_weight.h"
#include "solver/mpm/node_k.h"

namespace flume::mpm {

// How deep into the solid (cells, along the face's normal) and how far out into the water a node's push still
// counts for a face in MPM: the walls act on nodes within about two cells inside (ghost and boundary nodes
// that the water's stencils reach) and on nodes up to a cell outside a face between grid lines (the sub-cell
// cover). SPH's wall particles lie up to its wall's layers deep (ProbeFaces::depth).
constexpr double kProbeDepthCells = 2.5;
constexpr double kProbeReachCells = 1.0;

// The probes as the grid update reads them: per probe a point on its face and the face's outward normal (3
// doubles each), the grid's spacing (the B-spline's scale), how deep into the solid a push counts (m), and
// the symmetry plane (axis, coordinate; axis -1: none), across which a half domain's pushes count again at
// their images. The same sums serve SPH, whose walls push the water through their particles.
struct ProbeFaces {
  const double* point = nullptr;
  const double* normal = nullptr;
  int count = 0;
  double dx = 0;
  double depth = 0;
  int sym_axis = -1;
  double sym_at = 0;
};

// The axis closest to a normal: nodes in columns along it share a probe's footprint on the face.
template <int D>
FLUME_HD int probe_normal_axis(const double* n) {
  int a = 0;
  for (int d = 1; d < D; ++d)
    if (std::fabs(n[d]) > std::fabs(n[a])) a = d;
  return a;
}

// The face area each column of nodes stands for: dx^(D-1) of the plane across the normal axis, on the face.
template <int D>
FLUME_HD double probe_column_area(const double* n, double dx) {
  double area = 1;
  for (int d = 0; d < D - 1; ++d) area *= dx;
  return area / std::fabs(n[probe_normal_axis<D>(n)]);
}

// Probe q's weight of a node at x: the quadratic B-spline of its distance along the face on each axis across
// the normal (over the nodes of a lattice these sum to one, so a uniform push per column reads exactly),
// zero outside the layer from kProbeDepthCells inside the solid to kProbeReachCells into the water.
template <int D>
FLUME_HD double probe_node_weight(const ProbeFaces& f, int q, const double* x) {
  const double* p = f.point + 3 * q;
  const double* n = f.normal + 3 * q;
  double r[D], s = 0;
  for (int d = 0; d < D; ++d) {
    r[d] = x[d] - p[d];
    s += r[d] * n[d];
  }
  if (s <= -f.depth || s > kProbeReachCells * f.dx) return 0.0;
  const int a = probe_normal_axis<D>(n);
  double w = 1;
  for (int d = 0; d < D && w > 0; ++d)
    if (d != a) w *= bspline_weight((r[d] - s * n[d]) / f.dx);
  return w;
}

// The walls' push on the water at a node in the step (N s, times the node's load weight): its momentum after
// mpm::apply_boundaries less before (v_free). False when no wall acted on it, so only those nodes are summed.
template <int D, typename T>
FLUME_HD bool node_wall_push(double load_weight, T m, const T* v, const T* v_free, double* push) {
  bool pushed = false;
  for (int d = 0; d < D; ++d) {
    push[d] = load_weight * double(m) * (double(v[d]) - double(v_free[d]));
    pushed = pushed || push[d] != 0.0;
  }
  return pushed;
}

// Adds to each probe's sum the normal part of `push` (N s: the impulse the walls gave the water at the node
// at x in the step, times the node's load weight) by the node's weight, and, with a symmetry plane, the same
// for the node's image across it (the half grid's missing half).
template <int D>
FLUME_HD void add_probe_push(const ProbeFaces& f, const double* x, const double* push, double* sums) {
  for (int q = 0; q < f.count; ++q) {
    const double* n = f.normal + 3 * q;
    double pn = 0;
    for (int d = 0; d < D; ++d) pn += push[d] * n[d];
    double add = probe_node_weight<D>(f, q, x) * pn;
    if (f.sym_axis >= 0) {
      double xi[D];
      for (int d = 0; d < D; ++d) xi[d] = x[d];
      xi[f.sym_axis] = 2 * f.sym_at - x[f.sym_axis];
      add += probe_node_weight<D>(f, q, xi) * (pn - 2 * push[f.sym_axis] * n[f.sym_axis]);
    }
    if (add != 0.0) accumulate(&sums[q], add);
  }
}

}  // namespace flume::mpm
