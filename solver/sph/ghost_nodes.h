// Ghost nodes of the modified dynamic boundary conditions (mDBC, English et al. 2022): each wall particle
// takes its density from the water at its ghost node, its mirror image across the boundary's surface,
// extrapolated back to the particle with the density's gradient there. That keeps the water's pressure
// continuous into the wall, so the water rests against the surface instead of about 1.5 particle spacings off
// it as with DBC.
//
// The ghost is the particle's reflection through the nearest point of open space: across a face for a
// particle beside a flat wall or inside a solid's convex edge, through the corner for one in the solid
// beyond a concave corner of the water (the floor meeting a wall). Open space is the domain less the
// boundaries' solids; a symmetry plane is not a solid.
#pragma once
#include <vector>

#include "solver/scene.h"
#include "solver/sph/boundary_particles.h"

namespace flume::sph {

// The vector from each wall particle to its ghost node, 3 per particle (zero where no open point lies within
// `reach` m: such a particle reads the water at its own position).
std::vector<double> wall_ghost_vectors(const Scene& scene, const WallParticles& walls, double reach);

// For a point `offset` inside an axis-aligned box of half sizes `half` centred at the origin (a debris box in
// its own frame): the vector to its reflection across the nearest face.
void box_ghost_vector(const double half[3], const double offset[3], int dim, double out[3]);

}  // namespace flume::sph
