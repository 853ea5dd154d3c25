// The CPU backends' AVX2 copy against the portable one (solver/cpu_kernels.h): the same source compiled for
// AVX2 without fused multiply-add must give the same run to the bit, MPM (APIC and FLIP, float and double, 2D
// and 3D) and SPH. Each test builds its solver through both factories directly; skipped where the binary has
// no AVX2 copy or the CPU no AVX2.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>

#include "solver/cpu_kernels.h"
#include "solver/scene.h"
#include "solver/simulation.h"
#include "test_util.h"

namespace flume {

namespace {

bool avx2_here() {
#ifdef FLUME_TEST_AVX2_KERNELS
  return avx2_kernels_built() && cpu_supports_avx2();
#else
  return false;
#endif
}

test::FinalState run(const Scene& scene, bool avx2) {
  SimulationOptions o;
  o.threads = 2;
  const bool sph = scene.solver.method == SolverMethod::kSph;
  std::unique_ptr<Simulation> sim;
#ifdef FLUME_TEST_AVX2_KERNELS
  if (avx2) sim = sph ? make_sph_simulation_avx2(scene, o) : make_cpu_simulation_avx2(scene, o);
#endif
  if (!avx2) sim = sph ? make_sph_simulation_portable(scene, o) : make_cpu_simulation_portable(scene, o);
  EXPECT_EQ(test::run_until(*sim, scene.solver.end_time), RunStatus::kOk) << sim->message();
  return test::final_state(*sim);
}

bool same_series(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (!(a[i] == b[i] || (std::isnan(a[i]) && std::isnan(b[i])))) return false;
  return true;
}

void compare(const Scene& scene) {
  // Both copies exist only in a GCC x86-64 portable build, and the AVX2 one runs only on a CPU with AVX2.
  if (!avx2_here()) GTEST_SKIP() << "no AVX2 copy in this binary, or no AVX2 on this CPU";
  const test::FinalState portable = run(scene, false);
  const test::FinalState avx2 = run(scene, true);
  ASSERT_GT(portable.steps, 50) << "too short a run to compare";
  EXPECT_EQ(avx2.steps, portable.steps);
  EXPECT_TRUE(avx2.xyz == portable.xyz) << "positions differ";
  EXPECT_TRUE(avx2.vel == portable.vel) << "velocities differ";
  EXPECT_TRUE(avx2.p == portable.p) << "pressures differ";
  double moved = 0;  // the water must have moved for the comparison to mean anything
  for (double v : portable.vel) moved = std::max(moved, std::fabs(v));
  EXPECT_GT(moved, 0.1);
  for (const auto& [name, ts] : portable.record.gauges)
    EXPECT_TRUE(same_series(avx2.record.gauges.at(name).values, ts.values)) << name;
  EXPECT_TRUE(avx2.record.diagnostics.at("dt") == portable.record.diagnostics.at("dt"));
  // Energies and loads are OpenMP reductions of doubles, whose order of the threads' parts may vary.
  for (const char* k : {"kinetic", "potential", "elastic", "total"})
    EXPECT_LT(test::rel_diff(portable.record.diagnostics.at(k), avx2.record.diagnostics.at(k)), 1e-12) << k;
  for (const auto& [name, ts] : portable.record.loads)
    EXPECT_LT(test::rel_diff(ts.values, avx2.record.loads.at(name).values), 1e-12) << name;
  std::printf("[ info ] %zu particles, %ld steps: the AVX2 copy's run is the portable one's to the bit\n",
              portable.xyz.size() / 3, portable.steps);
}

Scene tank(const std::string& method, int dimension, const std::string& precision, double flip) {
  const std::string dim3 = R"({"name": "kernels3d", "dimension": 3,
    "domain": {"lo": [0.0, 0.0, 0.0], "hi": [0.6, 0.2, 0.3], "walls": "slip"},
    "solver": {"dx": 0.02, "ppc": 8, "end_time": 0.15},
    "fluid": {"bulk_modulus": 2.0e6, "jbar_psi": 0.9},
    "water": [{"lo": [0.04, 0.04, 0.04], "hi": [0.2, 0.16, 0.2]}],
    "boundaries": [{"name": "column", "type": "box", "lo": [0.26, 0.08, 0.0], "hi": [0.3, 0.12, 0.3]}],
    "instruments": {"gauges": [{"name": "g", "position": [0.3, 0.1]}],
                    "loads": [{"name": "column", "boundary": "column"}]}})";
  const std::string dim2 = R"({"name": "kernels2d", "dimension": 2,
    "domain": {"lo": [0.0, 0.0], "hi": [0.6, 0.3], "walls": "slip"},
    "solver": {"dx": 0.01, "ppc": 4, "end_time": 0.15},
    "fluid": {"bulk_modulus": 2.0e6, "jbar_psi": 0.9},
    "water": [{"lo": [0.02, 0.02], "hi": [0.2, 0.2]}],
    "boundaries": [{"name": "column", "type": "box", "lo": [0.26, 0.0], "hi": [0.3, 0.08]}],
    "instruments": {"gauges": [{"name": "g", "position": [0.3]}],
                    "loads": [{"name": "column", "boundary": "column"}]}})";
  // SPH's steps are the sound's (a tenth of MPM's here): a shorter run, the water still falling at 0.5 m/s.
  return parse_scene_text(dimension == 3 ? dim3 : dim2, "kernels.json",
                          {{"solver.method", method},
                           {"solver.end_time", method == "sph" ? "0.05" : "0.15"},
                           {"solver.precision", precision},
                           {"solver.flip", std::to_string(flip)}});
}

// The choice follows FLUME_CPU_KERNELS where the run sets it (ctest does not), else the CPU.
TEST(CpuKernels, ChosenIsTheBestTheCpuHasUnlessAskedOtherwise) {
  const char* asked = std::getenv("FLUME_CPU_KERNELS");
  const bool avx2 = asked ? std::string(asked) == "avx2" : avx2_here();
  EXPECT_EQ(cpu_kernels(), avx2 ? CpuKernels::kAvx2 : CpuKernels::kPortable);
}

TEST(CpuKernels, Mpm2DFloatApicIsTheSameToTheBit) { compare(tank("mpm", 2, "float", 0)); }
TEST(CpuKernels, Mpm3DFloatApicIsTheSameToTheBit) { compare(tank("mpm", 3, "float", 0)); }
TEST(CpuKernels, Mpm3DFloatFlipIsTheSameToTheBit) { compare(tank("mpm", 3, "float", 0.9)); }
TEST(CpuKernels, Mpm3DDoubleApicIsTheSameToTheBit) { compare(tank("mpm", 3, "double", 0)); }
TEST(CpuKernels, Sph2DFloatIsTheSameToTheBit) { compare(tank("sph", 2, "float", 0)); }
TEST(CpuKernels, Sph3DFloatIsTheSameToTheBit) { compare(tank("sph", 3, "float", 0)); }

}  // namespace
}  // namespace flume
