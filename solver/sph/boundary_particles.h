// The wall particles of an SPH run (dynamic boundary conditions, Crespo et al. 2007): the points of the
// fluid's lattice (spacing s, at (k + 1/2) s from the frame's origin, where water boxes that start on a
// multiple of s put their particles) that lie in a solid (a boundary box or half-space, or outside the
// domain) within `layers` lattice steps of open space, enough to fill the kernel's support 2h beside every
// wall, and less than `reach` (the support, 2h) deep in each solid that holds them. A point that deep is
// farther than the support from any point outside the solids, so no water outside them ever meets it (in 3D,
// 2h = 3.46 s: a face on the lattice's half points keeps three of the four layers).
#pragma once
#include <vector>

#include "solver/scene.h"

namespace flume::sph {

struct WallParticles {
  std::vector<double> x[3];
  std::vector<int> wall;         // index into scene.boundaries, or -1 for the domain's walls
  std::vector<double> velocity;  // the wall's prescribed velocity, 3 per particle
  std::size_t size() const { return wall.size(); }
};

// Throws InputError (naming solver.dx) when the lattice over the domain would exceed max_points.
WallParticles make_wall_particles(const Scene& scene, double spacing, int layers, double reach,
                                  double max_points = 4e8);

}  // namespace flume::sph
