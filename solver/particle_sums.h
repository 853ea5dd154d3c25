// The instruments' sums over the particles (velocity probes, volume gauges, pressure probes): each particle's
// term written once, as a host/device functor, for the host loop (InstrumentSet, PressureProbeSet) and for a
// backend that sums on its device (the CUDA backend: MpmCuda::sum_particles), which then hands back a few
// numbers instead of copying the particles to the host.
//
// A term is called with a particle (x(d), v(d), volume(): the reference volume; pressure() where the term
// needs it) and adds its contribution to `sum` (Term::kValues values). The host loop runs the particles in
// order, so its sums are the ones the instruments always summed; a device sums in its reduction's order, to
// round-off.
#pragma once
#include <cmath>
#include <cstddef>
#include <type_traits>

#include "common/host_device.h"
#include "solver/bspline_weight.h"

namespace flume {

constexpr int kMaxParticleSum = 4;  // the most values a term sums (a velocity probe: the weight and 3 velocities)

// A velocity probe at p: the particles within the quadratic B-spline support (1.5 dx), weighted by it. Sums
// the weight, then the weighted velocity (dim values).
struct ProbeTerm {
  static constexpr int kValues = 4;
  int dim;
  double p[3];
  double inv_dx;
  template <class Particle>
  FLUME_HD void operator()(const Particle& q, double* sum) const {
    double w = 1;
    for (int d = 0; d < dim && w > 0; ++d) w *= bspline_weight((q.x(d) - p[d]) * inv_dx);
    if (w <= 0) return;
    sum[0] += w;
    for (int d = 0; d < dim; ++d) sum[1 + d] += w * q.v(d);
  }
};

// A volume gauge at horizontal position g (InstrumentSet::gauge_elevation): each particle at or above `lowest`
// counts its reference volume with the B-spline weight of its horizontal distance. Sums the weighted volume.
struct GaugeTerm {
  static constexpr int kValues = 1;
  int up;  // the vertical axis, dim - 1
  double g[2];
  double lowest, inv_dx;
  template <class Particle>
  FLUME_HD void operator()(const Particle& q, double* sum) const {
    if (q.x(up) < lowest) return;
    double w = 1;
    for (int d = 0; d < up && w > 0; ++d) w *= bspline_weight((q.x(d) - g[d]) * inv_dx);
    if (w > 0) sum[0] += w * q.volume();
  }
};

// Whether a particle at x lies in a pressure probe's support (solver/pressure_probes.h: a layer [-dx/2, dx)
// deep along the face's normal n, within 1.5 dx along the face of the point p), with its weight w and the
// hydrostatic carry rho g . (x_face - x_p) from the particle to the face.
FLUME_HD bool pressure_probe_hit(int dim, const double* x, const double* p, const double* n, double dx,
                                 const double* g, double rho, double& w, double& carry) {
  double r[3] = {0, 0, 0}, sn = 0;
  for (int d = 0; d < dim; ++d) {
    r[d] = x[d] - p[d];
    if (!(std::fabs(r[d]) < 1.5 * dx)) return false;  // the support lies in this box
  }
  for (int d = 0; d < dim; ++d) sn += r[d] * n[d];
  if (sn < -0.5 * dx || sn >= dx) return false;
  double t2 = 0;
  for (int d = 0; d < dim; ++d) t2 += (r[d] - sn * n[d]) * (r[d] - sn * n[d]);
  w = bspline_weight(std::sqrt(t2) * (1.0 / dx));
  if (w <= 0) return false;
  double head = 0;
  for (int d = 0; d < dim; ++d) head -= g[d] * r[d];
  carry = rho * head;
  return true;
}

// A pressure probe's reading: sums the weight and the weighted pressure carried to the face.
struct PressureTerm {
  static constexpr int kValues = 2;
  int dim;
  double p[3], n[3], g[3];
  double dx, rho;
  template <class Particle>
  FLUME_HD void operator()(const Particle& q, double* sum) const {
    double x[3] = {0, 0, 0}, w, carry;
    for (int d = 0; d < dim; ++d) x[d] = q.x(d);
    if (!pressure_probe_hit(dim, x, p, n, dx, g, rho, w, carry)) return;
    sum[0] += w;
    sum[1] += w * (q.pressure() + carry);
  }
};

namespace detail {
template <class Solver, class = void>
struct sums_on_device : std::false_type {};
template <class Solver>
struct sums_on_device<Solver, std::void_t<decltype(Solver::kSumsOnDevice)>>
    : std::bool_constant<Solver::kSumsOnDevice> {};
}  // namespace detail
// Whether the solver sums particle terms itself (Solver::kSumsOnDevice, Solver::sum_particles).
template <class Solver>
constexpr bool sums_on_device = detail::sums_on_device<Solver>::value;

// Particle i of a solver with host arrays, as a term reads it.
template <class Solver>
struct HostParticle {
  const Solver& s;
  size_t i;
  double x(int d) const { return double(s.x(d, i)); }
  double v(int d) const { return double(s.v(d, i)); }
  double volume() const { return double(s.volume(i)); }
};

// The sum of `term` over the solver's particles, into sum[0 .. Term::kValues).
template <class Solver, class Term>
void sum_particles(const Solver& s, const Term& term, double* sum) {
  for (int k = 0; k < Term::kValues; ++k) sum[k] = 0;
  if constexpr (sums_on_device<Solver>) {
    s.sum_particles(term, sum);
  } else {
    for (size_t i = 0; i < s.n(); ++i) term(HostParticle<Solver>{s, i}, sum);
  }
}

}  // namespace flume
