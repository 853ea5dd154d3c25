#include "solver/sph/boundary_particles.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "common/errors.h"

namespace flume::sph {

namespace {
// Beyond a symmetry plane: where the modelled flow's mirror image lies. No wall is seeded there; the solver
// takes the images of the walls on the water's side instead (sph/mirror.h).
bool beyond_symmetry(const Scene& s, const Vec3d& p, double tol) {
  for (const auto& b : s.boundaries)
    if (b.condition == BoundaryCondition::kSymmetry) {
      double side = 0;
      for (int d = 0; d < s.dimension; ++d) side += (p[d] - b.shape.point[d]) * b.shape.normal[d];
      if (side < -tol) return true;
    }
  return false;
}

// Solid at p: outside the domain box, or in (or on the face of) a boundary's solid. The owner is the first
// boundary holding p, -1 for the domain's walls. A symmetry plane is not a solid.
bool solid_at(const Scene& s, const Vec3d& p, double tol, int& owner) {
  for (std::size_t b = 0; b < s.boundaries.size(); ++b)
    if (s.boundaries[b].condition != BoundaryCondition::kSymmetry &&
        shape_distance(s.boundaries[b].shape, p, s.dimension) <= tol) {
      owner = static_cast<int>(b);
      return true;
    }
  owner = -1;
  for (int d = 0; d < s.dimension; ++d)
    if (p[d] < s.domain_lo[d] || p[d] > s.domain_hi[d]) return true;
  return false;
}

// A lower bound on the distance from the solid point p to open space: its depth in the deepest solid holding
// it (the distance to a half-space's plane or a box's nearest face; outside the domain, the largest overshoot
// along an axis). Open space lies outside every solid, so at least that far.
double depth_in_solids(const Scene& s, const Vec3d& p, double tol) {
  double depth = 0;
  for (const auto& b : s.boundaries) {
    if (b.condition == BoundaryCondition::kSymmetry) continue;
    const double d = shape_distance(b.shape, p, s.dimension);
    if (d <= tol) depth = std::max(depth, -d);
  }
  for (int d = 0; d < s.dimension; ++d)
    depth = std::max({depth, s.domain_lo[d] - p[d], p[d] - s.domain_hi[d]});
  return depth;
}
}  // namespace

WallParticles make_wall_particles(const Scene& scene, double spacing, int layers, double reach,
                                  double max_points) {
  const int D = scene.dimension;
  long k0[3] = {0, 0, 0}, n[3] = {1, 1, 1};
  double total = 1;
  for (int d = 0; d < D; ++d) {
    k0[d] = static_cast<long>(std::floor(scene.domain_lo[d] / spacing - 0.5)) - layers - 1;
    const long k1 = static_cast<long>(std::ceil(scene.domain_hi[d] / spacing - 0.5)) + layers + 1;
    n[d] = k1 - k0[d] + 1;
    total *= double(n[d]);
  }
  if (total > max_points)
    throw InputError(scene.file, "solver.dx",
                     "the SPH wall lattice over the domain would hold " + std::to_string(long(total)) +
                         " points (allowed: at most " + std::to_string(long(max_points)) +
                         "): use a larger dx");
  const std::size_t count = static_cast<std::size_t>(total);
  auto point = [&](std::size_t idx, long* k) {
    Vec3d p{};
    for (int d = 0; d < D; ++d) {
      k[d] = static_cast<long>(idx % n[d]);
      idx /= n[d];
      p[d] = (k0[d] + k[d] + 0.5) * spacing;
    }
    return p;
  };
  // near[i]: an open point within `layers` steps on every axis (a box dilation of the open set, axis by
  // axis).
  std::vector<uint8_t> near(count);
  const double tol = 1e-9 * spacing;
#pragma omp parallel for schedule(static)
  for (long i = 0; i < long(count); ++i) {
    long k[3];
    const Vec3d p = point(i, k);
    int o;
    const bool solid = solid_at(scene, p, tol, o);
    near[i] = solid || beyond_symmetry(scene, p, tol) ? 0 : 1;
  }
  long stride = 1;
  std::vector<uint8_t> tmp(count);
  for (int d = 0; d < D; ++d) {
#pragma omp parallel for schedule(static)
    for (long i = 0; i < long(count); ++i) {
      const long ki = (i / stride) % n[d];
      uint8_t v = 0;
      for (long s = std::max(0L, ki - layers); s <= std::min(n[d] - 1, ki + layers) && !v; ++s)
        v = near[i + (s - ki) * stride];
      tmp[i] = v;
    }
    near.swap(tmp);
    stride *= n[d];
  }
  WallParticles w;
  for (std::size_t i = 0; i < count; ++i) {
    if (!near[i]) continue;
    long k[3];
    const Vec3d p = point(i, k);
    int o;
    if (!solid_at(scene, p, tol, o) || beyond_symmetry(scene, p, tol)) continue;
    if (depth_in_solids(scene, p, tol) >= reach) continue;
    for (int d = 0; d < 3; ++d) w.x[d].push_back(p[d]);
    w.wall.push_back(o);
    for (int d = 0; d < 3; ++d) w.velocity.push_back(o >= 0 ? scene.boundaries[o].velocity[d] : 0.0);
  }
  return w;
}

}  // namespace flume::sph
