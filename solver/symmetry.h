// The scene's symmetry plane as the kernels see it (mpm::SymmetryPlane), for the CPU and CUDA backends alike.
#pragma once
#include <cmath>

#include "solver/mpm_kernels.h"
#include "solver/scene.h"

namespace flume {

// b: a `symmetry` boundary (scene.cpp checked that it is an axis-aligned plane on a grid line or midway).
template <int D>
mpm::SymmetryPlane symmetry_plane(const Boundary& b, const double* grid_lo, double dx) {
  mpm::SymmetryPlane s;
  for (int d = 0; d < D; ++d)
    if (std::fabs(b.shape.normal[d]) > 0.5) s.axis = d;
  s.sign = b.shape.normal[s.axis] > 0 ? 1 : -1;  // the normal points into the modelled water
  s.at = b.shape.point[s.axis];
  s.twice = static_cast<int>(std::lround(2 * (s.at - grid_lo[s.axis]) / dx));
  return s;
}

}  // namespace flume
