// The apron-only variant (issue 3): the section instrument, the inflow that replays its record, and
// waseda_apron_2d against the waseda_2d run it was fed from.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "common/errors.h"
#include "solver/run.h"
#include "solver/scene.h"
#include "solver/simulation.h"
#include "store/h5/run_file.h"
#include "test_util.h"

namespace flume {
namespace {

namespace fs = std::filesystem;
const double kG = 9.80665, kRho = 998.0;

fs::path temp_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("flume_apron_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// (a) A box of water 0.2 m deep between x = 1 and 3 m: at rest between walls there, or moving at U = 0.5 m/s
// with free ends. The section at x = 2 m must read the depth h and the velocity U: at rest for 0.45 s; moving
// for 0.25 s, well before the rarefaction from the back end arrives (shallow-water theory: 1 m / (sqrt(g h) +
// U) = 0.53 s; measured, the non-hydrostatic collapse of the ends thins the middle by 0.5 mm at 0.25 s and 4
// mm at 0.45 s, so the window stops well short of it). The first sample, before the velocity is set, is
// skipped. The section's weights sum exactly over a lattice, so the bound is one particle's share of the
// depth, s^D / (dx bin), and the velocity that a depth error of that size carries in a long wave, tol_h
// sqrt(g / h) (linear long-wave theory).
TEST(Apron, SectionReadsDepthAndVelocityOfAUniformFlow) {
  const double h = 0.2;
  for (int dim : {2, 3})
    for (double U : {0.0, 0.5}) {
      std::string text;
      const std::string ends2 =
          U == 0 ? R"(, {"name": "back", "type": "half_space", "point": [1, 0], "normal": [1, 0]},
           {"name": "end", "type": "half_space", "point": [3, 0], "normal": [-1, 0]})"
                 : "";
      const std::string ends3 =
          U == 0 ? R"(, {"name": "back", "type": "half_space", "point": [1, 0, 0], "normal": [1, 0, 0]},
           {"name": "end", "type": "half_space", "point": [3, 0, 0], "normal": [-1, 0, 0]})"
                 : "";
      if (dim == 2)
        text =
            R"({"name": "section", "dimension": 2, "domain": {"lo": [-0.12, -0.12], "hi": [4.12, 0.6], "walls": "slip"},
          "boundaries": [{"name": "floor", "type": "half_space", "point": [0, 0], "normal": [0, 1], "condition": "slip"})" +
            ends2 + R"(],
          "water": [{"lo": [1, 0], "hi": [3, 0.2]}],
          "solver": {"dx": 0.02, "ppc": 4, "end_time": 0.45, "precision": "double"},
          "fluid": {"density": 998, "bulk_modulus": 2e6, "gamma": 7.125, "jbar_psi": 0.9},
          "instruments": {"sections": [{"name": "mid", "x_m": 2.0, "rate_hz": 100}]}})";
      else
        text =
            R"({"name": "section", "dimension": 3, "domain": {"lo": [-0.12, -0.12, -0.12], "hi": [4.12, 0.52, 0.5], "walls": "slip"},
          "boundaries": [{"name": "floor", "type": "half_space", "point": [0, 0, 0], "normal": [0, 0, 1], "condition": "slip"},
                         {"name": "right", "type": "half_space", "point": [0, 0.08, 0], "normal": [0, 1, 0], "condition": "slip"},
                         {"name": "left", "type": "half_space", "point": [0, 0.32, 0], "normal": [0, -1, 0], "condition": "slip"})" +
            ends3 + R"(],
          "water": [{"lo": [1, 0.08, 0], "hi": [3, 0.32, 0.2]}],
          "solver": {"dx": 0.04, "ppc": 8, "end_time": 0.45, "precision": "double"},
          "fluid": {"density": 998, "bulk_modulus": 2e6, "gamma": 7.125, "jbar_psi": 0.9},
          "instruments": {"sections": [{"name": "mid", "x_m": 2.0, "rate_hz": 100}]}})";
      const Scene scene = parse_scene_text(text, "section test");
      auto sim = make_simulation(scene, {});
      const double v0[3] = {U, 0, 0}, w[3] = {0, 0, 0}, c[3] = {0, 0, 0};
      sim->set_rigid_velocity(v0, w, c);
      ASSERT_EQ(test::run_until(*sim, 0.45), RunStatus::kOk) << sim->message();
      const SectionSeries& r = sim->record().sections.at("mid");
      const double dx = scene.solver.dx, s = dx / 2;
      const double tol_h = std::pow(s, dim) / (dx * (dim == 3 ? dx : 1.0)), tol_u = tol_h * std::sqrt(kG / h);
      double worst_h = 0, worst_u = 0;
      size_t wet = 0;
      const double window = U == 0 ? 0.45 : 0.25;
      size_t samples = 0;
      for (size_t i = 1; i < r.time.size() && r.time[i] <= window + 1e-9; ++i, ++samples)
        for (size_t j = 0; j < r.bins(); ++j) {
          if (dim == 3 && !(r.y[j] > 0.08 && r.y[j] < 0.32)) {
            EXPECT_EQ(r.depth[i * r.bins() + j], 0.0) << "a dry bin reads water, y = " << r.y[j];
            continue;
          }
          ++wet;
          worst_h = std::max(worst_h, std::fabs(r.depth[i * r.bins() + j] - h));
          worst_u = std::max(worst_u, std::fabs(r.velocity[i * r.bins() + j] - U));
        }
      std::printf(
          "%dD, U = %.1f m/s: %zu samples; worst |depth - h| %.2e m (tol %.2e), |u - U| %.2e m/s (tol "
          "%.2e)\n",
          dim, U, wet, worst_h, tol_h, worst_u, tol_u);
      EXPECT_EQ(wet, samples * (dim == 3 ? 6 : 1));
      EXPECT_LT(worst_h, tol_h);
      EXPECT_LT(worst_u, tol_u);
    }
}

// A synthetic section record: depth h(t) and velocity u(t), with a sheared profile u (0.5 + z / h) when
// `profile` (the inflow takes its shape and shifts it to carry the recorded flux h u).
std::string write_record(const fs::path& dir, bool profile, double x_m, double t_end, double* flux_integral,
                         double* h_max) {
  const std::string path = (dir / "record.h5").string();
  h5::RunFile f(path);
  std::vector<double> t, h, u, z, prof;
  const double layer = 0.02;
  for (int l = 0; l < 20; ++l) z.push_back((l + 0.5) * layer);
  *flux_integral = 0;
  *h_max = 0;
  for (int i = 0; i <= int(t_end * 200 + 0.5); ++i) {
    const double ti = i / 200.0;
    t.push_back(ti);
    h.push_back(0.12 + 0.03 * std::sin(2 * M_PI * ti / 0.8));
    u.push_back(0.4 + 0.1 * std::sin(2 * M_PI * ti / 0.5));
    *h_max = std::max(*h_max, h.back());
    for (double zl : z) prof.push_back(u.back() * (0.5 + std::min(zl, h.back()) / h.back()));
    if (i > 0) *flux_integral += 0.5 * (h[i] * u[i] + h[i - 1] * u[i - 1]) * (t[i] - t[i - 1]);
  }
  const std::string g = "/sections/s";
  f.write_series(g, "time", t);
  f.write_series(g, "depth", h);
  f.write_series(g, "velocity", u);
  if (profile) {
    f.write_series(g, "z", z);
    f.write_matrix(g, "velocity_profile", prof, z.size());
  }
  f.set_attribute(g, "x_m", x_m);
  f.set_attribute(g, "floor_m", 0.0);
  f.set_attribute(g, "bin_width_m", 0.0);
  f.finalize();
  return path;
}

std::string channel_scene(const std::string& record) {
  return R"({"name": "channel", "dimension": 2, "domain": {"lo": [0.2, -0.1], "hi": [4.0, 0.6], "walls": "slip"},
    "boundaries": [{"name": "floor", "type": "half_space", "point": [0, 0], "normal": [0, 1], "condition": "slip"}],
    "water": [{"lo": [0.5, 0], "hi": [3.9, 0.05]}],
    "inflow": {"record": ")" +
         record + R"(", "section": "s", "x_m": 0.5},
    "solver": {"dx": 0.02, "ppc": 4, "end_time": 1.5, "precision": "double"},
    "fluid": {"density": 998, "bulk_modulus": 2e6, "gamma": 7.125, "jbar_psi": 0.9}})";
}

double mass_downstream(const Simulation& sim, double x_in, double particle_mass) {
  std::vector<double> xyz;
  sim.particle_positions(xyz);
  size_t n = 0;
  for (size_t i = 0; i < xyz.size() / 3; ++i) n += xyz[3 * i] >= x_in;
  return n * particle_mass;
}

// (b) The water that enters through the plane in 1.5 s is rho integral(h u) dt of the record. Bound: the
// slots are error-diffused line by line (one particle, rho s^2, per lattice line, h_max / s + 1 lines), and
// each line ends the run with a slot part-way across (another particle per line): 2 rho s (h_max + s).
TEST(Apron, InflowInjectsTheRecordedFlux) {
  const fs::path dir = temp_dir("mass");
  for (bool profile : {false, true}) {
    double q = 0, h_max = 0;
    const std::string rec = write_record(dir, profile, 0.5, 1.5, &q, &h_max);
    const Scene scene = parse_scene_text(channel_scene(rec), "channel");
    auto sim = make_simulation(scene, {});
    const double s = scene.solver.dx / 2, mp = kRho * s * s;
    const double m0 = mass_downstream(*sim, 0.5, mp);
    ASSERT_EQ(test::run_until(*sim, 1.5), RunStatus::kOk) << sim->message();
    const double entered = mass_downstream(*sim, 0.5, mp) - m0, expected = kRho * q;
    const double tol = 2 * kRho * s * (h_max + s);
    std::printf(
        "profile %d: entered %.3f kg/m, recorded flux %.3f kg/m, difference %.3f (tol %.3f, %.1f%%)\n",
        profile, entered, expected, entered - expected, tol, 100 * tol / expected);
    EXPECT_NEAR(entered, expected, tol);
  }
  fs::remove_all(dir);
}

// The same with SPH (solver.method sph), which takes the same boundary (its buffer particles are fluid
// particles whose motion and density the boundary sets each step). The sheared profile, over 1 s, with K =
// 2e5 Pa (c0 = 14 m/s, 28 times the flow; SPH's step is set by c0).
TEST(Apron, SphInflowInjectsTheRecordedFlux) {
  const fs::path dir = temp_dir("mass_sph");
  double q = 0, h_max = 0;
  const std::string rec = write_record(dir, true, 0.5, 1.0, &q, &h_max);
  const Scene scene =
      parse_scene_text(channel_scene(rec), "channel",
                       {parse_override("solver.method=sph"), parse_override("solver.end_time=1.0"),
                        parse_override("fluid.bulk_modulus=2e5")});
  auto sim = make_simulation(scene, {Backend::kCpu, 1});
  const double s = scene.solver.dx / 2, mp = kRho * s * s;
  const double m0 = mass_downstream(*sim, 0.5, mp);
  ASSERT_EQ(test::run_until(*sim, 1.0), RunStatus::kOk) << sim->message();
  const double entered = mass_downstream(*sim, 0.5, mp) - m0, expected = kRho * q;
  const double tol = 2 * kRho * s * (h_max + s);
  std::printf("SPH: entered %.3f kg/m, recorded flux %.3f kg/m, difference %.3f (tol %.3f, %.1f%%)\n",
              entered, expected, entered - expected, tol, 100 * tol / expected);
  EXPECT_NEAR(entered, expected, tol);
  fs::remove_all(dir);
}

// (c) In 3D the inflow stands on the ground under the middle of its plane: a channel between two boxes whose
// faces bound the plane's lateral extent exactly (y_m = [0, 0.24], the boxes end and begin there). Read at
// the plane's edge, the side box's top (0.3 m) was taken for the floor and the water entered above it. Every
// particle near the plane must lie below the record's highest level by at most a particle spacing.
TEST(Apron, InflowStandsOnTheFloorBetweenSideBoxes) {
  const fs::path dir = temp_dir("side_boxes");
  double q = 0, h_max = 0;
  const std::string rec = write_record(dir, false, 0.5, 0.2, &q, &h_max);
  const std::string text =
      R"({"name": "channel3", "dimension": 3, "domain": {"lo": [0.2, -0.2, -0.08], "hi": [2.0, 0.44, 0.6], "walls": "slip"},
    "boundaries": [{"name": "floor", "type": "half_space", "point": [0, 0, 0], "normal": [0, 0, 1], "condition": "slip"},
                   {"name": "left", "type": "box", "lo": [0.2, -0.2, -0.08], "hi": [2.0, 0.0, 0.3], "condition": "slip"},
                   {"name": "right", "type": "box", "lo": [0.2, 0.24, -0.08], "hi": [2.0, 0.44, 0.3], "condition": "slip"}],
    "water": [{"lo": [1.8, 0, 0], "hi": [1.9, 0.24, 0.04]}],
    "inflow": {"record": ")" +
      rec + R"(", "section": "s", "x_m": 0.5, "y_m": [0.0, 0.24]},
    "solver": {"dx": 0.04, "ppc": 8, "end_time": 0.2, "precision": "double"},
    "fluid": {"density": 998, "bulk_modulus": 2e6, "gamma": 7.125, "jbar_psi": 0.9}})";
  const Scene scene = parse_scene_text(text, "channel3");
  auto sim = make_simulation(scene, {});
  ASSERT_EQ(test::run_until(*sim, 0.2), RunStatus::kOk) << sim->message();
  std::vector<double> xyz;
  sim->particle_positions(xyz);
  const double s = particle_spacing(scene);
  double top = 0;
  size_t near_plane = 0;
  for (size_t i = 0; i < xyz.size() / 3; ++i)
    if (xyz[3 * i] < 1.0) {
      top = std::max(top, xyz[3 * i + 2]);
      ++near_plane;
    }
  std::printf(
      "%zu particles within 0.5 m of the plane, the highest at z = %.3f m (record's highest level %.3f m)\n",
      near_plane, top, h_max);
  EXPECT_GT(near_plane, 0u);
  EXPECT_LT(top, h_max + s);
  fs::remove_all(dir);
}

TEST(Apron, BadRecordsAreInputErrors) {
  const fs::path dir = temp_dir("bad");
  auto field_of = [](const std::string& text) -> std::string {
    try {
      parse_scene_text(text, "channel");
    } catch (const InputError& e) {
      std::printf("%s\n", e.what());
      return e.field();
    }
    return "(no error)";
  };
  EXPECT_EQ(field_of(channel_scene((dir / "missing.h5").string())), "inflow.record");
  double q, h;
  const std::string rec = write_record(dir, false, 0.5, 1.5, &q, &h);
  std::string wrong = channel_scene(rec);
  wrong.replace(wrong.find("\"section\": \"s\""), 14, "\"section\": \"t\"");
  EXPECT_EQ(field_of(wrong), "inflow.section");
  std::string late = channel_scene(rec);
  late.replace(late.find("\"end_time\": 1.5"), 15, "\"end_time\": 2.5");
  EXPECT_EQ(field_of(late), "solver.end_time");
  std::string elsewhere = channel_scene(rec);
  elsewhere.replace(elsewhere.find("\"x_m\": 0.5"), 10, "\"x_m\": 0.9");
  EXPECT_EQ(field_of(elsewhere), "inflow.x_m");
  const std::string apron = std::string(FLUME_SOURCE_DIR) + "/scenes/waseda/waseda_apron_2d.json";
  try {
    load_scene(apron);
    ADD_FAILURE() << "a scene without inflow.record loaded";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "inflow.record") << e.what();
  }
  fs::remove_all(dir);
}

struct Series {
  std::vector<double> t, v;
  double at(double x) const {
    if (x <= t.front()) return v.front();
    if (x >= t.back()) return v.back();
    const size_t i = std::upper_bound(t.begin(), t.end(), x) - t.begin();
    const double w = (x - t[i - 1]) / (t[i] - t[i - 1]);
    return (1 - w) * v[i - 1] + w * v[i];
  }
};
Series gauge(const fs::path& run, const std::string& name) {
  const std::string f = (run / "result.h5").string();
  return {h5::read_vector(f, "/gauges/" + name + "/time"),
          h5::read_vector(f, "/gauges/" + name + "/elevation")};
}

// (c) The issue's check in 2D at dx = 0.02 m: waseda_2d for 5 s (the bore passes WG4 at 6.15 m by 3.2 s),
// then waseda_apron_2d fed from its apron_inflow section. WG3 and WG4 of the two runs: RMS difference over
// the record within 10% of the full run's peak (eta above still water, as the gauges report it). At dx = 0.04 m
// the water over the apron (0.025 m above still water) is thinner than one cell at WG3 and half a cell at WG4, so
// that comparison says more about sub-cell films than about the inflow (with the free-slip mirror it gave WG3
// 10.0 %, WG4 6.6 %; docs/waseda.md). FLUME_SET="solver.method=sph" measures SPH's replay (docs/sph.md).
TEST(Apron, Apron2dReproducesWg3AndWg4OfTheRunItWasFedFrom) {
  const fs::path dir = temp_dir("wg");
  std::vector<Override> common = {{"solver.dx", "0.02"}, {"solver.end_time", "5"}};
  for (const auto& o : test::env_overrides()) common.push_back(o);  // e.g. FLUME_SET="solver.method=sph"
  const std::string src = std::string(FLUME_SOURCE_DIR) + "/scenes/waseda/";
  const RunOutcome full = run_scene(load_scene(src + "waseda_2d.json", common), {}, (dir / "full").string());
  ASSERT_EQ(full.status, RunStatus::kOk) << full.message;
  std::vector<Override> sets = common;
  sets.push_back({"inflow.record", (dir / "full" / "result.h5").string()});
  const RunOutcome apron =
      run_scene(load_scene(src + "waseda_apron_2d.json", sets), {}, (dir / "apron").string());
  ASSERT_EQ(apron.status, RunStatus::kOk) << apron.message;
  for (const char* g : {"WG3", "WG4"}) {
    const Series a = gauge(dir / "full", g), b = gauge(dir / "apron", g);
    double peak = 0, sum2 = 0, sum2_late = 0;
    size_t late = 0;
    for (size_t i = 0; i < a.t.size(); ++i) {
      peak = std::max(peak, a.v[i]);
      const double d = b.at(a.t[i]) - a.v[i];
      sum2 += d * d;
      if (a.t[i] >= 2.0) sum2_late += d * d, ++late;
    }
    const double rms = std::sqrt(sum2 / a.t.size()), rms_late = std::sqrt(sum2_late / late);
    std::printf(
        "%s: peak %.4f m (apron %.4f m); RMS difference %.4f m = %.1f%% of the peak over 0-5 s, %.1f%% over "
        "2-5 s\n",
        g, peak, *std::max_element(b.v.begin(), b.v.end()), rms, 100 * rms / peak, 100 * rms_late / peak);
    EXPECT_LE(rms, 0.10 * peak) << g;
  }
  std::printf(
      "cost: full %.2f s wall, %ld steps x %zu particles; apron %.2f s wall, %ld steps x %zu particles "
      "(at the end); ratios %.2f (wall), %.2f (particle-steps)\n",
      full.cost.wall_s, full.cost.steps, full.cost.particles, apron.cost.wall_s, apron.cost.steps,
      apron.cost.particles, apron.cost.wall_s / full.cost.wall_s,
      double(apron.cost.steps) * apron.cost.particles / (double(full.cost.steps) * full.cost.particles));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace flume
