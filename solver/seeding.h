// The particles a scene starts with, for both backends (MpmSolver and the CUDA solver): a regular lattice of
// ppc^(1/D) particles per cell per axis in each water box, hydrostatically preloaded where the box asks, and
// flagged where the reservoir's vacuum holds the water. Host code, header-only so that the CUDA library needs
// nothing from the solver library.
//
// A box that is not a whole number of spacings long on an axis gets lround(L / spacing) particles there,
// stretched to fit, so each particle carries the box's volume over its particles, prod (hi - lo) / count, not
// spacing^D: every box then holds rho times its volume (at dx = 0.04 m the Waseda basin's 0.23 m, 11.5
// spacings seeded as 12, held 4.6 % too much water with spacing^D).
#pragma once
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "solver/scene.h"

namespace flume {

struct Seeds {
  std::vector<double> x[3];    // positions, D axes used
  std::vector<double> strain;  // e = J - 1
  std::vector<uint8_t> held;   // 1 for water the reservoir's vacuum holds (issue 3)
  std::vector<double> volume;  // reference volume (m^3, m^2 in 2D): mass rho volume
  bool any_held = false;
  std::size_t size() const { return strain.size(); }
};

// `displaced(p)`: true where a solid (a debris box) takes the place of the water, which is then not seeded.
template <int D>
Seeds seed_water(const Scene& scene, double spacing, const std::function<bool(const double*)>& displaced = {}) {
  Seeds s;
  const auto& B = scene.basin;
  const bool forced = B.present && B.forcing.model != ForcingModel::kNone;
  for (std::size_t w = 0; w < scene.water.size(); ++w) {
    const auto& box = scene.water[w];
    long count[D];
    for (int d = 0; d < D; ++d) count[d] = std::max(1L, std::lround((box.hi[d] - box.lo[d]) / spacing));
    long total = 1;
    double volume = 1;  // the box's volume per lattice site
    for (int d = 0; d < D; ++d) {
      total *= count[d];
      volume *= (box.hi[d] - box.lo[d]) / count[d];
    }
    for (long k = 0; k < total; ++k) {
      long r = k;
      double p[D];
      for (int d = D - 1; d >= 0; --d) {
        const long idx = r % count[d];
        r /= count[d];
        p[d] = box.lo[d] + (idx + 0.5) * (box.hi[d] - box.lo[d]) / count[d];
      }
      // Overlapping water boxes would double the water: keep a point only for its first box.
      bool dup = false;
      for (std::size_t u = 0; u < w && !dup; ++u) {
        bool in = true;
        for (int d = 0; d < D; ++d) in &= p[d] >= scene.water[u].lo[d] && p[d] < scene.water[u].hi[d];
        dup = in;
      }
      if (dup) continue;
      if (displaced && displaced(p)) continue;
      for (int d = 0; d < D; ++d) s.x[d].push_back(p[d]);
      // Hydrostatic start: invert p = K/gamma (J^-gamma - 1) for the strain e = J - 1.
      double e = 0;
      if (box.hydrostatic) {
        const double head = std::max(0.0, box.surface - p[D - 1]);
        const double pressure = scene.fluid.density * std::fabs(scene.solver.gravity[D - 1]) * head;
        const double g = scene.fluid.gamma;
        e = std::expm1(-std::log1p(g * pressure / scene.fluid.bulk_modulus) / g);
      }
      s.strain.push_back(e);
      // The reservoir's water above still-water level is what the vacuum holds.
      const bool held = forced && p[0] < B.reservoir_length_m && p[D - 1] > B.still_water_m;
      s.held.push_back(held ? 1 : 0);
      s.volume.push_back(volume);
      s.any_held |= held;
    }
  }
  return s;
}

// The mass of particles with these reference volumes, as a backend stores them (in its precision): rho times
// their sum in double. Both backends total their water with it, in seeding order, so they agree exactly.
template <typename Volumes>
double water_mass(const Volumes& volume, double rho) {
  double sum = 0;
  for (const auto& v : volume) sum += double(v);
  return rho * sum;
}

}  // namespace flume
