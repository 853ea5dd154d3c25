// A water box in rigid rotation, for the angular-momentum checks every backend runs (test_conservation for
// the CPU, test_cuda for the CUDA source): the scene of a blob spinning in free space and the angular
// momentum that theory gives it, orbital part and APIC spin (docs/solver.md, "Angular momentum of a
// particle").
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "solver/scene.h"
#include "solver/simulation.h"

namespace flume::test {

// A water box of half-width `half` centred at the origin, in a domain of half-width 1 m, no gravity: the
// walls are many blob widths away, so no wall node receives mass while it spins.
inline Scene free_blob(int dim, double dx, double half, double bulk_modulus = 2.0e6) {
  auto vec = [dim](double v) {
    std::string s = "[";
    for (int d = 0; d < dim; ++d) s += std::string(d ? ", " : "") + std::to_string(v);
    return s + "]";
  };
  const std::string text = R"({"name": "free_blob", "dimension": )" + std::to_string(dim) + R"(,
    "domain": {"lo": )" + vec(-1) +
                           R"(, "hi": )" + vec(1) + R"(},
    "solver": {"dx": )" + std::to_string(dx) +
                           R"(, "ppc": )" + (dim == 2 ? "4" : "8") +
                           R"(, "cfl": 0.4, "precision": "double", "end_time": 10.0, "gravity": )" + vec(0) +
                           R"(},
    "fluid": {"density": 1000, "bulk_modulus": )" +
                           std::to_string(bulk_modulus) +
                           R"(, "gamma": 7.0, "viscosity": 1.0e-3, "jbar_psi": 0.5},
    "water": [{"lo": )" + vec(-half) +
                           R"(, "hi": )" + vec(half) + R"(}],
    "instruments": {"diagnostics_rate_hz": 1000}
  })";
  return parse_scene_text(text, "free_blob.json");
}

// The angular momentum about the origin of the scene's single water box turning rigidly at omega about its
// own centre (Simulation::set_rigid_velocity with v0 = 0), from the lattice the box is seeded with
// (solver/seeding.h; the box a whole number n of spacings h long on each axis, asserted), of total mass
// M:
//  - orbital: sum m r x (omega x r) = I omega, with the lattice's inertia I_aa = sum_{b != a} S_b, where
//    S_b = M (L_b^2 - h_b^2) / 12 is the second moment of n equally spaced points (the box's L^2/12, less the
//    spacing's h^2/12), and no products of inertia (the lattice is symmetric about the centre);
//  - APIC spin: per particle m dx^2/2 omega for the affine field C = [omega]x of quadratic B-splines
//    (D_p = dx^2/4 I; Jiang et al. 2015, eq. 26 and section 5.3).
// The box's centre moves with v0 = 0, so the total does not depend on the origin.
inline void rigid_box_angular_momentum(const Scene& scene, double M, const double omega[3], double L[3]) {
  const int D = scene.dimension;
  const auto& box = scene.water.at(0);
  const double spacing = particle_spacing(scene);
  double S[3] = {0, 0, 0};
  for (int d = 0; d < D; ++d) {
    const double len = box.hi[d] - box.lo[d];
    const double h = len / std::max(1L, std::lround(len / spacing));
    EXPECT_NEAR(h, spacing, 1e-12) << "the formula is the whole lattice's";
    S[d] = M * (len * len - h * h) / 12;
  }
  const double spin = M * scene.solver.dx * scene.solver.dx / 2;
  for (int a = 0; a < 3; ++a) {
    double I = 0;
    for (int b = 0; b < 3; ++b)
      if (b != a) I += S[b];
    L[a] = (I + spin) * omega[a];
  }
  if (D == 2) L[0] = L[1] = 0;  // in 2D only the out-of-plane axis turns
}

// Sets the blob of free_blob turning at omega about its centre and checks the backend's angular momentum
// against rigid_box_angular_momentum. Both parts are sums of n positive terms in double: 1e-12 of |L| is ~1e4
// ulps of round-off, while a spin of the wrong sign is off by M dx^2 |omega|, 2.4 % of |L| for the 2D blob at
// dx 0.005 m.
inline void expect_rigid_rotation_angular_momentum(Simulation& sim, const Scene& scene,
                                                   const double omega[3]) {
  const double v0[3] = {0, 0, 0}, centre[3] = {0, 0, 0};
  sim.set_rigid_velocity(v0, omega, centre);
  double linear[3], angular[3], expected[3];
  sim.momentum(linear, angular);
  rigid_box_angular_momentum(scene, sim.total_mass(), omega, expected);
  const double L0 =
      std::sqrt(expected[0] * expected[0] + expected[1] * expected[1] + expected[2] * expected[2]);
  const double spin = sim.total_mass() * scene.solver.dx * scene.solver.dx / 2;
  for (int d = 0; d < 3; ++d) {
    EXPECT_NEAR(angular[d], expected[d], 1e-12 * L0)
        << "axis " << d << " (the APIC spin is " << spin * omega[d] << ")";
    EXPECT_NEAR(linear[d], 0.0, 1e-12 * L0 / scene.solver.dx);
  }
}

// Largest |L(t) - L(0)| / |L(0)| over `steps` steps of the blob spinning at omega about its centre (the
// caller checks the blob stayed clear of the walls).
inline double spinning_blob_drift(Simulation& sim, const double omega[3], int steps) {
  const double v0[3] = {0, 0, 0}, centre[3] = {0, 0, 0};
  sim.set_rigid_velocity(v0, omega, centre);
  double linear[3], a[3], b[3];
  sim.momentum(linear, a);
  const double L0 = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  double worst = 0;
  for (int s = 0; s < steps; ++s) {
    EXPECT_EQ(sim.step(), RunStatus::kRunning) << sim.message();
    sim.momentum(linear, b);
    double d2 = 0;
    for (int d = 0; d < 3; ++d) d2 += (b[d] - a[d]) * (b[d] - a[d]);
    worst = std::max(worst, std::sqrt(d2) / L0);
  }
  return worst;
}

}  // namespace flume::test
