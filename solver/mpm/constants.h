// The scene's constants the step reads, in the solver's precision T, for both backends (MpmSolver, MpmCuda
// take them as a base, so both read the same names). Host code.
#pragma once
#include "solver/mpm_kernels.h"
#include "solver/scene.h"

namespace flume::mpm {

constexpr int kPad = kBlock;  // nodes of padding below the domain, so every node index is non-negative

template <int D, typename T>
struct SceneConstants {
  explicit SceneConstants(const Scene& scene) {
    dx_ = scene.solver.dx;
    inv_dx_ = T(1) / T(dx_);
    for (int d = 0; d < D; ++d) {
      grid_lo_[d] = scene.domain_lo[d] - kPad * dx_;
      gravity_[d] = T(scene.solver.gravity[d]);
    }
    const auto& f = scene.fluid;
    mu_ = T(f.viscosity);
    psi_ = T(f.jbar_psi);
    flip_ = T(scene.solver.flip);
    law_ = TaitLaw<T>(T(f.bulk_modulus), T(f.gamma));
    law_d_ = TaitLaw<double>(double(law_.K), double(law_.gamma));
    for (int d = 0; d < D; ++d) strain_slope_[d] = T(-f.density * scene.solver.gravity[d] / f.bulk_modulus);
    c_ = sound_speed(f.bulk_modulus, f.density);
  }

  double dx_ = 0;
  T inv_dx_ = 0;
  double grid_lo_[D] = {};  // the grid's node 0, kPad nodes below the domain
  T gravity_[D] = {};
  T mu_ = 0, psi_ = 0;      // viscosity, J-bar blend (mpm::g2p_particle)
  T flip_ = 0;              // FLIP's share (mpm::flip_velocity)
  TaitLaw<T> law_;          // the particle loops copy it into a local: a member is reloaded after every store
  TaitLaw<double> law_d_;   // the same law in double, for the energy audit and diagnostics
  T strain_slope_[D] = {};  // s of mpm::hydrostatic_strain
  double c_ = 0;            // sound speed
};

}  // namespace flume::mpm
