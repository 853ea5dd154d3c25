// The step's audit, for both backends: the slack the energy check allows and the one-line messages that stop
// an unstable run. Host code (the backends reduce the energies each in their own way, mpm::AuditTerms).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <sstream>
#include <string>
#include <vector>

#include "solver/scene.h"

namespace flume::mpm {

// Slack for the energy audit: MPM dissipates, so the total may only grow by round-off and by the compression
// work of the initial loading. 1% of the larger of the initial kinetic energy and the potential energy of
// lifting all the water by its own height bounds those by a wide margin, and an explicit-step blow-up grows
// exponentially, far past it within a few steps.
inline double energy_slack(const Scene& scene, double mass, double kinetic) {
  const int D = scene.dimension;
  double zmin = 1e300, zmax = -1e300;
  for (const auto& w : scene.water) {
    zmin = std::min(zmin, w.lo[D - 1]);
    zmax = std::max(zmax, w.hi[D - 1]);
  }
  double g = 0;
  for (int d = 0; d < D; ++d) g += scene.solver.gravity[d] * scene.solver.gravity[d];
  return 0.01 * std::max({kinetic, mass * std::sqrt(g) * (zmax - zmin), 1e-12});
}

inline std::string fmt_point(const double* x, int dim) {
  std::ostringstream s;
  s.precision(4);
  s << "(";
  for (int d = 0; d < dim; ++d) s << (d ? ", " : "") << x[d];
  s << ") m";
  return s.str();
}

// kind 1: a non-finite value or J <= 0; 2: the particle left the domain (by more than a cell).
inline std::string bad_particle_message(int kind, double t_new, long step, double dt, long long particle,
                                        const double* x, int dim) {
  std::ostringstream s;
  s << (kind == 1 ? "non-finite value (NaN/Inf) or non-positive volume ratio J"
                  : "a particle left the domain")
    << " at t = " << t_new << " s (step " << step << ", dt = " << dt << " s), particle " << particle << " at "
    << fmt_point(x, dim) << "; try a smaller solver.cfl or a finer solver.dx";
  return s.str();
}

// Where the energy grew: the fastest particle, found serially (this runs once, when the run stops). v: D
// arrays.
template <int D, typename T>
std::string energy_growth_message(double t_new, long step, double total, double initial, double max_speed,
                                  const std::vector<T>* x, const std::vector<T>* v, size_t n) {
  size_t fastest = 0;
  double best = -1;
  for (size_t i = 0; i < n; ++i) {
    double v2 = 0;
    for (int d = 0; d < D; ++d) v2 += double(v[d][i]) * v[d][i];
    if (v2 > best) {
      best = v2;
      fastest = i;
    }
  }
  double xf[D];
  for (int d = 0; d < D; ++d) xf[d] = x[d][fastest];
  std::ostringstream s;
  s << "energy grew beyond what gravity and forcing supply at t = " << t_new << " s (step " << step
    << "): total " << total << " J against " << initial << " J initially (max speed " << max_speed
    << " m/s, particle " << fastest << " at " << fmt_point(xf, D) << "); try a smaller solver.cfl";
  return s.str();
}

}  // namespace flume::mpm
