// MpmSolver (solver/mpm/cpu_solver.h): the checkpoint, the energy audit's sums and the diagnostics (particle
// fields for output, momentum, a rigid initial motion).
#include <algorithm>
#include <cmath>

#include "solver/interleave_axes.h"
#include "solver/mpm/cpu_solver.h"
#include "solver/mpm/diagnostics_k.h"

namespace flume::mpm {

// Everything a step reads that an earlier step wrote: the particles, the clock, the step-size control, the
// energy audit, the instruments, the inflow and the debris, and the block each particle was last sorted into.
// The block lists and the grid are rebuilt from those, so a resumed run repeats the uninterrupted one step
// for step, to the bit.
template <int D, typename T, bool Flip>
void MpmSolver<D, T, Flip>::checkpoint(StateArchive& ar) {
  ar.section(std::string("mpm ") + std::to_string(D) + "D " + (sizeof(T) == 4 ? "float" : "double"));
  for (int d = 0; d < D; ++d) {
    ar(x_[d]);
    ar(v_[d]);
  }
  for (auto& c : C_) ar(c);
  ar(e_);
  ar(vol_);
  ar(held_);
  ar(tag_);
  run_.checkpoint(ar, scene_);  // refuses an unstable run; a finished one resumed to a later end runs on
  ar.fields(needs_sort_, blocks_.key);  // not a function of the positions (BlockGrid::key)
  instruments_.checkpoint(ar);
  ar.expect("inflow", inflow_ ? 1 : 0);
  if (inflow_) inflow_->checkpoint(ar);
  ar.expect("debris", debris_ ? 1 : 0);
  if (debris_) debris_->bodies().checkpoint(ar);
  if (ar.loading()) {
    n_ = x_[0].size();
    if (!particle_lengths_agree<D>(n_, x_, v_, C_, e_, vol_, held_, tag_))
      ar.fail("particles", "particle arrays of different lengths");
    if (!needs_sort_) {
      if (blocks_.key.size() != n_) ar.fail("particles", "block keys for a different particle count");
      blocks_.build(n_, grid_lo_, dx_, walls_);
      fit_to_blocks();
    }
  }
}

template <int D, typename T, bool Flip>
Energy MpmSolver<D, T, Flip>::energy() const {
  double ke = 0, pe = 0, el = 0;
#pragma omp parallel for reduction(+ : ke, pe, el) schedule(static)
  for (size_t i = 0; i < n_; ++i) {
    double v2 = 0, gx = 0;
    for (int d = 0; d < D; ++d) {
      v2 += double(v_[d][i]) * v_[d][i];
      gx += double(gravity_[d]) * x_[d][i];
    }
    const double V = vol_[i], mp = rho_ * V;
    ke += 0.5 * mp * v2;
    pe -= mp * gx;
    el += V * law_d_.energy_density(double(e_[i]));
  }
  return {ke, pe, el, debris_ ? debris_->bodies().energy() : 0.0};
}

template <int D, typename T, bool Flip>
void MpmSolver<D, T, Flip>::particle_positions(std::vector<double>& xyz) const {
  interleave_axes<D>(x_, n_, xyz);
}

template <int D, typename T, bool Flip>
void MpmSolver<D, T, Flip>::particle_velocities(std::vector<double>& vel) const {
  interleave_axes<D>(v_, n_, vel);
}

template <int D, typename T, bool Flip>
void MpmSolver<D, T, Flip>::particle_pressures(std::vector<double>& p) const {
  p.resize(n_);
  for (size_t i = 0; i < n_; ++i) p[i] = law_d_.pressure(double(e_[i]));
}

template <int D, typename T, bool Flip>
void MpmSolver<D, T, Flip>::momentum(double linear[3], double angular[3]) const {
  particles_momentum<D>(n_, rho_, dx_, x_, v_, C_, vol_, linear, angular);
}

template <int D, typename T, bool Flip>
void MpmSolver<D, T, Flip>::set_rigid_velocity(const double v0[3], const double omega[3], const double centre[3]) {
  run_.max_speed = impose_rigid_motion<D>(n_, v0, omega, centre, x_, v_, C_);
  run_.restart_audit(energy());
}

#define FLUME_INSTANTIATE(D, T, Flip)                                                   \
  template void MpmSolver<D, T, Flip>::checkpoint(StateArchive&);                       \
  template Energy MpmSolver<D, T, Flip>::energy() const;                               \
  template void MpmSolver<D, T, Flip>::particle_positions(std::vector<double>&) const;  \
  template void MpmSolver<D, T, Flip>::particle_velocities(std::vector<double>&) const; \
  template void MpmSolver<D, T, Flip>::particle_pressures(std::vector<double>&) const;  \
  template void MpmSolver<D, T, Flip>::momentum(double[3], double[3]) const;            \
  template void MpmSolver<D, T, Flip>::set_rigid_velocity(const double[3], const double[3], const double[3]);
FLUME_MPM_SOLVER_VARIANTS(FLUME_INSTANTIATE)
#undef FLUME_INSTANTIATE

}  // namespace flume::mpm
