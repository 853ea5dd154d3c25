// A symmetry plane (mpm::SymmetryPlane) is exact: half of a mirror-symmetric flow, modelled with the plane,
// moves as that half of the whole does, to round-off. The grid of the half is folded so that every node gets
// what the particles of the other half would have given it, and the water is the same particles as the whole's
// on that side, so the only difference is the order of floating-point sums; the check is that each particle of
// the half sits where a particle of the whole sits, with its velocity. Any treatment of the plane as a wall,
// however good, leaves the first nodes beside it a one-sided stencil and fails this by orders of magnitude: the
// slip plane the half basin used before is run alongside and must be at least a hundred times worse.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "common/errors.h"
#include "solver/scene.h"
#include "solver/simulation.h"
#include "symmetric_tank.h"
#include "test_util.h"

namespace flume {
namespace {

std::string tank(const std::string& span, const std::string& plane, double y_lo) {
  return test::symmetric_tank(span != "full", plane, y_lo, 0.3);
}

struct State {
  std::vector<double> x, v;
  size_t n = 0;
};
State run(const std::string& text) {
  const Scene scene = parse_scene_text(text, "tank.json");
  auto sim = make_simulation(scene, {});
  EXPECT_EQ(test::run_until(*sim, scene.solver.end_time), RunStatus::kOk) << sim->message();
  State s;
  sim->particle_positions(s.x);
  sim->particle_velocities(s.v);
  s.n = sim->particle_count();
  return s;
}

// Largest distance from a particle of the half to the nearest particle of the whole on its side, and the largest
// difference of their velocities.
void compare(const State& half, const State& full, double& dist, double& dv) {
  dist = dv = 0;
  for (size_t i = 0; i < half.n; ++i) {
    double best = 1e30;
    size_t j_best = 0;
    for (size_t j = 0; j < full.n; ++j) {
      double r2 = 0;
      for (int d = 0; d < 3; ++d) r2 += (half.x[3 * i + d] - full.x[3 * j + d]) * (half.x[3 * i + d] - full.x[3 * j + d]);
      if (r2 < best) {
        best = r2;
        j_best = j;
      }
    }
    dist = std::max(dist, std::sqrt(best));
    for (int d = 0; d < 3; ++d) dv = std::max(dv, std::fabs(half.v[3 * i + d] - full.v[3 * j_best + d]));
  }
}

void check(double y_lo) {
  const State full = run(tank("full", "", y_lo));
  const State half = run(tank("half", "symmetry", y_lo));
  const State slip = run(tank("half", "slip", y_lo));
  ASSERT_EQ(2 * half.n, full.n);
  double dist, dv, slip_dist, slip_dv;
  compare(half, full, dist, dv);
  compare(slip, full, slip_dist, slip_dv);
  double vmax = 0;
  for (double u : full.v) vmax = std::max(vmax, std::fabs(u));
  const double dx = 0.02;
  std::printf("after 0.3 s (%zu particles in the whole, top speed %.2f m/s): symmetry plane %.2e m (%.1e dx), "
              "%.2e m/s; slip plane %.2e m (%.1e dx), %.2e m/s\n",
              full.n, vmax, dist, dist / dx, dv, slip_dist, slip_dist / dx, slip_dv);
  // Round-off, amplified by 500 steps of a splashing flow, stays far below a millionth of a cell in double; the
  // bound, 1e-4 dx, is a thousand times below what the one-sided stencil of a wall does to the particles beside it.
  EXPECT_LT(dist, 1e-4 * dx);
  EXPECT_LT(dv, 1e-4 * vmax);
  EXPECT_GT(slip_dist, 100 * dist);
}

TEST(Symmetry, HalfMovesAsTheWholeWithThePlaneOnAGridLine3D) { check(-0.06); }
TEST(Symmetry, HalfMovesAsTheWholeWithThePlaneMidwayBetweenGridLines3D) { check(-0.05); }

// The scene refuses a plane the fold cannot map onto the grid, naming the boundary's field.
TEST(Symmetry, RefusesPlanesOffTheGridOrTheAxes) {
  std::string off = tank("half", "symmetry", -0.055);  // 12.75 cells from domain.lo
  try {
    parse_scene_text(off, "tank.json");
    FAIL() << "accepted a plane 12.75 cells from domain.lo";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("grid line or midway"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("point"), std::string::npos) << e.what();
  }
  std::string tilted = tank("half", "symmetry", -0.06);
  const std::string normal = R"("normal": [0, -1, 0], "condition": "symmetry")";
  tilted.replace(tilted.find(normal), normal.size(), R"("normal": [0.6, -0.8, 0], "condition": "symmetry")");
  try {
    parse_scene_text(tilted, "tank.json");
    FAIL() << "accepted a tilted symmetry plane";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("along a grid axis"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace flume
