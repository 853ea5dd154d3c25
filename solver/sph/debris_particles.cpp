#include "solver/sph/debris_particles.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "common/errors.h"
#include "solver/sph/ghost_nodes.h"

namespace flume::sph {

DebrisParticles make_debris_particles(const Scene& scene, double spacing, int layers, double max_points) {
  DebrisParticles p;
  if (!scene.debris.present) return p;
  // The count first, from the lattice's extent alone: nothing is allocated from an unchecked size.
  double total = 0;
  for (const DebrisBody& b : scene.debris.bodies) {
    double n = 1;
    for (int a = 0; a < 3; ++a) n *= std::max(1.0, std::round(b.size[a] / spacing));
    total += n;
  }
  if (total > max_points)
    throw InputError(scene.file, "solver.dx",
                     "the debris boxes would carry " + std::to_string(long(total)) +
                         " SPH boundary particles (allowed: at most " + std::to_string(long(max_points)) +
                         "): use a larger dx");
  for (std::size_t k = 0; k < scene.debris.bodies.size(); ++k) {
    const DebrisBody& b = scene.debris.bodies[k];
    int n[3];
    double step[3];
    for (int a = 0; a < 3; ++a) {
      n[a] = static_cast<int>(std::max(1.0, std::round(b.size[a] / spacing)));
      step[a] = b.size[a] / n[a];
    }
    const double mass = scene.fluid.density * step[0] * step[1] * step[2];
    const double half[3] = {0.5 * b.size[0], 0.5 * b.size[1], 0.5 * b.size[2]};
    auto within_layers = [&](int a, int i) { return i < layers || i >= n[a] - layers; };
    for (int i = 0; i < n[0]; ++i)
      for (int j = 0; j < n[1]; ++j)
        for (int l = 0; l < n[2]; ++l) {
          if (!within_layers(0, i) && !within_layers(1, j) && !within_layers(2, l)) continue;
          const int idx[3] = {i, j, l};
          double o[3], g[3];
          for (int a = 0; a < 3; ++a) o[a] = -0.5 * b.size[a] + (idx[a] + 0.5) * step[a];
          box_ghost_vector(half, o, 3, g);
          for (int a = 0; a < 3; ++a) {
            p.offset[a].push_back(o[a]);
            p.ghost[a].push_back(g[a]);
          }
          p.body.push_back(static_cast<int>(k));
          p.mass.push_back(mass);
        }
  }
  return p;
}

}  // namespace flume::sph
