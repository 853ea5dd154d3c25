// Checkpoints (solver/checkpoint.h): a run stopped at any step and resumed from its checkpoint repeats the
// uninterrupted run step for step, bit for bit: the same records, particles and debris trajectories (the
// diagnostics' energy sums to their reduction order's rounding). Covered:
// the Waseda 2D basin (reservoir hold and release, gate, gauges, section), its apron fed through the inflow
// boundary, a floating box, a finished run extended to a later end time through run_scene's file, and the
// refusals (another scene, a missing, corrupt or truncated file), and particle snapshots kept across a resume.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "common/errors.h"
#include "solver/checkpoint.h"
#include "solver/cuda/mpm_cuda.h"
#include "solver/debris_coupling.h"
#include "solver/run.h"
#include "solver/scene.h"
#include "solver/simulation.h"
#include "store/h5/run_file.h"
#include "tests/solver/tank_scene.h"
#include "tests/solver/test_util.h"

namespace flume {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("flume_ckpt_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string waseda(const std::string& file) { return std::string(FLUME_SOURCE_DIR) + "/scenes/waseda/" + file; }

// Where two vectors first differ, for the failure message.
std::string first_difference(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return "sizes " + std::to_string(a.size()) + " and " + std::to_string(b.size());
  for (size_t i = 0; i < a.size(); ++i)
    if (a[i] != b[i]) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "first at %zu of %zu: %.17g against %.17g", i, a.size(), a[i], b[i]);
      return buf;
    }
  return "none";
}

void expect_same_series(const TimeSeries& a, const TimeSeries& b, const std::string& what) {
  EXPECT_TRUE(a.time == b.time) << what << " time: " << first_difference(a.time, b.time);
  EXPECT_TRUE(a.values == b.values) << what << ": " << first_difference(a.values, b.values);
}

// Every record of two runs, exactly; but the energies of the diagnostics, which are OpenMP reductions whose
// partial sums join in the order threads finish (not repeatable from run to run, resumed or not): to within
// the rounding of summing n terms of one sign in another order, n eps of the sum.
void expect_same_record(const Record& a, const Record& b, size_t n) {
  ASSERT_EQ(a.gauges.size(), b.gauges.size());
  for (const auto& [k, s] : a.gauges) expect_same_series(s, b.gauges.at(k), "gauge " + k);
  for (const auto& [k, s] : a.probes) expect_same_series(s, b.probes.at(k), "probe " + k);
  for (const auto& [k, s] : a.loads) expect_same_series(s, b.loads.at(k), "load " + k);
  ASSERT_EQ(a.pressures.size(), b.pressures.size());
  for (const auto& [k, s] : a.pressures) expect_same_series(s, b.pressures.at(k), "pressure probe " + k);
  for (const auto& [k, s] : a.sections) {
    EXPECT_EQ(s.time, b.sections.at(k).time) << k;
    EXPECT_EQ(s.depth, b.sections.at(k).depth) << k;
    EXPECT_EQ(s.velocity, b.sections.at(k).velocity) << k;
    EXPECT_EQ(s.profile, b.sections.at(k).profile) << k;
  }
  for (const auto& [k, v] : a.diagnostics) {
    const auto& w = b.diagnostics.at(k);
    if (k == "kinetic" || k == "potential" || k == "elastic" || k == "total") {
      ASSERT_EQ(v.size(), w.size()) << k;
      for (size_t i = 0; i < v.size(); ++i)
        EXPECT_NEAR(v[i], w[i], double(n) * 2.3e-16 * std::max(std::fabs(v[i]), std::fabs(w[i]))) << k << " " << i;
    } else {
      EXPECT_TRUE(v == w) << "diagnostic " << k << ": " << first_difference(v, w);
    }
  }
}

size_t samples(const Record& r) {
  size_t n = 0;
  for (const auto& [k, s] : r.gauges) n += s.size();
  for (const auto& [k, s] : r.sections) n += s.time.size();
  return n;
}

using Factory = std::function<std::unique_ptr<Simulation>(const Scene&)>;
std::unique_ptr<Simulation> cpu(const Scene& s) { return make_simulation(s, {}); }

// `scene` run to its end straight, and again stopped at t_stop, checkpointed, rebuilt from the scene, loaded
// and run on (null where a run failed: the failure is reported).
struct Resumed {
  std::unique_ptr<Simulation> straight, resumed;
};
Resumed run_and_resume(const Scene& scene, double t_stop, const Factory& make) {
  Resumed r;
  auto straight = make(scene);
  EXPECT_EQ(test::run_until(*straight, scene.solver.end_time), RunStatus::kOk) << straight->message();

  auto first = make(scene);
  EXPECT_EQ(test::run_until(*first, t_stop), RunStatus::kRunning);
  StateArchive out;
  first->checkpoint(out);
  const long steps_at_stop = first->steps();

  auto resumed = make(scene);
  StateArchive in(out.bytes(), "memory");
  resumed->checkpoint(in);
  in.finish();
  first.reset();
  EXPECT_EQ(resumed->steps(), steps_at_stop);
  const RunStatus end = test::run_until(*resumed, scene.solver.end_time);
  EXPECT_EQ(end, RunStatus::kOk) << resumed->message();
  std::printf("%s: stopped at t = %.3f s (step %ld of %ld), checkpoint %.2f MB, %zu particles at the end, %zu "
              "gauge and section samples compared\n",
              scene.name.c_str(), t_stop, steps_at_stop, straight->steps(), out.bytes().size() / 1048576.0,
              straight->particle_count(), samples(straight->record()));
  if (::testing::Test::HasFailure()) return r;
  r.straight = std::move(straight);
  r.resumed = std::move(resumed);
  return r;
}

// Runs `scene` to its end straight and resumed from a checkpoint at t_stop: both must agree to the bit.
void expect_exact_resume(const Scene& scene, double t_stop, const Factory& make = cpu) {
  const Resumed r = run_and_resume(scene, t_stop, make);
  ASSERT_TRUE(r.straight && r.resumed);
  const Simulation *straight = r.straight.get(), *resumed = r.resumed.get();
  EXPECT_EQ(resumed->steps(), straight->steps());
  EXPECT_EQ(resumed->time(), straight->time());
  expect_same_record(straight->record(), resumed->record(), straight->particle_count());
  std::vector<double> xa, xb, va, vb;
  straight->particle_positions(xa);
  resumed->particle_positions(xb);
  straight->particle_velocities(va);
  resumed->particle_velocities(vb);
  EXPECT_EQ(xa, xb);
  EXPECT_EQ(va, vb);
  if (straight->debris()) {
    const DebrisRecorder& ra = straight->debris()->recorder();
    const DebrisRecorder& rb = resumed->debris()->recorder();
    for (int b = 0; b < ra.body_count(); ++b) {
      EXPECT_EQ(ra.solver_rate(b).time, rb.solver_rate(b).time);
      EXPECT_EQ(ra.solver_rate(b).position, rb.solver_rate(b).position) << ra.name(b);
      EXPECT_EQ(ra.solver_rate(b).velocity, rb.solver_rate(b).velocity) << ra.name(b);
      EXPECT_EQ(ra.resampled(b).force, rb.resampled(b).force) << ra.name(b);
    }
  }
}

// A 2D dam break against a wall with pressure probes on it (their interval sums and clocks are state) and a
// connected gauge, stopped between two of the probes' samples as the front runs up the wall.
Scene dam_probe_scene(const std::vector<Override>& overrides = {}) {
  return parse_scene_text(R"({"name": "dam_probe", "dimension": 2,
    "domain": {"lo": [-0.05, -0.05], "hi": [0.65, 0.4], "walls": "slip"},
    "solver": {"dx": 0.01, "ppc": 4, "precision": "float", "end_time": 0.3},
    "fluid": {"bulk_modulus": 2.0e5, "jbar_psi": 0.9},
    "water": [{"lo": [0, 0], "hi": [0.2, 0.2]}],
    "boundaries": [
      {"name": "floor", "type": "half_space", "point": [0, 0], "normal": [0, 1], "condition": "slip"},
      {"name": "wall", "type": "half_space", "point": [0.6, 0], "normal": [-1, 0], "condition": "slip"}],
    "instruments": {"gauges": [{"name": "G1w", "position": [0.5], "reading": "connected"}],
      "pressure_probes": [{"name": "PS1", "position": [0.6, 0.01], "normal": [-1, 0], "rate_hz": 300},
                          {"name": "PS2", "position": [0.5, 0.0], "normal": [0, 1]}]}})",
                                       "dam_probe.json", overrides);
}
TEST(Checkpoint, ResumedPressureProbesRepeatTheUninterruptedRun) { expect_exact_resume(dam_probe_scene(), 0.2); }
// SPH's state: the particles in their last cell order, their sub-particle stress, the walls' densities.
TEST(Checkpoint, SphResumedPressureProbesRepeatTheUninterruptedRun) {
  expect_exact_resume(dam_probe_scene({parse_override("solver.method=sph"), parse_override("solver.dx=0.02")}), 0.2);
}
#ifdef FLUME_CUDA_EMULATION_AVAILABLE
// The CUDA backend reads its instruments from host mirrors of the particles (solver/cuda/mpm_cuda.cu).
TEST(Checkpoint, CudaEmulationResumedPressureProbesRepeatTheUninterruptedRun) {
  expect_exact_resume(dam_probe_scene(), 0.2, [](const Scene& s) { return make_cuda_host_emulation(s, {}); });
}
#endif

// The 2D basin: the reservoir held by its vacuum, then released through the gate; stopped mid-release.
TEST(Checkpoint, ResumedBasinRepeatsTheUninterruptedRun) {
  const Scene scene =
      load_scene(waseda("waseda_2d.json"), {parse_override("solver.dx=0.04"), parse_override("solver.end_time=1.2")});
  expect_exact_resume(scene, 0.55);
}

// SPH on the same basin in double (the wall particles' densities and the vacuum's hold are state as well).
TEST(Checkpoint, SphResumedBasinRepeatsTheUninterruptedRun) {
  const Scene scene =
      load_scene(waseda("waseda_2d.json"), {parse_override("solver.dx=0.04"), parse_override("solver.end_time=0.8"),
                                            parse_override("solver.method=sph"), parse_override("solver.precision=double")});
  expect_exact_resume(scene, 0.5);
}

#ifdef FLUME_CUDA_EMULATION_AVAILABLE
// The CUDA backend's source on the host (solver/cuda/mpm_cuda.h): the same basin, stopped mid-release. Its
// sums run in a fixed order (sequential), so its diagnostics repeat to the bit as well.
TEST(Checkpoint, CudaEmulationResumedBasinRepeatsTheUninterruptedRun) {
  const Scene scene = load_scene(waseda("waseda_2d.json"),
                                 {parse_override("solver.dx=0.04"), parse_override("solver.end_time=1.2")});
  expect_exact_resume(scene, 0.55, [](const Scene& s) { return make_cuda_host_emulation(s, {}); });
}
#endif

// The apron fed through the inflow boundary by the section record a run of the 2D basin (to 3.5 s at dx 0.04 m)
// writes under `dir`; `more`: further overrides of the apron.
Scene fed_apron(const fs::path& dir, const std::vector<Override>& more = {}) {
  const Scene feed = load_scene(waseda("waseda_2d.json"),
                                {parse_override("solver.dx=0.04"), parse_override("solver.end_time=3.5")});
  EXPECT_EQ(run_scene(feed, {}, (dir / "feed").string()).status, RunStatus::kOk);
  std::vector<Override> o = {parse_override("solver.dx=0.04"), parse_override("solver.end_time=3.5"),
                             parse_override("inflow.record=" + (dir / "feed" / "result.h5").string())};
  o.insert(o.end(), more.begin(), more.end());
  return load_scene(waseda("waseda_apron_2d.json"), o);
}

// The apron: the lattice lines' advance and their error carries are part of the state.
TEST(Checkpoint, ResumedInflowRepeatsTheUninterruptedRun) {
  const fs::path dir = temp_dir("inflow");
  const Scene apron = fed_apron(dir);
  expect_exact_resume(apron, 2.9);  // the bore crosses the inflow plane from about 2.3 s
#ifdef FLUME_CUDA_EMULATION_AVAILABLE
  {
    SCOPED_TRACE("the CUDA backend's source on the host");
    expect_exact_resume(apron, 2.9, [](const Scene& s) { return make_cuda_host_emulation(s, {}); });
  }
#endif
  fs::remove_all(dir);
}

// SPH's apron behind the same boundary (its buffer particles' densities are set from the strain it places):
// stopped as the bore crosses the inflow plane. K = 2e5 Pa (c0 = 14 m/s) keeps SPH's steps few.
TEST(Checkpoint, SphResumedInflowRepeatsTheUninterruptedRun) {
  const fs::path dir = temp_dir("inflow_sph");
  const Scene apron =
      fed_apron(dir, {parse_override("solver.method=sph"), parse_override("fluid.bulk_modulus=2e5"),
                      parse_override("solver.end_time=2.6")});
  expect_exact_resume(apron, 2.45);
  fs::remove_all(dir);
}

// A box floating in a tank: the body's pose and velocity, the trajectories recorded so far and the particle
// impulses pending for the next exchange are part of the state. (A box touching a solid resumes with Bullet's
// contact caches rebuilt, which changes that step's warm start: not exact, not tested here.)
TEST(Checkpoint, ResumedFloatingBoxRepeatsTheUninterruptedRun) {
  const double depth = 0.15, H = 0.08;
  const Scene scene = parse_scene_text(test::tank_scene(0.3, depth, H, 419.0, depth - 0.04 + H / 2, 0.02, 0.12),
                                       "floating");
  expect_exact_resume(scene, 0.05);
}
// The same with SPH: the boxes' particles (their order, offsets and densities) and the film are state too.
TEST(Checkpoint, SphResumedFloatingBoxRepeatsTheUninterruptedRun) {
  const double depth = 0.15, H = 0.08;
  const Scene scene = parse_scene_text(test::tank_scene(0.3, depth, H, 419.0, depth - 0.04 + H / 2, 0.03, 0.03),
                                       "floating", {parse_override("solver.method=sph")});
  expect_exact_resume(scene, 0.015);
}
#ifdef FLUME_CUDA_EMULATION_AVAILABLE
TEST(Checkpoint, CudaEmulationResumedFloatingBoxRepeatsTheUninterruptedRun) {
  const double depth = 0.15, H = 0.08;
  const Scene scene = parse_scene_text(test::tank_scene(0.3, depth, H, 419.0, depth - 0.04 + H / 2, 0.02, 0.12),
                                       "floating");
  expect_exact_resume(scene, 0.05, [](const Scene& s) { return make_cuda_host_emulation(s, {}); });
}
#endif

// --- the device: the same resumes on a GPU (skipped without one) ---
//
// On a GPU the scatter's atomics sum in an order that changes from run to run, so a resumed run repeats the
// uninterrupted one to round-off, not to the bit. The bounds are the CUDA tests' for double on a device
// (tests/solver/test_cuda.cpp, Bounds: 1e-9 of the natural scale, times 10 for the atomics and FMA
// contraction): 1e-8 of dx for positions, gauges, section depths and debris centres, 1e-8 m/s for probes and
// section velocities, 1e-8 of rho g H for pressure probes (H: `head`), 1e-8 of the weight for loads, 1e-8 of
// the potential energy for the energy diagnostic, and sample times to 1e-8 s (they are sums of step sizes
// that differ by round-off).
void expect_close_series(const std::map<std::string, TimeSeries>& a, const std::map<std::string, TimeSeries>& b,
                         double bound, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (const auto& [k, s] : a) {
    const TimeSeries& t = b.at(k);
    ASSERT_EQ(s.time.size(), t.time.size()) << what << " " << k;
    ASSERT_EQ(s.values.size(), t.values.size()) << what << " " << k;
    for (size_t i = 0; i < s.time.size(); ++i) EXPECT_NEAR(s.time[i], t.time[i], 1e-8) << what << " " << k;
    for (size_t i = 0; i < s.values.size(); ++i)
      if (!(std::isnan(s.values[i]) && std::isnan(t.values[i]))) {
        EXPECT_NEAR(s.values[i], t.values[i], bound) << what << " " << k << " value " << i;
      }
  }
}
void expect_close_values(const std::vector<double>& a, const std::vector<double>& b, double bound,
                         const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  double worst = 0;
  for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::fabs(a[i] - b[i]));
  EXPECT_LE(worst, bound) << what;
}

void expect_close_resume(const Scene& scene, double t_stop, double head) {
  const Resumed r = run_and_resume(scene, t_stop, test::gpu);
  ASSERT_TRUE(r.straight && r.resumed);
  const Simulation &a = *r.straight, &b = *r.resumed;
  const double tol = 1e-8, dx = scene.solver.dx, g = 9.80665;
  EXPECT_EQ(a.steps(), b.steps()) << "the adaptive steps must agree";
  EXPECT_NEAR(a.time(), b.time(), tol);
  const Record &ra = a.record(), &rb = b.record();
  expect_close_series(ra.gauges, rb.gauges, tol * dx, "gauge");
  expect_close_series(ra.probes, rb.probes, tol, "probe");
  expect_close_series(ra.loads, rb.loads, tol * a.total_mass() * g, "load");
  expect_close_series(ra.pressures, rb.pressures, tol * scene.fluid.density * g * head, "pressure probe");
  for (const auto& [k, s] : ra.sections) {
    const SectionSeries& t = rb.sections.at(k);
    expect_close_values(s.time, t.time, tol, "section time " + k);
    expect_close_values(s.depth, t.depth, tol * dx, "section depth " + k);
    expect_close_values(s.velocity, t.velocity, tol, "section velocity " + k);
    expect_close_values(s.profile, t.profile, tol, "section profile " + k);
  }
  const auto &ea = ra.diagnostics.at("total"), &eb = rb.diagnostics.at("total");
  const double pe0 = std::fabs(ra.diagnostics.at("potential").front());
  expect_close_values(ea, eb, tol * pe0, "energy diagnostic");
  std::vector<double> xa, xb;
  a.particle_positions(xa);
  b.particle_positions(xb);
  expect_close_values(xa, xb, tol * dx, "particle positions");
  if (a.debris()) {
    const DebrisRecorder &da = a.debris()->recorder(), &db = b.debris()->recorder();
    for (int k = 0; k < da.body_count(); ++k) {
      const auto &pa = da.solver_rate(k).position, &pb = db.solver_rate(k).position;
      ASSERT_EQ(pa.size(), pb.size()) << da.name(k);
      double worst = 0;
      for (size_t i = 0; i < pa.size(); ++i)
        worst = std::max(worst, std::hypot(pa[i][0] - pb[i][0], pa[i][1] - pb[i][1], pa[i][2] - pb[i][2]));
      EXPECT_LE(worst, tol * dx) << "debris centre " << da.name(k);
    }
  }
}

TEST(Checkpoint, CudaResumedPressureProbesRepeatTheUninterruptedRun) {
  SKIP_WITHOUT_DEVICE();
  expect_close_resume(dam_probe_scene({parse_override("solver.precision=double")}), 0.2, 0.2);
}
TEST(Checkpoint, CudaResumedBasinRepeatsTheUninterruptedRun) {
  SKIP_WITHOUT_DEVICE();
  const Scene scene = load_scene(waseda("waseda_2d.json"), {parse_override("solver.dx=0.04"),
                                                            parse_override("solver.end_time=1.2"),
                                                            parse_override("solver.precision=double")});
  expect_close_resume(scene, 0.55, 0.9);
}
TEST(Checkpoint, CudaResumedInflowRepeatsTheUninterruptedRun) {
  SKIP_WITHOUT_DEVICE();
  const fs::path dir = temp_dir("cuda_inflow");
  const Scene apron = fed_apron(dir, {parse_override("solver.precision=double")});
  expect_close_resume(apron, 2.9, 0.9);
  fs::remove_all(dir);
}
TEST(Checkpoint, CudaResumedFloatingBoxRepeatsTheUninterruptedRun) {
  SKIP_WITHOUT_DEVICE();
  const double depth = 0.15, H = 0.08;
  const Scene scene = parse_scene_text(test::tank_scene(0.3, depth, H, 419.0, depth - 0.04 + H / 2, 0.02, 0.12),
                                       "floating");
  expect_close_resume(scene, 0.05, depth);
}

std::vector<double> gauge(const fs::path& run, const std::string& name) {
  return h5::read_vector((run / "result.h5").string(), "/gauges/" + name + "/elevation");
}

// The command line, killed: `flume run --checkpoint-every 1` killed with SIGKILL after 3 s of wall time, then
// `flume run --resume` with the same arguments, writes the same gauge records, to the bit, as a run never
// interrupted. (The run is sized to take several times 3 s on one thread; if it finished before the kill, the
// test says so rather than passing.)
TEST(Checkpoint, KilledRunResumesToTheSameRecords) {
  const fs::path dir = temp_dir("killed");
  const std::string args = " " + waseda("waseda_2d.json") +
                           " --set solver.dx=0.02 --set solver.end_time=1.5 --threads 1 --quiet --out ";
  ASSERT_EQ(test::run_command(std::string(FLUME_EXE) + " run" + args + (dir / "straight").string()), 0);
  const std::string split = (dir / "split").string();
  test::run_command("timeout -s KILL 3 " + std::string(FLUME_EXE) + " run" + args + split + " --checkpoint-every 1");
  ASSERT_FALSE(fs::exists(dir / "split" / "run.json")) << "the run finished within 3 s: nothing was killed";
  ASSERT_TRUE(fs::exists(dir / "split" / "checkpoint.bin"));
  ASSERT_EQ(test::run_command(std::string(FLUME_EXE) + " run" + args + split + " --resume"), 0);
  for (const char* g : {"WG1", "WG2", "WG3", "WG4"}) {
    const auto a = gauge(dir / "straight", g), b = gauge(dir / "split", g);
    EXPECT_FALSE(a.empty());
    EXPECT_TRUE(a == b) << g << ": " << first_difference(a, b);
  }
  const auto run = nlohmann::json::parse(test::read_text((dir / "split" / "run.json").string()));
  EXPECT_EQ(run["status"], "ok");
  fs::remove_all(dir);
}

// A finished run resumed to a later end time keeps what it recorded (the records of the run to 0.6 s are the
// first samples of the extended one, exactly) and runs on to the new end, its wall time counting both parts.
// (It is not the run straight to 1.2 s to the bit: the first part's last step was cut short to land on 0.6 s.)
TEST(Checkpoint, FinishedRunExtendsToALaterEndTime) {
  const fs::path dir = temp_dir("extend");
  const auto scene_to = [&](double t) {
    return load_scene(waseda("waseda_2d.json"),
                      {parse_override("solver.dx=0.04"), parse_override("solver.end_time=" + std::to_string(t))});
  };
  CheckpointOptions every;
  every.every_s = 1e6;  // only the one at the end
  const RunOutcome a = run_scene(scene_to(0.6), {}, (dir / "run").string(), false, every);
  ASSERT_EQ(a.status, RunStatus::kOk);
  ASSERT_TRUE(fs::exists(dir / "run" / "checkpoint.bin"));
  const auto first = gauge(dir / "run", "WG1");
  const auto first_t = h5::read_vector((dir / "run" / "result.h5").string(), "/gauges/WG1/time");
  CheckpointOptions resume;
  resume.resume = true;
  const RunOutcome b = run_scene(scene_to(1.2), {}, (dir / "run").string(), false, resume);
  ASSERT_EQ(b.status, RunStatus::kOk) << b.message;
  const auto ext = gauge(dir / "run", "WG1");
  const auto ext_t = h5::read_vector((dir / "run" / "result.h5").string(), "/gauges/WG1/time");
  ASSERT_GT(ext.size(), first.size());
  EXPECT_TRUE(std::vector<double>(ext.begin(), ext.begin() + first.size()) == first);
  EXPECT_NEAR(ext_t.back(), 1.2, 0.011);  // 100 Hz
  EXPECT_NEAR(first_t.back(), 0.6, 0.011);
  EXPECT_GE(b.cost.wall_s, a.cost.wall_s);
  fs::remove_all(dir);
}

std::string error_field(const std::function<void()>& f, const std::string& expect_in_message) {
  try {
    f();
  } catch (const InputError& e) {
    std::printf("%s\n", e.what());
    EXPECT_NE(std::string(e.what()).find(expect_in_message), std::string::npos) << e.what();
    return e.field();
  }
  return "(no error)";
}

TEST(Checkpoint, RefusesWhatDoesNotFit) {
  const fs::path dir = temp_dir("refuse");
  const auto scene = [&](const std::string& more) {
    std::vector<Override> o = {parse_override("solver.dx=0.04"), parse_override("solver.end_time=0.2")};
    if (!more.empty()) o.push_back(parse_override(more));
    return load_scene(waseda("waseda_2d.json"), o);
  };
  CheckpointOptions every, resume;
  every.every_s = 1e6;
  resume.resume = true;
  const std::string out = (dir / "run").string();
  // No checkpoint yet.
  EXPECT_EQ(error_field([&] { run_scene(scene(""), {}, out, false, resume); }, "no checkpoint"), "");
  ASSERT_EQ(run_scene(scene(""), {}, out, false, every).status, RunStatus::kOk);
  // Another scene: only solver.end_time may change.
  EXPECT_EQ(error_field([&] { run_scene(scene("reservoir.gate_height_m=0.12"), {}, out, false, resume); },
                        "another scene"),
            "scene");
  // The CUDA backend checkpoints as well (Checkpoint.CudaEmulation*); on a machine without a device it is refused
  // before anything runs.
  if (!cuda_available()) {
    SimulationOptions cuda;
    cuda.backend = Backend::kCuda;
    EXPECT_EQ(error_field([&] { run_scene(scene(""), cuda, out, false, every); }, "CUDA"), "cuda");
  }
  // A flipped byte, then a truncated file.
  const fs::path ck = dir / "run" / "checkpoint.bin";
  std::string bytes = test::read_text(ck.string());
  std::string flipped = bytes;
  flipped[flipped.size() / 2] ^= 0x5a;
  std::ofstream(ck, std::ios::binary | std::ios::trunc) << flipped;
  EXPECT_EQ(error_field([&] { run_scene(scene(""), {}, out, false, resume); }, "corrupt"), "");
  std::ofstream(ck, std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() - 100);
  EXPECT_EQ(error_field([&] { run_scene(scene(""), {}, out, false, resume); }, "truncated"), "");
  // The intact file resumes (a finished run at its own end time: nothing more to do).
  std::ofstream(ck, std::ios::binary | std::ios::trunc) << bytes;
  EXPECT_EQ(run_scene(scene(""), {}, out, false, resume).status, RunStatus::kOk);
  fs::remove_all(dir);
}

// Snapshots and checkpoints together: a finished run with snapshots, extended to a later end time from its
// checkpoint, keeps the snapshots it took (to the bit) and adds those of the extension, as many and at the same
// times as a run straight to the end. (Before this, a checkpointed run with snapshots was refused.)
TEST(Checkpoint, SnapshotsSurviveAnExtension) {
  const fs::path dir = temp_dir("snapshots");
  const std::string scene = (dir / "dam.json").string();
  std::ofstream(scene) << R"({"name": "dam", "dimension": 2,
    "domain": {"lo": [0.0, 0.0], "hi": [1.0, 0.5], "walls": "slip"},
    "solver": {"dx": 0.02, "ppc": 4, "end_time": 0.2},
    "water": [{"lo": [0.05, 0.05], "hi": [0.35, 0.25]}],
    "instruments": {"snapshot_rate_hz": 50}})";
  const std::string cmd = std::string(FLUME_EXE) + " run " + scene + " --threads 1 --quiet --out ";
  ASSERT_EQ(test::run_command(cmd + (dir / "straight").string()), 0);
  const std::string split = (dir / "split").string();
  ASSERT_EQ(test::run_command(cmd + split + " --set solver.end_time=0.1 --checkpoint-every 1"), 0);
  fs::copy_file(dir / "split" / "result.h5", dir / "first.h5");
  ASSERT_EQ(test::run_command(cmd + split + " --resume"), 0);

  auto times = [](const fs::path& file) {
    h5::Reader r(file.string());
    std::vector<double> t;
    for (const auto& name : r.list("/snapshots")) t.push_back(r.number_attribute("/snapshots/" + name, "time"));
    return t;
  };
  const std::vector<double> straight = times(dir / "straight" / "result.h5"), first = times(dir / "first.h5"),
                            extended = times(dir / "split" / "result.h5");
  ASSERT_EQ(straight.size(), 11u);  // 0, 0.02, ..., 0.2
  EXPECT_EQ(first.size(), 6u);
  ASSERT_EQ(extended.size(), straight.size());
  // The same sample times (the first part's last step was cut short to land on 0.1 s: within a step after it).
  for (std::size_t k = 0; k < straight.size(); ++k) EXPECT_NEAR(extended[k], straight[k], 2e-3) << k;
  // The first part's snapshots, kept to the bit (the one at 0.1 s taken again from the checkpointed state).
  h5::Reader a((dir / "first.h5").string()), b((dir / "split" / "result.h5").string());
  for (const auto& name : a.list("/snapshots"))
    EXPECT_TRUE(a.read_vector("/snapshots/" + name + "/xyz") == b.read_vector("/snapshots/" + name + "/xyz")) << name;
  // ParaView's sidecar lists every snapshot.
  std::ifstream xmf(dir / "split" / "result.xmf");
  const std::string text((std::istreambuf_iterator<char>(xmf)), std::istreambuf_iterator<char>());
  std::size_t grids = 0;
  for (std::size_t at = text.find("GridType=\"Uniform\""); at != std::string::npos;
       at = text.find("GridType=\"Uniform\"", at + 1))
    ++grids;
  EXPECT_EQ(grids, straight.size());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace flume
