// The debris coupling's per-node and per-particle bodies, written once for both backends (the CPU's grid update
// and G2P through solver/mpm/cpu_debris.h, the CUDA kernels in cuda/mpm_cuda.cu). The exchange itself, a small
// implicit solve over the nodes found and the rigid bodies' step, stays on the host: solver/debris_coupling.h
// explains the method.
#pragma once
#include <cstdint>

#include "solver/mpm_kernels.h"
#include "solver/rigid/rigid_box_geometry.h"

namespace flume {

// A grid node inside a debris box's band, as the grid update found it.
struct CouplingNode {
  uint64_t id = 0;  // grid node's storage index (the sort key)
  int body = -1;
  double x[3] = {0, 0, 0};  // node position
  double n[3] = {0, 0, 0};  // box's outward normal at the node (its nearest face)
  double m = 0;             // water mass on the node
  double p = 0;             // water pressure on the node (Pa): the equation of state at its mass-weighted strain
  double v[3] = {0, 0, 0};  // node velocity before the exchange; after the exchange: the projected velocity
};

namespace mpm {

// Nodes up to one cell outside a box are its moving-wall nodes: then a water particle touching the box puts
// (nearly) all its weight on them (quadratic B-splines reach 1.5 cells; nodes 1-1.5 cells away carry at most
// 1/8), so the box feels the water's full pressure. With only the nodes inside the box it would feel the share
// of the face's position between nodes, 1/2 on average (docs/solver.md, "Measurements behind the constants";
// tests/solver/test_debris.cpp).
constexpr double kCouplingBandCells = 1.0;

// The box holding point x, the deepest when several do (signed distance <= tol), or -1; writes its outward
// normal at x. `radius` holds each box's bounding radius.
FLUME_HD int locate_box(const RigidBoxView* views, const double* radius, int nbodies, const double x[3], double tol,
                        double n[3]) {
  int best = -1;
  // A node exactly tol out (a face on a grid line, a band of whole cells) is in the band whatever the round-off
  // of the face's position: without the margin one side of a box could keep its nodes and the opposite side
  // lose them.
  double best_d = tol > 0 ? tol * (1 + 1e-9) : tol;
  for (int b = 0; b < nbodies; ++b) {
    const RigidBoxView& v = views[b];
    const double r2 = (x[0] - v.centre[0]) * (x[0] - v.centre[0]) + (x[1] - v.centre[1]) * (x[1] - v.centre[1]) +
                      (x[2] - v.centre[2]) * (x[2] - v.centre[2]);
    // The bounding sphere grown by tol: a node tol outside a face may lie beyond the bare half-diagonal (one a
    // cell off the Waseda container's end faces does), and culling it there dropped the band's nodes round the
    // box's ends, edges and corners from the coupling and from the film's rim.
    const double reach = radius[b] + (tol > 0 ? tol : 0.0);
    if (r2 > reach * reach + 1e-12) continue;
    const double d = box_signed_distance(v, x);
    if (d <= best_d) {
      best_d = d;
      best = b;
    }
  }
  if (best >= 0) box_outward_normal(views[best], x, n);
  return best;
}

// A node with water mass m at xn in the band (`band`, m) of a box becomes a moving-wall node of it: c holds what
// the exchange needs. e_node is the node's mass-weighted strain less its hydrostatic part (the well-balanced
// J-bar, mpm::hydrostatic_strain); the pressure is the equation of state at the whole strain. Returns false
// where no box's band holds the node.
template <int D, typename T>
FLUME_HD bool coupling_node(const RigidBoxView* views, const double* radius, int nbodies, const double* xn,
                            double band, uint64_t id, T m, T e_node, const T* v, const TaitLaw<double>& law,
                            const T* strain_slope, CouplingNode& c) {
  for (int d = 0; d < 3; ++d) c.x[d] = d < D ? xn[d] : 0.0;
  c.body = locate_box(views, radius, nbodies, c.x, band, c.n);
  if (c.body < 0) return false;
  c.id = id;
  c.m = double(m);
  double slope[D];
  for (int d = 0; d < D; ++d) slope[d] = double(strain_slope[d]);
  c.p = law.pressure(double(e_node) + hydrostatic_strain<D>(c.x, slope));
  for (int d = 0; d < D; ++d) c.v[d] = double(v[d]);
  return true;
}

// A water particle found inside a box after G2P goes back to the box's surface, without the velocity that
// approached it (grid nodes alone let a moving face overtake the particles just ahead of it: a particle's
// velocity interpolates constrained and free nodes). Returns the box, or -1 where none holds x. What the
// particle of mass `mass` loses, the box's share, goes to `share`: the impulse (N s), then its moment about the
// origin; zero where the particle was not approaching.
FLUME_HD int push_out_of_box(const RigidBoxView* views, const double* radius, int nbodies, double mass, double x[3],
                             double v[3], double share[6]) {
  for (int k = 0; k < 6; ++k) share[k] = 0;
  double n[3];
  const int b = locate_box(views, radius, nbodies, x, 0.0, n);
  if (b < 0) return -1;
  const RigidBoxView& view = views[b];
  const double depth = -box_signed_distance(view, x);
  for (int d = 0; d < 3; ++d) x[d] += depth * n[d];
  double vb[3];
  box_surface_velocity(view, x, vb);
  double rel = 0;
  for (int d = 0; d < 3; ++d) rel += (v[d] - vb[d]) * n[d];
  if (rel >= 0) return b;
  double* J = share;
  for (int d = 0; d < 3; ++d) {
    v[d] -= rel * n[d];
    J[d] = mass * rel * n[d];  // the water's lost momentum (rel < 0: into the box)
  }
  share[3] = x[1] * J[2] - x[2] * J[1];
  share[4] = x[2] * J[0] - x[0] * J[2];
  share[5] = x[0] * J[1] - x[1] * J[0];
  return b;
}

}  // namespace mpm
}  // namespace flume
