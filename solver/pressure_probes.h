// Pressure probes (issue 30): the water's pressure on a solid face at a point, as a flush-mounted pressure
// sensor on a wall, quay or column face reads it. Read by InstrumentSet (solver/instruments.h) after every step.
//
// Estimator. The particles within one cell of the point count: those whose distance from the face along its
// normal, s, is in [-dx/2, dx) (a layer one cell deep on the water's side; -dx/2 lets in a particle pressed a
// little into the wall) and whose distance along the face from the point, t, is under 1.5 dx, weighted by the
// quadratic B-spline w(t / dx) (the grid's own kernel: a disc of radius 1.5 dx on the face in 3D, a segment in
// 2D). Each particle's pressure is the solver's equation of state at its strain (Tait, from J for MPM; from
// rho for SPH: Simulation::particle_pressures), carried from the particle to the face with the hydrostatic
// gradient, p + rho g . (x_face - x_p), since the particles nearest the face sit half a spacing off it (at
// rest the correction is exact; in an impact it leaves out the deceleration's gradient over that half
// spacing). The reading is the weighted mean, 0 when no particle is in the support (a dry sensor).
//
// Filter. As the load cells report the mean force over each sampling interval (impulse / time), a probe
// reports the mean of its per-step readings over the interval (each weighted by its step), so a short impact
// between two samples is not lost; the first sample (t = 0) is the reading then. Each step costs one parallel pass
// over the particles' positions and, when one is in a probe's support, the solver's pass computing every
// particle's pressure; a backend that sums on its device (the CUDA backend) instead reduces each probe's
// PressureTerm there (solver/particle_sums.h), and only the sums come to the host.
#pragma once
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "solver/bspline_weight.h"
#include "solver/particle_sums.h"
#include "solver/checkpoint.h"
#include "solver/scene.h"
#include "solver/simulation.h"

namespace flume {

template <class Solver>
class PressureProbeSet {
 public:
  explicit PressureProbeSet(const Scene& scene) : scene_(scene) {
    for (const auto& p : scene.instruments.pressure_probes) clocks_.push_back(1.0 / p.rate_hz);
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
    read(s, now_);
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
  std::vector<double> wsum_, psum_, pressure_;
  std::vector<Hit> hits_;
  std::vector<std::vector<Hit>> local_;  // per thread
};

}  // namespace flume
