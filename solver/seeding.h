// The particles a scene starts with, for both backends (MpmSolver and the CUDA solver) and SPH: a regular
// lattice of ppc^(1/D) particles per cell per axis in each water box, hydrostatically preloaded where the box
// asks, and flagged where the reservoir's vacuum holds the water. Host code, header-only so that the CUDA
// library needs nothing from the solver library.
//
// A box that is not a whole number of spacings long on an axis still holds rho times its volume; how the
// lattice fits it (Lattice):
//   kAnchored   (MPM) rows a spacing apart from the box's low face, the last row only as thick as what is
//               left, its particle at that slab's middle with that slab's volume. The seeds then move
//               continuously with the box's faces: a face crossing a row boundary starts a row of zero
//               volume, where stretching jumped by a row (calibrated gate heights and fill levels cross such
//               boundaries; docs/solver.md, "Seeding a box").
//   kStretched  (SPH, whose kernel sums want one particle spacing and one mass) lround(L / spacing) rows
//               stretched to fit, each carrying the box's volume over its particles.
#pragma once
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "solver/scene.h"

namespace flume {

enum class Lattice { kAnchored, kStretched };

// The rows of a box `length` long on one axis: row i's centre lies `centre` from the low face, `width` thick.
struct LatticeRows {
  long count = 0;
  double pitch = 0;  // the full rows' width and spacing
  double last = 0;   // the last row's width (pitch unless kAnchored cuts it)

  double centre(long i) const { return i + 1 < count ? (i + 0.5) * pitch : (count - 1) * pitch + 0.5 * last; }
  double width(long i) const { return i + 1 < count ? pitch : last; }
};

inline LatticeRows lattice_rows(double length, double spacing, Lattice lattice) {
  LatticeRows r;
  if (lattice == Lattice::kStretched) {
    r.count = std::max(1L, std::lround(length / spacing));
    r.pitch = r.last = length / r.count;
    return r;
  }
  // A length within round-off of a whole number of spacings is that number: no sliver row.
  const double q = length / spacing;
  long whole = static_cast<long>(std::floor(q + 1e-9));
  double rest = length - whole * spacing;
  if (rest <= 1e-9 * spacing) rest = 0;
  if (whole == 0) {
    whole = 1;
    rest = length;
  }
  r.pitch = spacing;
  r.count = whole + (rest > 0 ? 1 : 0);
  r.last = rest > 0 ? rest : spacing;
  return r;
}

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
Seeds seed_water(const Scene& scene, double spacing, const std::function<bool(const double*)>& displaced = {},
                 Lattice lattice = Lattice::kAnchored) {
  Seeds s;
  const auto& B = scene.basin;
  const bool forced = B.present && B.forcing.model != ForcingModel::kNone;
  for (std::size_t w = 0; w < scene.water.size(); ++w) {
    const auto& box = scene.water[w];
    LatticeRows rows[D];
    long total = 1;
    for (int d = 0; d < D; ++d) {
      rows[d] = lattice_rows(box.hi[d] - box.lo[d], spacing, lattice);
      total *= rows[d].count;
    }
    for (long k = 0; k < total; ++k) {
      long r = k;
      double p[D];
      double volume = 1;
      for (int d = D - 1; d >= 0; --d) {
        const long idx = r % rows[d].count;
        r /= rows[d].count;
        p[d] = box.lo[d] + rows[d].centre(idx);
        volume *= rows[d].width(idx);
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
