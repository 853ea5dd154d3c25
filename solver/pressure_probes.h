// Pressure probes (issue 30): the water's pressure on a solid face at a point, as a flush-mounted pressure
// sensor on a wall, quay or column face reads it. Read by InstrumentSet (solver/instruments.h) after every
// step.
//
// Reading. What a sensor's face feels is the wall's force on the water there, per unit area. Both methods
// exert it at points of their own, MPM at the grid nodes a wall acts on, SPH through the wall's particles,
// and sum it along the probe's normal with the grid's B-spline weights along the face (solver/mpm/probe_k.h,
// Solver::probe_push); the reading is that push over the step and the open face area the weights cover
// (probe_open_area). Probes a cell apart along a wall then carry its load cell's force.
//
// The first sample (t = 0, before any step has pushed) reads the particles instead: those whose distance from
// the face along its normal is in [-dx/2, dx) and whose distance along it is under 1.5 dx, weighted by the
// same B-spline, each particle's pressure (the solver's equation of state: Simulation::particle_pressures, or
// summed on the device: solver/particle_sums.h) carried to the face with the hydrostatic gradient, p + rho g
// . (x_face - x_p): exact at rest. 0 with no particle in the support (a dry sensor).
//
// Filter. As the load cells report the mean force over each sampling interval (impulse / time), a probe
// reports the mean of its per-step readings over the interval (each weighted by its step), so a short impact
// between two samples is not lost.
#pragma once
#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "solver/bspline_weight.h"
#include "solver/checkpoint.h"
#include "solver/mpm/probe_k.h"
#include "solver/particle_sums.h"
#include "solver/scene.h"
#include "solver/simulation.h"
#include "solver/solids.h"

namespace flume {

namespace detail {
template <class Solver, class = void>
struct probes_read_wall_push : std::false_type {};
template <class Solver>
struct probes_read_wall_push<Solver, std::void_t<decltype(Solver::kProbesReadWallPush)>>
    : std::bool_constant<Solver::kProbesReadWallPush> {};
}  // namespace detail
// Whether the solver reads pressure probes from its walls' push on the water (Solver::kProbesReadWallPush,
// probe_push()): MPM's at the grid nodes, SPH's through its wall particles.
template <class Solver>
constexpr bool probes_read_wall_push = detail::probes_read_wall_push<Solver>::value;

template <class Solver>
class PressureProbeSet {
 public:
  explicit PressureProbeSet(const Scene& scene) : scene_(scene) {
    for (const auto& p : scene.instruments.pressure_probes) {
      clocks_.push_back(1.0 / p.rate_hz);
      area_.push_back(probe_open_area(scene, p));
    }
    next_.assign(clocks_.size(), 0.0);
    sum_.assign(clocks_.size(), 0.0);
    since_.assign(clocks_.size(), 0.0);
  }

  bool empty() const { return clocks_.empty(); }

  // The pressure each probe reads now (Pa), as the header describes.
  void read(const Solver& s, std::vector<double>& out) {
    const auto& probes = scene_.instruments.pressure_probes;
    const int D = s.dim();
    const double dx = scene_.solver.dx, rho = scene_.fluid.density;
    const auto& g = scene_.solver.gravity;
    const size_t np = probes.size();
    if constexpr (sums_on_device<Solver>) {
      out.assign(np, 0.0);
      for (size_t k = 0; k < np; ++k) {
        const auto& p = probes[k];
        const PressureTerm term{D,  {p.position[0], p.position[1], p.position[2]},
                                {p.normal[0], p.normal[1], p.normal[2]}, {g[0], g[1], g[2]}, dx, rho};
        double sum[PressureTerm::kValues];
        sum_particles(s, term, sum);
        out[k] = sum[0] > 0 ? sum[1] / sum[0] : 0.0;
      }
      return;
    }
    wsum_.assign(np, 0.0);
    psum_.assign(np, 0.0);
    // First the particles in a support, from their positions alone (in parallel: each thread gathers its
    // contiguous share of the particles, and the shares are joined in order, so the sums below run in particle
    // order whatever the thread count); pressures only if any is.
    int threads = 1;
#ifdef _OPENMP
    threads = omp_get_max_threads();
#endif
    local_.resize(static_cast<size_t>(threads));
    for (auto& l : local_) l.clear();
    const size_t n = s.n();
    if (n > 0) (void)s.x(0, 0);  // the CUDA backend refreshes its host copy on a first read: not in the threads
#pragma omp parallel for schedule(static) num_threads(threads)
    for (size_t i = 0; i < n; ++i) {
      int me = 0;
#ifdef _OPENMP
      me = omp_get_thread_num();
#endif
      double x[3] = {0, 0, 0};
      for (int d = 0; d < D; ++d) x[d] = double(s.x(d, i));
      for (size_t k = 0; k < np; ++k) {
        const auto& p = probes[k];
        double w, carry;
        if (pressure_probe_hit(D, x, p.position.data(), p.normal.data(), dx, g.data(), rho, w, carry))
          local_[static_cast<size_t>(me)].push_back({i, k, w, carry});
      }
    }
    hits_.clear();
    for (const auto& l : local_) hits_.insert(hits_.end(), l.begin(), l.end());
    if (!hits_.empty()) s.particle_pressures(pressure_);
    for (const Hit& h : hits_) {
      wsum_[h.probe] += h.w;
      psum_[h.probe] += h.w * (pressure_[h.particle] + h.carry);
    }
    out.assign(np, 0.0);
    for (size_t k = 0; k < np; ++k) out[k] = wsum_[k] > 0 ? psum_[k] / wsum_[k] : 0.0;
  }

  // Called after every step (and at t = 0): adds the step's reading to each interval's mean and records the
  // probes whose sample is due (all of them when `force`).
  void step(const Solver& s, double t, double dt, bool force, Record& record) {
    if (clocks_.empty()) return;
    if constexpr (probes_read_wall_push<Solver>) {
      // At t = 0 no step has pushed yet: the water is at rest, and the particles' pressure says so.
      if (dt > 0) {
        read_push(s, dt, now_);
      } else {
        read(s, now_);
      }
    } else {
      read(s, now_);
    }
    const auto& probes = scene_.instruments.pressure_probes;
    for (size_t k = 0; k < clocks_.size(); ++k) {
      sum_[k] += now_[k] * dt;  // samples fall on step ends, so the steps since one tile its interval
      if (!force && t + 1e-12 < next_[k]) continue;
      while (next_[k] <= t + 1e-12) next_[k] += clocks_[k];
      const double span = t - since_[k];
      auto& ts = record.pressures[probes[k].name];
      ts.time.push_back(t);
      ts.values.push_back(span > 0 ? sum_[k] / span : now_[k]);
      sum_[k] = 0;
      since_[k] = t;
    }
  }

  // The pressure from the walls' push (solver/mpm/probe_k.h): the push along the normal over the step and the
  // open face area the probe's weights cover (probe_open_area).
  void read_push(const Solver& s, double dt, std::vector<double>& out) const {
    const auto& probes = scene_.instruments.pressure_probes;
    const auto& push = s.probe_push();
    out.assign(probes.size(), 0.0);
    for (size_t k = 0; k < probes.size(); ++k) out[k] = area_[k] > 0 ? push[k] / (dt * area_[k]) : 0.0;
  }

  // The face area behind a probe's reading of the walls' push: over the columns of pushing points its weights
  // reach (MPM: the grid's nodes, domain_lo + k dx on each axis across the normal; SPH: the wall particles'
  // lattice, (k + 1/2) s at its spacing s), each column's weight times the part of its face cell that is
  // open water in front of the face: not inside another solid, nor beyond the edge of a box's face (sampled
  // on an 8-point grid per axis, a quarter cell off the face on either side; across a symmetry plane at its
  // image). Open everywhere this is one column's area times the weights' sum (1 over a lattice of dx, dx / s
  // over one of s); next to a floor the row of nodes on it carries the water of half a cell, and so counts
  // half, so that a uniform pressure reads as itself up to the corner.
  static double probe_open_area(const Scene& scene, const PressureProbe& p) {
    const int D = scene.dimension;
    const double dx = scene.solver.dx;
    const bool sph = scene.solver.method == SolverMethod::kSph;
    const double step = sph ? particle_spacing(scene) : dx;  // the lattice of the points that push
    const double* n = p.normal.data();
    const int a = D == 3 ? mpm::probe_normal_axis<3>(n) : mpm::probe_normal_axis<2>(n);
    const double column = D == 3 ? mpm::probe_column_area<3>(n, step) : mpm::probe_column_area<2>(n, step);
    int across[2] = {-1, -1}, nt = 0;
    for (int d = 0; d < D; ++d)
      if (d != a) across[nt++] = d;
    const Boundary* plane = nullptr;
    for (const auto& b : scene.boundaries)
      if (b.condition == BoundaryCondition::kSymmetry) plane = &b;
    constexpr int kSub = 8;
    double area = 0;
    double origin[2] = {0, 0};
    for (int t = 0; t < nt; ++t) origin[t] = sph ? 0.5 * step : scene.domain_lo[across[t]];
    const long reach = static_cast<long>(std::ceil(1.5 * dx / step)) + 1;
    long k0[2] = {0, 0};
    for (int t = 0; t < nt; ++t)
      k0[t] = std::lround(std::floor((p.position[across[t]] - origin[t]) / step)) - reach;
    for (long i = 0; i < (nt > 0 ? 2 * reach + 2 : 1); ++i)
      for (long j = 0; j < (nt > 1 ? 2 * reach + 2 : 1); ++j) {
        const long k[2] = {k0[0] + i, k0[1] + j};
        double node[2] = {0, 0}, w = 1;
        for (int t = 0; t < nt; ++t) {
          node[t] = origin[t] + double(k[t]) * step;
          w *= bspline_weight((node[t] - p.position[across[t]]) / dx);
        }
        if (w <= 0) continue;
        int open = 0;
        for (int u = 0; u < kSub; ++u)
          for (int v = 0; v < (nt > 1 ? kSub : 1); ++v) {
            const double off[2] = {((u + 0.5) / kSub - 0.5) * step, ((v + 0.5) / kSub - 0.5) * step};
            // The face point, then a quarter cell in front of it (water's side) and behind it (the solid's).
            Vec3d on = p.position;
            // Along the face: the axes across the normal move, the normal's axis follows the face's plane.
            for (int t = 0; t < nt; ++t) {
              const double along = node[t] + off[t] - p.position[across[t]];
              on[across[t]] += along;
              on[a] -= along * n[across[t]] / n[a];
            }
            Vec3d front = on, back = on;
            for (int d = 0; d < D; ++d) {
              front[d] += 0.25 * dx * n[d];
              back[d] -= 0.25 * dx * n[d];
            }
            if (plane) {  // beyond a symmetry plane: its image
              const int sa = mpm::probe_normal_axis<3>(plane->shape.normal.data());
              for (Vec3d* q : {&front, &back}) {
                const double side = ((*q)[sa] - plane->shape.point[sa]) * plane->shape.normal[sa];
                if (side < 0) (*q)[sa] = 2 * plane->shape.point[sa] - (*q)[sa];
              }
            }
            // Open water in front of a solid face: not another solid's inside, nor past the edge of a box's
            // face.
            open += !inside_solid(scene, front, false) && inside_solid(scene, back, false) ? 1 : 0;
          }
        area += w * column * open / double(nt > 1 ? kSub * kSub : kSub);
      }
    return area;
  }

  void checkpoint(StateArchive& ar) {
    ar.expect("instruments.pressure_probes", next_.size());
    ar(next_);
    ar(sum_);
    ar(since_);
  }

 private:
  struct Hit {
    size_t particle, probe;
    double w, carry;
  };
  const Scene& scene_;
  std::vector<double> clocks_, next_, sum_, since_, now_;
  std::vector<double> area_;  // per probe: the face area of one column of nodes (reading from the grid)
  std::vector<double> wsum_, psum_, pressure_;
  std::vector<Hit> hits_;
  std::vector<std::vector<Hit>> local_;  // per thread
};

}  // namespace flume
