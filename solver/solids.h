// Where the scene's solids are, for the instruments that weigh what they read by the open space around them
// (gauges near a wall, pressure probes near a corner). Host code.
#pragma once
#include "solver/scene.h"

namespace flume {

// Whether point p lies inside a solid of the scene (a boundary box, or behind a boundary plane) or outside
// the domain box. Beyond a symmetry plane lies the water's mirror image, a solid only when
// `symmetry_is_solid`.
inline bool inside_solid(const Scene& s, const Vec3d& p, bool symmetry_is_solid = true) {
  for (int d = 0; d < s.dimension; ++d)
    if (p[d] < s.domain_lo[d] || p[d] > s.domain_hi[d]) return true;
  for (const auto& b : s.boundaries) {
    if (!symmetry_is_solid && b.condition == BoundaryCondition::kSymmetry) continue;
    const auto& sh = b.shape;
    if (sh.type == ShapeType::kBox) {
      bool in = true;
      for (int d = 0; d < s.dimension; ++d) in &= p[d] > sh.lo[d] && p[d] < sh.hi[d];
      if (in) return true;
    } else {
      double side = 0;
      for (int d = 0; d < s.dimension; ++d) side += (p[d] - sh.point[d]) * sh.normal[d];
      if (side < 0) return true;
    }
  }
  return false;
}

}  // namespace flume
