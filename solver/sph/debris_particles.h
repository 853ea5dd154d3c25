// The boundary particles of the debris boxes in an SPH run (issue 24). Each box carries a lattice of
// particles that the water meets as it meets the walls' (their density from the water at their ghost nodes,
// mDBC, or evolved by continuity, DBC; pressure by the equation of state) but that move with the box. The
// water's pair forces on a box's particles, summed, are its load (force, and torque about the centre); Bullet
// (RigidWorld) adds gravity and contact and moves the box, and its particles take the box's motion. This is
// how DualSPHysics couples floating bodies (Crespo et al. 2015, section 2.5; Canelas et al. 2016).
//
// The lattice, per body axis: n = max(1, round(size / s)) points at the step size / n (s the water's
// spacing), the outer layer half a step inside the faces, as the water's lattice stops half a step short of a
// solid. Only the points within `layers` steps of a face are kept: the kernel's support reaches no deeper.
#pragma once
#include <vector>

#include "solver/scene.h"

namespace flume::sph {

struct DebrisParticles {
  std::vector<double> offset[3];  // body frame, from the box's centre, m
  std::vector<int> body;          // index into scene.debris.bodies
  std::vector<double> mass;       // rho0 times the lattice cell's volume, kg
  std::vector<double> ghost[3];   // body frame, to the ghost node across the nearest face (mDBC), m
  std::size_t size() const { return body.size(); }
};

// Throws InputError (naming solver.dx) when the boxes would carry more than max_points particles.
DebrisParticles make_debris_particles(const Scene& scene, double spacing, int layers, double max_points = 1e8);

}  // namespace flume::sph
