// SPH (solver.method sph, issue 24): the hydrostatic column in 2D and 3D (bottom pressure rho g h within 2 %,
// the surface still to half a particle spacing over 2 s), exact mass, and linear momentum conserved to
// round-off in a closed box without gravity.
//
// The columns run with a sound speed of 14 m/s, ten times sqrt(g h) for h = 0.2 m, as DualSPHysics sets it
// (coefsound 10): the density then varies by rho g h / (rho c0^2) = 1 %, and the step is 10x MPM's default's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "common/errors.h"
#include "solver/scene.h"
#include "solver/simulation.h"
#include "test_util.h"

namespace flume {
namespace {

// One thread: these runs are small enough that a second thread's barriers cost more than it gains on a shared
// machine (the SPH loops give the same result for any thread count: each particle gathers from its
// neighbours).
const SimulationOptions kOneThread{Backend::kCpu, 1};

constexpr double kRho = 1000, kG = 9.80665, kH = 0.2, kW = 0.1;

std::string vec(int dim, double a, int axis, double rest = 0.0) {
  std::string s = "[";
  for (int k = 0; k < dim; ++k) s += std::string(k ? ", " : "") + std::to_string(k == axis ? a : rest);
  return s + "]";
}

// A column kW wide and kH deep on the floor z = 0 between walls, in a domain with room above.
std::string column_scene(int dim, double dx, const std::string& precision, double end_time) {
  // The floor first: a wall particle in a corner, inside the floor and a side wall, belongs to the first
  // boundary that holds it, and the corners' particles carry the floor's load next to the walls.
  std::string loads = R"({"name": "floor", "boundary": "floor", "rate_hz": 50})";
  std::string walls = R"({"name": "floor", "type": "half_space", "point": )" + vec(dim, 0.0, dim - 1) +
                      R"(, "normal": )" + vec(dim, 1.0, dim - 1) + "}";
  for (int d = 0; d < dim - 1; ++d) {
    const std::string axis = std::to_string(d);
    walls += R"(,{"name": "lo)" + axis + R"(", "type": "half_space", "point": )" + vec(dim, 0.0, d) +
             R"(, "normal": )" + vec(dim, 1.0, d) + "}";
    walls += R"(,{"name": "hi)" + axis + R"(", "type": "half_space", "point": )" + vec(dim, kW, d) +
             R"(, "normal": )" + vec(dim, -1.0, d) + "}";
    loads += R"(,{"name": "lo)" + axis + R"(", "boundary": "lo)" + axis + R"(", "rate_hz": 50})";
    loads += R"(,{"name": "hi)" + axis + R"(", "boundary": "hi)" + axis + R"(", "rate_hz": 50})";
  }
  std::string lo = vec(dim, 0.0, -1), hi = vec(dim, kH, dim - 1, kW);
  const double pad = std::max(0.05, 2.5 * dx);  // water at least 2 dx inside the domain
  return R"({"name": "sph_column", "dimension": )" + std::to_string(dim) + R"(,
    "domain": {"lo": )" +
         vec(dim, -pad, -1, -pad) + R"(, "hi": )" + vec(dim, 0.3, dim - 1, kW + pad) + R"(},
    "solver": {"method": "sph", "dx": )" +
         std::to_string(dx) + R"(, "ppc": )" + (dim == 2 ? "4" : "8") + R"(, "precision": ")" + precision +
         R"(", "end_time": )" + std::to_string(end_time) + R"(},
    "fluid": {"bulk_modulus": 2.0e5, "gamma": 7.0, "viscosity": 1.0e-3},
    "water": [{"lo": )" +
         lo + R"(, "hi": )" + hi + R"(}],
    "boundaries": [)" +
         walls + R"(],
    "instruments": {"diagnostics_rate_hz": 10, "loads": [)" +
         loads + R"(]}
  })";
}

// Mean height of the top layer of particles (those within half a spacing of the highest) away from the walls.
double surface_height(const Simulation& sim, int dim, double spacing) {
  std::vector<double> xyz;
  sim.particle_positions(xyz);
  const int up = dim - 1;
  double top = -1e300;
  for (size_t i = 0; i < sim.particle_count(); ++i) top = std::max(top, xyz[3 * i + up]);
  double s = 0;
  int n = 0;
  for (size_t i = 0; i < sim.particle_count(); ++i)
    if (xyz[3 * i + up] > top - 0.5 * spacing) {
      s += xyz[3 * i + up];
      ++n;
    }
  return s / n;
}

// Least-squares p = a + b z over the particles more than one kernel support (2h) from the walls and the
// surface, where the discrete pressure has no boundary layer. Returns {a (the floor's pressure), b}.
std::pair<double, double> pressure_profile(const Simulation& sim, int dim, double edge) {
  std::vector<double> xyz, p;
  sim.particle_positions(xyz);
  sim.particle_pressures(p);
  const int up = dim - 1;
  double sz = 0, sp = 0, szz = 0, szp = 0;
  size_t n = 0;
  for (size_t i = 0; i < sim.particle_count(); ++i) {
    const double z = xyz[3 * i + up];
    bool interior = z > edge && z < kH - edge;
    for (int d = 0; d < up; ++d) interior &= xyz[3 * i + d] > edge && xyz[3 * i + d] < kW - edge;
    if (!interior) continue;
    sz += z;
    sp += p[i];
    szz += z * z;
    szp += z * p[i];
    ++n;
  }
  if (n < 3) return {std::nan(""), std::nan("")};
  const double b = (n * szp - sz * sp) / (n * szz - sz * sz);
  return {(sp - b * sz) / n, b};
}

// The bottom pressure is the floor's load (the wall particles' reaction, as a pressure sensor in the floor
// reads it) over the floor's area, averaged over the last 0.2 s: a dozen periods of the column's acoustic
// oscillation (4h / c0 = 0.06 s). The interior pressure profile (pressure_profile) is printed beside it.
// `floor_only`: the bottom pressure is the floor's load alone; else all the walls' vertical load (at 5
// particles across, in 3D, the wall particles in the corners, inside both the floor and a side wall, take a
// share of the floor's load that depends on which boundary they are counted to: 8 % more on the floor with
// the floor first).
void check_column(int dim, double dx, const std::string& precision, bool floor_only) {
  const double end = 2.0;
  const Scene scene = parse_scene_text(column_scene(dim, dx, precision, end), "sph_column.json");
  auto sim = make_simulation(scene, kOneThread);
  const double spacing = dx / 2;  // ppc 4 in 2D, 8 in 3D: two particles per cell and axis
  const double h = std::sqrt(double(dim)) * spacing;
  const double z0 = surface_height(*sim, dim, spacing);
  const double mass0 = sim->total_mass();
  ASSERT_EQ(test::run_until(*sim, end - 0.2), RunStatus::kRunning) << sim->message();
  double p0 = 0, slope = 0;
  int fits = 0;
  RunStatus st = RunStatus::kRunning;
  while (st == RunStatus::kRunning) {
    st = sim->step();
    if (sim->steps() % 10) continue;
    const auto [a, b] = pressure_profile(*sim, dim, 2 * h);
    p0 += a;
    slope += b;
    ++fits;
  }
  ASSERT_EQ(st, RunStatus::kOk) << sim->message();
  p0 /= fits;
  slope /= fits;
  // The walls' vertical load over the last 0.2 s, averaged: the floor's alone, and all the walls' together.
  auto mean_vertical = [&](const TimeSeries& load) {
    double f = 0;
    int samples = 0;
    for (size_t i = 0; i < load.size(); ++i)
      if (load.time[i] > end - 0.2 + 1e-9) {
        f += load.at(i, dim - 1);
        ++samples;
      }
    return f / samples;
  };
  double tank = 0;
  for (const auto& [name, load] : sim->record().loads) tank += mean_vertical(load);
  const double area = dim == 2 ? kW : kW * kW;
  const double floor_p = -mean_vertical(sim->record().loads.at("floor")) / area;  // the water pushes it down
  const double tank_p = -tank / area;
  const double z1 = surface_height(*sim, dim, spacing);
  std::printf(
      "%dD %s: floor pressure %.1f Pa, all walls' load %.1f Pa (rho g h = %.1f); interior fit: %.1f Pa at z "
      "= 0, slope %.1f Pa/m "
      "(-rho g = %.1f); surface moved %.3g spacings; %ld steps\n",
      dim, precision.c_str(), floor_p, tank_p, kRho * kG * kH, p0, slope, -kRho * kG, (z1 - z0) / spacing,
      sim->steps());
  EXPECT_NEAR(floor_only ? floor_p : tank_p, kRho * kG * kH, 0.02 * kRho * kG * kH);
  EXPECT_LT(std::fabs(z1 - z0), 0.5 * spacing);
  EXPECT_EQ(sim->total_mass(), mass0);
}

TEST(SphHydrostatic, Column2D) { check_column(2, 0.01, "double", true); }
// 3D at 10 particles of depth (5 across: no interior two supports from every wall, so only the floor's load
// and the surface are checked), to keep the test within a minute.
TEST(SphHydrostatic, Column3D) { check_column(3, 0.04, "float", false); }

// Mass: every particle keeps its mass, and the water's is rho times its boxes' volume.
TEST(SphConservation, MassIsExact) {
  const Scene scene = parse_scene_text(column_scene(2, 0.01, "double", 0.05), "sph_column.json");
  auto sim = make_simulation(scene, kOneThread);
  const double m0 = sim->total_mass();
  EXPECT_NEAR(m0, kRho * kW * kH, 1e-12 * m0);
  ASSERT_EQ(test::run_until(*sim, 0.05), RunStatus::kOk) << sim->message();
  EXPECT_EQ(sim->total_mass(), m0);
}

// A spinning, drifting square of water in a closed box without gravity, far from the walls: the pair forces
// are antisymmetric, so the water's linear momentum changes only by round-off. Its bound: a few ulps of the
// largest momentum a particle pair exchanges over the run, summed over the particles.
TEST(SphConservation, LinearMomentumWithoutGravity) {
  const std::string text = R"({"name": "sph_blob", "dimension": 2,
    "domain": {"lo": [-0.3, -0.3], "hi": [0.4, 0.4]},
    "solver": {"method": "sph", "dx": 0.01, "ppc": 4, "precision": "double", "end_time": 0.1, "gravity": [0, 0]},
    "fluid": {"bulk_modulus": 2.0e5, "gamma": 7.0, "viscosity": 1.0e-3},
    "water": [{"lo": [0.0, 0.0], "hi": [0.1, 0.1], "hydrostatic": false}]
  })";
  const Scene scene = parse_scene_text(text, "sph_blob.json");
  auto sim = make_simulation(scene, kOneThread);
  const double v0[3] = {0.2, -0.1, 0}, omega[3] = {0, 0, 3.0}, centre[3] = {0.05, 0.05, 0};
  sim->set_rigid_velocity(v0, omega, centre);
  double L0[3], A0[3];
  sim->momentum(L0, A0);
  ASSERT_EQ(test::run_until(*sim, 0.1), RunStatus::kOk) << sim->message();
  double L1[3], A1[3];
  sim->momentum(L1, A1);
  const double scale = std::hypot(L0[0], L0[1]);
  std::printf("linear momentum: (%.17g, %.17g) -> (%.17g, %.17g) kg m/s over %ld steps\n", L0[0], L0[1],
              L1[0], L1[1], sim->steps());
  const double eps = std::numeric_limits<double>::epsilon();
  for (int d = 0; d < 2; ++d)
    EXPECT_LE(std::fabs(L1[d] - L0[d]), 100 * eps * scale * std::sqrt(double(sim->steps()))) << "axis " << d;
}

// solver.method: mpm unless the scene says sph; any other value is one line of input error naming the field.
TEST(SphScene, MethodIsRead) {
  const std::string base = column_scene(2, 0.01, "double", 0.01);
  EXPECT_EQ(parse_scene_text(base, "c.json").solver.method, SolverMethod::kSph);
  EXPECT_EQ(parse_scene_text(base, "c.json", {{"solver.method", "mpm"}}).solver.method, SolverMethod::kMpm);
  try {
    parse_scene_text(base, "c.json", {{"solver.method", "lbm"}});
    FAIL() << "solver.method lbm was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("solver.method"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace flume
