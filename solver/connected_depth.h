// The connected-water reading of a gauge (issue 30; a gauge's `"reading": "connected"`): the top of the water
// connected to the ground under the gauge, as a wire or resistance gauge reads it (the wire conducts only
// through water that touches the bottom), so spray and drops above the surface do not count.
//
// Rule. The particles in the gauge's column (horizontal distance under dx/2 from the gauge on each horizontal
// axis: one cell wide, centred on it) and at or above the ground less dx/4 are sorted by height. Walking up
// from the ground, each must lie within one cell (dx) of the one below it (the first, of the ground); the walk
// stops at the first gap over one cell. The surface is the last connected particle's height plus half a
// particle spacing (the layer that particle stands for), so water at rest on the seeding lattice reads its
// depth. No connected particle: the ground. At rest the particles of a column are a spacing (dx/2 at the
// default ppc) apart in height, so a gap of a cell is an air layer of at least half a cell.
// (The volume reading, the default, counts all water over the gauge instead: a bore broken into a foam of
// particles with gaps over a cell reads lower here, as a real wire gauge in aerated water does.)
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include "solver/scene.h"

namespace flume {

// The connected surface's elevation over a column, given the heights of the column's particles (sorted
// here), the ground under the gauge, the largest gap and the particle spacing.
inline double connected_surface(std::vector<double>& heights, double ground, double gap, double spacing) {
  std::sort(heights.begin(), heights.end());
  double level = ground, top = ground;
  bool wet = false;
  for (const double z : heights) {
    if (z - level > gap) break;
    level = std::max(level, z);
    top = z + 0.5 * spacing;
    wet = true;
  }
  return wet ? std::max(top, ground) : ground;
}

// The connected reading of gauge `g` (elevation, before its datum) from the solver's particles.
template <class Solver>
double connected_elevation(const Solver& s, const Scene& scene, const Gauge& g, double ground,
                           std::vector<double>& heights) {
  const int D = s.dim(), up = D - 1;
  const double dx = scene.solver.dx;
  heights.clear();
  const double lowest = ground - 0.25 * dx;  // water below the ground here is beside the gauge, not under it
  for (size_t i = 0; i < s.n(); ++i) {
    const double z = double(s.x(up, i));
    if (z < lowest) continue;
    bool in = true;
    for (int d = 0; d < up && in; ++d) in = std::fabs(double(s.x(d, i)) - g.position[d]) < 0.5 * dx;
    if (in) heights.push_back(z);
  }
  return connected_surface(heights, ground, dx, particle_spacing(scene));
}

}  // namespace flume
