// The CUDA backend against the CPU backend (issue 2: one physics source for OpenMP and CUDA).
//
// Both backends run the same discrete step from the same mpm_kernels.h functions; they differ only in the
// order in which P2G sums a node's contributions (the CPU's per-block tiles against the GPU's atomics) and,
// on a GPU, in the compiler's FMA contraction. So in double they must agree to round-off growing over the
// run, and in float to float round-off; the bounds below follow from that, with the margins stated where
// they are set. Particles are sorted by the same stable key sort from the same seeding order, so the i-th
// particle is the same particle in both runs and positions are compared one by one.
//
// Three groups:
//  - CudaCli: `flume run --backend cuda` on a machine without a device exits 2 with a one-line message.
//  - CudaEmulation: the CUDA backend's source compiled for the host against Thrust's sequential system
//    (make_cuda_host_emulation). Runs everywhere the CUDA toolkit is installed, GPU or not: it checks the
//    block-sparse bookkeeping, the scatter/gather indexing and every formula of mpm_cuda.cu.
//  - Cuda: the real device, skipped (GTEST_SKIP) without one.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>

#include "rotation.h"
#include "solver/cuda/mpm_cuda.h"
#include "solver/run.h"
#include "solver/scene.h"
#include "solver/simulation.h"
#include "solver/debris_coupling.h"
#include "symmetric_tank.h"
#include "tank_scene.h"
#include "test_util.h"

namespace flume {
namespace {

constexpr double kRho = 1000, kG = 9.80665;
constexpr double kA = 0.05715;  // Martin & Moyce column width (m)

// The checkout and the flume executable; the environment may override where the tests run on another machine
// (bench/run_gpu_bench.sh carries them to the GPU machine).
std::string source_dir() {
  const char* e = std::getenv("FLUME_SOURCE_DIR");
  return e ? e : FLUME_SOURCE_DIR;
}
std::string flume_exe() {
  const char* e = std::getenv("FLUME_EXE");
  return e ? e : FLUME_EXE;
}

using Factory = std::function<std::unique_ptr<Simulation>(const Scene&)>;

std::unique_ptr<Simulation> cpu(const Scene& s) { return make_simulation(s, {}); }
using test::gpu;
#ifdef FLUME_CUDA_EMULATION_AVAILABLE
std::unique_ptr<Simulation> emulated(const Scene& s) { return make_cuda_host_emulation(s, {}); }
#endif

// A column of water H = 0.2 m high, 0.1 m wide, at rest on a slip floor between slip walls (the hydrostatic
// test's scene), with a load cell and a pressure probe on the floor and a velocity probe and a gauge mid-column
// (the probes and the gauge are summed on the device: solver/particle_sums.h).
Scene column(int dim, const std::string& precision, double end_time) {
  const bool d2 = dim == 2;
  std::string walls;
  for (int d = 0; d < dim - 1; ++d) {
    auto vec = [&](double a, int axis) {
      std::string s = "[";
      for (int k = 0; k < dim; ++k) s += std::string(k ? ", " : "") + (k == axis ? std::to_string(a) : "0.0");
      return s + "]";
    };
    walls += R"({"type": "half_space", "point": )" + vec(0.0, d) + R"(, "normal": )" + vec(1.0, d) +
             R"(, "condition": "slip"},)";
    walls += R"({"type": "half_space", "point": )" + vec(0.1, d) + R"(, "normal": )" + vec(-1.0, d) +
             R"(, "condition": "slip"},)";
  }
  walls += R"({"name": "floor", "type": "half_space", "point": )" +
           std::string(d2 ? "[0.0, 0.0]" : "[0.0, 0.0, 0.0]") + R"(, "normal": )" +
           std::string(d2 ? "[0.0, 1.0]" : "[0.0, 0.0, 1.0]") + R"(, "condition": "slip"})";
  const std::string text = R"({"name": "column", "dimension": )" + std::to_string(dim) + R"(,
    "domain": {"lo": )" + std::string(d2 ? "[-0.04, -0.04]" : "[-0.04, -0.04, -0.04]") +
                           R"(, "hi": )" + (d2 ? "[0.14, 0.3]" : "[0.14, 0.14, 0.3]") + R"(},
    "solver": {"dx": 0.01, "ppc": )" +
                           (d2 ? "4" : "8") + R"(, "cfl": 0.4, "precision": ")" + precision +
                           R"(", "end_time": )" + std::to_string(end_time) + R"(},
    "fluid": {"bulk_modulus": 2.0e6, "gamma": 7.0, "viscosity": 1.0e-3, "jbar_psi": 0.9},
    "water": [{"lo": )" + (d2 ? "[0.0, 0.0]" : "[0.0, 0.0, 0.0]") +
                           R"(, "hi": )" + (d2 ? "[0.1, 0.2]" : "[0.1, 0.1, 0.2]") +
                           R"(, "hydrostatic": false}],
    "boundaries": [)" + walls +
                           R"(],
    "instruments": {"loads": [{"name": "floor", "boundary": "floor", "rate_hz": 100}],
                    "probes": [{"name": "mid", "position": )" +
                           (d2 ? "[0.05, 0.1]" : "[0.05, 0.05, 0.1]") + R"(}],
                    "gauges": [{"name": "G", "position": )" + (d2 ? "[0.05]" : "[0.05, 0.05]") + R"(}],
                    "pressure_probes": [{"name": "PS", "position": )" +
                           (d2 ? "[0.05, 0.0]" : "[0.05, 0.05, 0.0]") + R"(, "normal": )" +
                           (d2 ? "[0.0, 1.0]" : "[0.0, 0.0, 1.0]") + R"(, "rate_hz": 100}]}
  })";
  return parse_scene_text(text, "column.json");
}

Scene martin_moyce(double dx, const std::string& precision) {
  return load_scene(source_dir() + "/scenes/dam_break/martin_moyce_2d.json",
                    {{"solver.dx", std::to_string(dx)},
                     {"solver.precision", precision},
                     {"instruments.snapshot_rate_hz", "0"}});
}

// Half a dam break in a 3D tank with a symmetry plane at y = 0.2 m midway between grid lines (symmetric_tank.h)
// and a column across it, with a load cell on the column: the fold, the mirror beyond the plane and the
// particles' images.
Scene half_tank(double end_time) {
  return parse_scene_text(test::symmetric_tank(true, "symmetry", -0.05, end_time, 0.3), "half_tank.json");
}

// What two backends' runs of one scene differ by.
struct Difference {
  double position = 0;    // largest |x_a - x_b| over particles and axes (m)
  double pressure = 0;    // largest |p_a - p_b| over particles (Pa)
  double front = 0;       // largest difference of the leading edge (largest x) over the run's steps (m)
  double floor_load = 0;  // largest difference of the floor load cell's samples, relative to the weight
  double gauge = 0;       // largest difference of gauge samples (m)
  double probe = 0;       // largest difference of probe samples (m/s)
  double pressure_probe = 0;  // largest difference of pressure probe samples (Pa)
  double energy = 0;  // largest difference of the total energy diagnostic, relative to the potential energy
  double body = 0;    // largest difference of a debris body's centre over the run's steps (m)
  long steps_a = 0, steps_b = 0;
};

double max_series_diff(const std::map<std::string, TimeSeries>& a,
                       const std::map<std::string, TimeSeries>& b) {
  double d = 0;
  for (const auto& [name, ta] : a) {
    const TimeSeries& tb = b.at(name);
    EXPECT_EQ(ta.size(), tb.size()) << name;
    for (size_t i = 0; i < std::min(ta.values.size(), tb.values.size()); ++i)
      if (!(std::isnan(ta.values[i]) && std::isnan(tb.values[i])))
        d = std::max(d, std::fabs(ta.values[i] - tb.values[i]));
  }
  return d;
}

// Runs the scene to its end with both backends in lockstep and compares them.
Difference compare(const Scene& scene, const Factory& make_a, const Factory& make_b) {
  auto a = make_a(scene);
  auto b = make_b(scene);
  EXPECT_EQ(a->particle_count(), b->particle_count());
  EXPECT_DOUBLE_EQ(a->total_mass(), b->total_mass());
  Difference r;
  std::vector<double> xa, xb;
  RunStatus sa = RunStatus::kRunning, sb = RunStatus::kRunning;
  while (sa == RunStatus::kRunning && sb == RunStatus::kRunning) {
    sa = a->step();
    sb = b->step();
    a->particle_positions(xa);
    b->particle_positions(xb);
    double fa = -1e300, fb = -1e300;
    for (size_t i = 0; i < a->particle_count(); ++i) {
      fa = std::max(fa, xa[3 * i]);
      fb = std::max(fb, xb[3 * i]);
    }
    r.front = std::max(r.front, std::fabs(fa - fb));
    if (a->debris() && b->debris())
      for (int k = 0; k < a->debris()->body_count(); ++k)
        r.body = std::max(r.body, (a->debris()->world().state(k).position -
                                   b->debris()->world().state(k).position).norm());
  }
  EXPECT_EQ(a->debris() != nullptr, b->debris() != nullptr);
  EXPECT_EQ(sa, RunStatus::kOk) << a->message();
  EXPECT_EQ(sb, RunStatus::kOk) << b->message();
  r.steps_a = a->steps();
  r.steps_b = b->steps();
  std::vector<double> pa, pb;
  a->particle_pressures(pa);
  b->particle_pressures(pb);
  for (size_t i = 0; i < std::min(xa.size(), xb.size()); ++i)
    r.position = std::max(r.position, std::fabs(xa[i] - xb[i]));
  for (size_t i = 0; i < std::min(pa.size(), pb.size()); ++i)
    r.pressure = std::max(r.pressure, std::fabs(pa[i] - pb[i]));
  const Record &ra = a->record(), &rb = b->record();
  const double weight = a->total_mass() * kG;
  r.floor_load = max_series_diff(ra.loads, rb.loads) / weight;
  r.gauge = max_series_diff(ra.gauges, rb.gauges);
  r.probe = max_series_diff(ra.probes, rb.probes);
  r.pressure_probe = max_series_diff(ra.pressures, rb.pressures);
  const auto& ea = ra.diagnostics.at("total");
  const auto& eb_total = rb.diagnostics.at("total");
  const double pe0 = std::fabs(ra.diagnostics.at("potential").front());
  EXPECT_EQ(ea.size(), eb_total.size());
  for (size_t i = 0; i < std::min(ea.size(), eb_total.size()); ++i)
    r.energy = std::max(r.energy, std::fabs(ea[i] - eb_total[i]) / pe0);
  std::printf(
      "%s %s %dD: %ld/%ld steps; max differences: position %.3e m, pressure %.3e Pa, front %.3e m, "
      "floor load %.3e (of weight), gauge %.3e m, probe %.3e m/s, pressure probe %.3e Pa, energy %.3e (of "
      "potential), debris %.3e m\n",
      scene.name.c_str(), to_string(scene.solver.precision), scene.dimension, r.steps_a, r.steps_b,
      r.position, r.pressure, r.front, r.floor_load, r.gauge, r.probe, r.pressure_probe, r.energy, r.body);
  return r;
}

// Round-off bounds. In double a step's P2G sums differ by summation order, ~1e-16 relative, and the runs
// below (up to ~4000 steps) let that grow at most to ~1e-12 relative in a damped flow; the bounds take 1e-9
// of the natural scale (dx for positions, rho g H for pressures, the weight for loads): three orders of
// margin over round-off, six orders below anything a validation test resolves. On a GPU the order also
// changes from run to run (atomics) and FMA contraction adds the same size of difference: the same bounds
// times 10. In float the same reasoning with 6e-8 per operation gives 1e-3 of the natural scale, checked on a
// GPU only.
struct Bounds {
  double position, pressure, front, load, gauge, probe, energy, body;
};
Bounds double_bounds(double dx, double head, double scale = 1) {
  const double p = kRho * kG * head;
  return {1e-9 * dx * scale, 1e-9 * p * scale, 1e-9 * dx * scale, 1e-9 * scale,
          1e-9 * dx * scale, 1e-9 * scale,     1e-9 * scale,      1e-9 * dx * scale};
}
Bounds float_bounds(double dx, double head) {
  const double p = kRho * kG * head;
  return {1e-3 * dx, 1e-3 * p, 1e-3 * dx, 1e-3, 1e-3 * dx, 1e-3, 1e-3, 1e-3 * dx};
}

void expect_within(const Difference& d, const Bounds& b) {
  EXPECT_EQ(d.steps_a, d.steps_b) << "the adaptive steps must agree";
  EXPECT_LE(d.position, b.position) << "particle positions";
  EXPECT_LE(d.pressure, b.pressure) << "particle pressures";
  EXPECT_LE(d.front, b.front) << "front position";
  EXPECT_LE(d.floor_load, b.load) << "floor load cell";
  EXPECT_LE(d.gauge, b.gauge) << "gauges";
  EXPECT_LE(d.probe, b.probe) << "probes";
  EXPECT_LE(d.pressure_probe, b.pressure) << "pressure probes";
  EXPECT_LE(d.energy, b.energy) << "energy diagnostic";
  EXPECT_LE(d.body, b.body) << "debris centres";
}

// A dam break at CFL 5 blows up (issue 2, item 6): both backends must stop at the same step, for the same
// reason, naming the same particle.
void expect_same_instability(const Factory& make_b) {
  const Scene scene = martin_moyce(kA / 10, "double");
  Scene unstable = scene;
  unstable.solver.cfl = 5;
  auto a = cpu(unstable);
  auto b = make_b(unstable);
  EXPECT_EQ(test::run_until(*a, unstable.solver.end_time), RunStatus::kUnstable);
  EXPECT_EQ(test::run_until(*b, unstable.solver.end_time), RunStatus::kUnstable);
  EXPECT_EQ(a->steps(), b->steps());
  const std::string ma = a->message(), mb = b->message();
  std::printf("cpu:  %s\nother: %s\n", ma.c_str(), mb.c_str());
  // Up to the energy figures, which are printed to 6 digits and may differ in the last by round-off.
  EXPECT_EQ(ma.substr(0, ma.find("): total")), mb.substr(0, mb.find("): total")));
  EXPECT_EQ(ma.substr(ma.find(", particle")), mb.substr(mb.find(", particle")));
}

// The Waseda basin's boxes: a node inside the 0.04 m gate panel is held by both of its faces, one at the quay's
// top edge by the top and the front (mpm::wall_faces); the bore passes the gate within the 0.8 s.
Scene waseda_gate_and_quay() {
  return load_scene(source_dir() + "/scenes/waseda/waseda_2d.json",
                    {{"solver.dx", "0.04"}, {"solver.precision", "double"}, {"solver.end_time", "0.8"}});
}

// The Waseda apron fed through the inflow boundary (solver/inflow.h) by a section the full basin recorded:
// the buffer's lattice, the particles it adds and removes, and the re-sorts they force. The bore crosses the
// inflow plane from about 2.3 s. `scale`: the bounds' (10 on a device).
void expect_inflow_apron_matches_cpu(const Factory& other, double scale) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("flume_cuda_inflow_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const Scene feed = load_scene(source_dir() + "/scenes/waseda/waseda_2d.json",
                                {{"solver.dx", "0.04"}, {"solver.end_time", "2.6"}});
  ASSERT_EQ(run_scene(feed, {}, (dir / "feed").string()).status, RunStatus::kOk);
  const Scene apron = load_scene(source_dir() + "/scenes/waseda/waseda_apron_2d.json",
                                 {{"solver.dx", "0.04"},
                                  {"solver.precision", "double"},
                                  {"solver.end_time", "2.6"},
                                  {"inflow.record", (dir / "feed" / "result.h5").string()}});
  expect_within(compare(apron, cpu, other), double_bounds(0.04, 0.9, scale));
  std::filesystem::remove_all(dir);
}

// Free rotation conserves the total angular momentum, orbital plus spin, to round-off (the CPU's test runs 1000
// steps; 200 here, as the emulation is single-threaded): the two parts trade as the square blob rounds, so a
// spin of the wrong sign drifts. `scale`: the bound's (10 on a device).
void expect_spinning_blob_conserves(const Factory& make, double scale) {
  for (int dim : {2, 3}) {
    SCOPED_TRACE(std::to_string(dim) + "D");
    auto sim = make(test::free_blob(dim, dim == 2 ? 0.005 : 0.02, 0.1));
    const double omega[3] = {dim == 3 ? 3.0 : 0.0, dim == 3 ? -4.0 : 0.0, 10.0};
    const double worst = test::spinning_blob_drift(*sim, omega, 200);
    std::printf("[ info ] %dD: 200 steps to t = %.4f s: max |L - L0| / |L0| = %.2e\n", dim, sim->time(),
                worst);
    EXPECT_LT(worst, 1e-11 * scale);
  }
}

// --- the command line without a device ---

TEST(CudaCli, RunWithoutDeviceExitsTwoWithOneLine) {
  if (cuda_available()) GTEST_SKIP() << "a CUDA device is present: `flume run --backend cuda` runs instead";
  // The flume executable is a build dependency of this test (tests/solver/CMakeLists.txt): its absence is a
  // broken build, not a missing device, so it fails rather than skips.
  ASSERT_TRUE(std::filesystem::exists(flume_exe())) << "no flume executable at " << flume_exe();
  const auto dir = std::filesystem::temp_directory_path() / ("flume_cuda_cli_" + std::to_string(::getpid()));
  const std::string err = (dir / "stderr.txt").string();
  std::filesystem::create_directories(dir);
  const int rc = test::run_command(flume_exe() + " run " + source_dir() +
                                   "/scenes/dam_break/martin_moyce_2d.json --out " + (dir / "out").string() +
                                   " --backend cuda 2> " + err);
  const std::string text = test::read_text(err);
  std::filesystem::remove_all(dir);
  EXPECT_EQ(rc, 2) << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
  EXPECT_NE(text.find("--backend"), std::string::npos) << text;
  EXPECT_NE(text.find("cuda"), std::string::npos) << text;
  std::printf("%s", text.c_str());
}

TEST(CudaCli, DevicePresenceIsAnAnswerNotAnError) {
  // Must return, not throw or abort, with or without a driver.
  const bool present = cuda_available();
  std::printf("CUDA device present: %s\n", present ? "yes" : "no");
  SUCCEED();
}

// --- the CUDA backend's source on the host ---

#ifdef FLUME_CUDA_EMULATION_AVAILABLE
TEST(CudaEmulation, HydrostaticColumn2DDoubleMatchesCpu) {
  expect_within(compare(column(2, "double", 0.2), cpu, emulated), double_bounds(0.01, 0.2));
}
TEST(CudaEmulation, HydrostaticColumn3DDoubleMatchesCpu) {
  expect_within(compare(column(3, "double", 0.02), cpu, emulated), double_bounds(0.01, 0.2));
}
TEST(CudaEmulation, MartinMoyce2DDoubleMatchesCpu) {
  expect_within(compare(martin_moyce(kA / 10, "double"), cpu, emulated), double_bounds(kA / 10, 2 * kA));
}
TEST(CudaEmulation, InstabilityMatchesCpu) { expect_same_instability(emulated); }
TEST(CudaEmulation, WasedaGateAndQuay2DDoubleMatchesCpu) {
  expect_within(compare(waseda_gate_and_quay(), cpu, emulated), double_bounds(0.04, 0.9));
}
TEST(CudaEmulation, InflowApron2DDoubleMatchesCpu) { expect_inflow_apron_matches_cpu(emulated, 1); }
// FLIP (solver.flip): the old velocity's channels in both backends' scatters, the symmetry fold of them (the
// half tank) and the 3D solver with 16 lanes on the CPU.
Scene with_flip(Scene s) {
  s.solver.flip = 0.9;
  return s;
}
TEST(CudaEmulation, WasedaGateAndQuay2DDoubleWithFlipMatchesCpu) {
  expect_within(compare(with_flip(waseda_gate_and_quay()), cpu, emulated), double_bounds(0.04, 0.9));
}
TEST(CudaEmulation, SymmetryPlane3DDoubleWithFlipMatchesCpu) {
  expect_within(compare(with_flip(half_tank(0.15)), cpu, emulated), double_bounds(0.02, 0.3));
}
TEST(CudaEmulation, SymmetryPlane3DDoubleMatchesCpu) {
  expect_within(compare(half_tank(0.15), cpu, emulated), double_bounds(0.02, 0.3));
}
// The angular momentum diagnostic's APIC spin against theory (rotation.h; the CPU's in test_conservation):
// the CUDA source had it with the opposite sign.
TEST(CudaEmulation, RigidRotationAngularMomentumMatchesTheory) {
  for (int dim : {2, 3}) {
    SCOPED_TRACE(std::to_string(dim) + "D");
    const Scene scene = dim == 2 ? test::free_blob(2, 0.005, 0.1) : test::free_blob(3, 0.02, 0.1);
    auto sim = emulated(scene);
    const double omega[3] = {dim == 3 ? 3.0 : 0.0, dim == 3 ? -4.0 : 0.0, 10.0};
    test::expect_rigid_rotation_angular_momentum(*sim, scene, omega);
  }
}
TEST(CudaEmulation, AngularMomentumOfASpinningBlob) { expect_spinning_blob_conserves(emulated, 1); }
// Debris: a box of 600 kg/m^3 dropped from 3 cm above a still tank's surface hits it at 0.08 s and plunges:
// the coupling nodes round the box, the implicit exchange, the particles pushed out of the moving box and the
// box's energy in the audit.
Scene falling_box() {  // in double (the tank scene's default precision)
  return parse_scene_text(test::tank_scene(0.2, 0.1, 0.06, 600.0, 0.16, 0.02, 0.15), "falling_box.json");
}
// The water must have stopped part of the fall for the comparison to mean anything: at the end the box falls
// slower than in free fall by more than a tenth.
void expect_water_slowed_the_box(const Simulation& sim) {
  const double v = sim.debris()->world().state(0).velocity.z(), free_fall = -kG * sim.time();
  std::printf("box's vertical velocity at %.3f s: %.3f m/s (free fall %.3f m/s)\n", sim.time(), v, free_fall);
  EXPECT_GT(v, 0.9 * free_fall);
}
TEST(CudaEmulation, FallingBox3DDoubleMatchesCpu) {
  const Scene scene = falling_box();
  expect_within(compare(scene, cpu, emulated), double_bounds(0.02, 0.1));
  auto sim = emulated(scene);
  ASSERT_EQ(test::run_until(*sim, scene.solver.end_time), RunStatus::kOk);
  expect_water_slowed_the_box(*sim);
}
// The 3D strip of the Waseda basin with its three containers: the vacuum's hold on the reservoir, the gate
// and the quay as 3D boxes, the containers' bands and films on the dry apron, until just before the bore
// reaches them (the first contacts then amplify round-off through Bullet's contact solve, so later states
// are compared by runs, not step by step: bench/run_gpu_bench.sh flume-runs).
Scene waseda_strip(const std::string& precision, double end_time) {
  return load_scene(source_dir() + "/scenes/waseda/waseda_strip.json",
                    {{"solver.precision", precision}, {"solver.end_time", std::to_string(end_time)}});
}
TEST(CudaEmulation, WasedaStrip3DDoubleMatchesCpu) {
  expect_within(compare(waseda_strip("double", 0.8), cpu, emulated), double_bounds(0.05, 0.9));
}
TEST(CudaEmulation, HydrostaticColumn2DFloatMatchesCpu) {
  expect_within(compare(column(2, "float", 0.2), cpu, emulated), float_bounds(0.01, 0.2));
}
#endif

// --- the device ---

TEST(Cuda, HydrostaticColumn2DDoubleMatchesCpu) {
  SKIP_WITHOUT_DEVICE();
  expect_within(compare(column(2, "double", 0.3), cpu, gpu), double_bounds(0.01, 0.2, 10));
}
TEST(Cuda, HydrostaticColumn3DDoubleMatchesCpu) {
  SKIP_WITHOUT_DEVICE();
  expect_within(compare(column(3, "double", 0.1), cpu, gpu), double_bounds(0.01, 0.2, 10));
}
TEST(Cuda, SymmetryPlane3DDoubleWithFlipMatchesCpu) {
  SKIP_WITHOUT_DEVICE();
  expect_within(compare(with_flip(half_tank(0.15)), cpu, gpu), double_bounds(0.02, 0.3, 10));
}
TEST(Cuda, SymmetryPlane3DDoubleMatchesCpu) {
  SKIP_WITHOUT_DEVICE();
  expect_within(compare(half_tank(0.15), cpu, gpu), double_bounds(0.02, 0.3, 10));
}
TEST(Cuda, RigidRotationAngularMomentumMatchesTheory) {
  SKIP_WITHOUT_DEVICE();
  const Scene scene = test::free_blob(3, 0.02, 0.1);
  const double omega[3] = {3.0, -4.0, 10.0};
  test::expect_rigid_rotation_angular_momentum(*gpu(scene), scene, omega);
}
TEST(Cuda, HydrostaticColumn2DFloatMatchesCpu) {
  SKIP_WITHOUT_DEVICE();
  expect_within(compare(column(2, "float", 0.3), cpu, gpu), float_bounds(0.01, 0.2));
}
TEST(Cuda, MartinMoyce2DDoubleMatchesCpu) {
  SKIP_WITHOUT_DEVICE();
  expect_within(compare(martin_moyce(kA / 20, "double"), cpu, gpu), double_bounds(kA / 20, 2 * kA, 10));
}
TEST(Cuda, MartinMoyce2DFloatFrontMatchesCpu) {
  SKIP_WITHOUT_DEVICE();
  // In float a free-surface flow amplifies round-off where the surface breaks, so particle-by-particle
  // agreement is not expected; the front (the validated quantity) must agree to one particle spacing (dx/2),
  // a sixth of the 0.15 a that the validation against Martin & Moyce allows.
  const Difference d = compare(martin_moyce(kA / 20, "float"), cpu, gpu);
  EXPECT_LE(d.front, (kA / 20) / 2);
}
TEST(Cuda, FallingBox3DDoubleMatchesCpu) {
  SKIP_WITHOUT_DEVICE();
  const Scene scene = falling_box();
  expect_within(compare(scene, cpu, gpu), double_bounds(0.02, 0.1, 10));
  auto sim = gpu(scene);
  ASSERT_EQ(test::run_until(*sim, scene.solver.end_time), RunStatus::kOk);
  expect_water_slowed_the_box(*sim);
}
TEST(Cuda, WasedaStrip3DDoubleMatchesCpu) {
  SKIP_WITHOUT_DEVICE();
  expect_within(compare(waseda_strip("double", 0.8), cpu, gpu), double_bounds(0.05, 0.9, 10));
}
// Once the bore breaks over the quay and strikes the containers, round-off stops being round-off: a splash or
// a contact that opens a step earlier moves particles and bodies by a finite amount, and on a GPU the atomics'
// order changes from run to run, so two GPU runs of the same scene differ as well (docs/benchmarks.md: the
// containers' rest positions spread by 2 cm over 6 s). A bound on the GPU against the CPU must then come from
// that chaos itself: the GPU may differ from the CPU by no more than a margin times what it differs from
// itself (both differences grow from one-ulp seeds at the same rate; 20 allows for the seeds' spread). A wrong
// term in the exchange moves the containers by a fraction of their motion, orders of magnitude more.
TEST(Cuda, WasedaStrip3DThroughImpactDiffersFromCpuAsFromItself) {
  SKIP_WITHOUT_DEVICE();
  const Scene scene = waseda_strip("double", 2.9);
  const Difference vs_cpu = compare(scene, cpu, gpu);
  const Difference vs_gpu = compare(scene, gpu, gpu);
  const Bounds floor = double_bounds(0.05, 0.9, 10);
  const double margin = 20;
  EXPECT_EQ(vs_cpu.steps_a, vs_cpu.steps_b) << "the adaptive steps must agree";
  EXPECT_LE(vs_cpu.body, margin * std::max(vs_gpu.body, floor.body)) << "debris centres";
  EXPECT_LE(vs_cpu.position, margin * std::max(vs_gpu.position, floor.position)) << "particle positions";
  EXPECT_LE(vs_cpu.gauge, margin * std::max(vs_gpu.gauge, floor.gauge)) << "gauges";
  EXPECT_LE(vs_cpu.energy, margin * std::max(vs_gpu.energy, floor.energy)) << "energy diagnostic";
}
TEST(Cuda, WasedaGateAndQuay2DDoubleMatchesCpu) {
  SKIP_WITHOUT_DEVICE();
  expect_within(compare(waseda_gate_and_quay(), cpu, gpu), double_bounds(0.04, 0.9, 10));
}
TEST(Cuda, InflowApron2DDoubleMatchesCpu) {
  SKIP_WITHOUT_DEVICE();
  expect_inflow_apron_matches_cpu(gpu, 10);
}
TEST(Cuda, AngularMomentumOfASpinningBlob) {
  SKIP_WITHOUT_DEVICE();
  expect_spinning_blob_conserves(gpu, 10);
}
TEST(Cuda, InstabilityMatchesCpu) {
  SKIP_WITHOUT_DEVICE();
  expect_same_instability(gpu);
}
TEST(Cuda, RunWritesResult) {
  SKIP_WITHOUT_DEVICE();
  // The flume executable is a build dependency of this test (tests/solver/CMakeLists.txt): its absence is a
  // broken build, not a missing device, so it fails rather than skips.
  ASSERT_TRUE(std::filesystem::exists(flume_exe())) << "no flume executable at " << flume_exe();
  const auto dir = std::filesystem::temp_directory_path() / ("flume_cuda_run_" + std::to_string(::getpid()));
  const int rc = test::run_command(flume_exe() + " run " + source_dir() +
                                   "/scenes/dam_break/martin_moyce_2d.json --out " + dir.string() +
                                   " --backend cuda --set solver.end_time=0.05 2>/dev/null");
  EXPECT_EQ(rc, 0);
  EXPECT_TRUE(std::filesystem::exists(dir / "result.h5"));
  EXPECT_NE(test::read_text((dir / "run.json").string()).find("\"ok\""), std::string::npos);
  std::filesystem::remove_all(dir);
}

// The GPU benchmark (issue 2, item 8), run by bench/run_gpu_bench.sh on the GPU machine, where only this test
// program travels: FLUME_GPU_BENCH_SCENE names the scene (the 3D dam break of about a million particles) and
// FLUME_GPU_BENCH_STEPS the measured steps. Timed as `flume bench` times: one warm-up step, then the steps.
TEST(CudaBench, ParticleStepsPerSecond) {
  const char* scene_file = std::getenv("FLUME_GPU_BENCH_SCENE");
  const char* steps_text = std::getenv("FLUME_GPU_BENCH_STEPS");
  if (!scene_file || !steps_text)
    GTEST_SKIP() << "set FLUME_GPU_BENCH_SCENE and FLUME_GPU_BENCH_STEPS to run";
  SKIP_WITHOUT_DEVICE();
  const long steps = std::atol(steps_text);
  std::printf("| precision | particles | steps | ms/step | particle-steps/s | grid MB | active blocks |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (const char* precision : {"float", "double"}) {
    const Scene scene = load_scene(scene_file, {{"solver.precision", precision}});
    auto sim = gpu(scene);
    sim->step();
    const long steps0 = sim->steps();
    const auto t0 = std::chrono::steady_clock::now();
    RunStatus st = RunStatus::kRunning;
    for (long i = 0; i < steps && st == RunStatus::kRunning; ++i) st = sim->step();
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_NE(st, RunStatus::kUnstable) << sim->message();
    const long n = sim->steps() - steps0;
    std::printf("| %s | %zu | %ld | %.3f | %.3e | %.1f | %zu |\n", precision, sim->particle_count(), n,
                1000 * wall / n, double(n) * double(sim->particle_count()) / wall,
                sim->grid_bytes() / 1048576.0, sim->active_blocks());
  }
}

}  // namespace
}  // namespace flume
