// The scene's boundaries as the node update reads them (mpm::Wall, mpm::Container, mpm::SymmetryPlane), set
// up once per run for both backends. Host code.
#pragma once
#include <cmath>
#include <vector>

#include "solver/mpm/node_k.h"
#include "solver/mpm/probe_k.h"
#include "solver/scene.h"
#include "solver/symmetry.h"

namespace flume::mpm {

// The scene's boundaries in scene order (the node update applies them in that order); a `symmetry` one stays
// in the list, where the node update skips it, so that a wall's index is its load cell's.
template <int D, typename T>
std::vector<Wall<D, T>> scene_walls(const Scene& scene) {
  std::vector<Wall<D, T>> walls;
  for (const auto& b : scene.boundaries) {
    Wall<D, T> w;
    w.box = b.shape.type == ShapeType::kBox;
    for (int d = 0; d < D; ++d) {
      w.a[d] = w.box ? b.shape.lo[d] : b.shape.point[d];
      w.b[d] = w.box ? b.shape.hi[d] : b.shape.normal[d];
      w.vb[d] = T(b.velocity[d]);
    }
    w.bc = static_cast<Bc>(static_cast<int>(b.condition));
    w.mu = T(b.friction);
    w.subcell_axes = b.subcell_axes;
    w.bed_k = T(scene.fluid.density * bed_drag_coefficient(b.roughness, scene.solver.dx) *
                std::pow(scene.solver.dx, D - 1));
    walls.push_back(w);
  }
  return walls;
}

template <int D, typename T>
Container<D, T> scene_container(const Scene& scene) {
  Container<D, T> c;
  for (int d = 0; d < D; ++d) {
    c.lo[d] = scene.domain_lo[d];
    c.hi[d] = scene.domain_hi[d];
  }
  c.bc = static_cast<Bc>(static_cast<int>(scene.domain_walls));
  c.mu = T(scene.domain_wall_friction);
  return c;
}

// The scene's symmetry plane into `plane`; false when it has none (scene.cpp allows one at most).
template <int D>
bool scene_symmetry_plane(const Scene& scene, const double* grid_lo, double dx, SymmetryPlane& plane) {
  for (const auto& b : scene.boundaries)
    if (b.condition == BoundaryCondition::kSymmetry) {
      plane = symmetry_plane<D>(b, grid_lo, dx);
      return true;
    }
  return false;
}

// The pressure probes' faces for mpm::add_probe_push: every probe's point (3 doubles each, scene order), then
// every probe's normal. `geometry` must outlive the view probe_faces makes of it.
inline std::vector<double> probe_geometry(const Scene& scene) {
  std::vector<double> g;
  for (const auto& p : scene.instruments.pressure_probes)
    g.insert(g.end(), p.position.begin(), p.position.end());
  for (const auto& p : scene.instruments.pressure_probes) g.insert(g.end(), p.normal.begin(), p.normal.end());
  return g;
}
inline ProbeFaces probe_faces(const std::vector<double>& geometry, double dx, const SymmetryPlane* plane,
                              double depth_cells = kProbeDepthCells) {
  ProbeFaces f;
  f.count = static_cast<int>(geometry.size() / 6);
  f.point = geometry.data();
  f.normal = geometry.data() + 3 * f.count;
  f.dx = dx;
  f.depth = depth_cells * dx;
  if (plane) {
    f.sym_axis = plane->axis;
    f.sym_at = plane->at;
  }
  return f;
}

}  // namespace flume::mpm
