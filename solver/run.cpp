#include "solver/run.h"

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "common/errors.h"
#include "flume_version.h"
#include "solver/checkpoint.h"
#include "solver/debris_coupling.h"
#include "solver/debris_metrics.h"
#include "solver/run_output.h"
#include "store/h5/run_file.h"

namespace flume {

double peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;  // Linux reports kilobytes
}

void write_record(h5::RunFile& file, const Scene& scene, const Record& record) {
  for (const auto& [name, ts] : record.gauges) {
    file.write_series("/gauges/" + name, "time", ts.time);
    file.write_series("/gauges/" + name, "elevation", ts.values);
  }
  for (const auto& [name, ts] : record.probes) {
    file.write_series("/probes/" + name, "time", ts.time);
    file.write_matrix("/probes/" + name, "velocity", ts.values, ts.components);
  }
  for (const auto& [name, ts] : record.loads) {
    file.write_series("/loads/" + name, "time", ts.time);
    file.write_matrix("/loads/" + name, "force", ts.values, ts.components);
  }
  // /sections/<name>: time (n), depth and velocity (n in 2D; n x bins in 3D, with the bin centres y).
  for (const auto& [name, sr] : record.sections) {
    const std::string g = "/sections/" + name;
    file.write_series(g, "time", sr.time);
    if (sr.y.empty()) {
      file.write_series(g, "depth", sr.depth);
      file.write_series(g, "velocity", sr.velocity);
    } else {
      file.write_series(g, "y", sr.y);
      file.write_matrix(g, "depth", sr.depth, sr.bins());
      file.write_matrix(g, "velocity", sr.velocity, sr.bins());
    }
    file.write_series(g, "z", sr.z);
    file.write_matrix(g, "velocity_profile", sr.profile, sr.z.size());  // (time x bins) x layers
    file.set_attribute(g, "x_m", sr.x_m);
    file.set_attribute(g, "floor_m", sr.floor_m);
    file.set_attribute(g, "bin_width_m", sr.bin_width_m);
    file.set_attribute(g, "dimension", scene.dimension);
    file.set_attribute(g, "units", "time s; y m (bin centres, bins bin_width_m wide); depth m (water volume per "
                                   "unit area, mass / density); velocity m/s (depth-averaged streamwise, 0 where dry); "
                                   "z m (layer centres, layers dx thick from floor_m); velocity_profile m/s "
                                   "(time x bins rows, z columns; a layer without water holds the bin's velocity)");
  }
  for (const auto& [name, v] : record.diagnostics) file.write_series("/diagnostics", name, v);
  file.set_attribute("/", "scene", scene.name);
  file.set_attribute("/", "scene_file", scene.file);
  file.set_attribute("/", "scene_json", scene.source_json);
  file.set_attribute("/", "dimension", scene.dimension);
  file.set_attribute("/", "dx", scene.solver.dx);
  file.set_attribute("/", "flume_version", std::string(FLUME_VERSION) + " (" + FLUME_GIT_VERSION + ")");
}

namespace {
// /debris/<name>/{solver,resampled}/<field>: the trajectories at the solver's rate and at the accelerometer
// rate, with the accelerometer force m a (debris_recorder.h).
void write_debris(h5::RunFile& file, const DebrisRecorder& rec) {
  auto flat3 = [](const std::vector<std::array<double, 3>>& a) {
    std::vector<double> v;
    v.reserve(3 * a.size());
    for (const auto& x : a) v.insert(v.end(), x.begin(), x.end());
    return v;
  };
  for (int b = 0; b < rec.body_count(); ++b)
    for (int which = 0; which < 2; ++which) {
      const DebrisSeries& s = which == 0 ? rec.solver_rate(b) : rec.resampled(b);
      const std::string g = "/debris/" + rec.name(b) + (which == 0 ? "/solver" : "/resampled");
      file.write_series(g, "time", s.time);
      file.write_matrix(g, "position", flat3(s.position), 3);
      std::vector<double> q;
      for (const auto& x : s.orientation) q.insert(q.end(), x.begin(), x.end());
      file.write_matrix(g, "orientation", q, 4);
      file.write_matrix(g, "velocity", flat3(s.velocity), 3);
      file.write_matrix(g, "angular_velocity", flat3(s.angular_velocity), 3);
      file.write_matrix(g, "acceleration", flat3(s.acceleration), 3);
      file.write_matrix(g, "force", flat3(s.force), 3);
      file.write_matrix(g, "specific_force_body", flat3(s.specific_force_body), 3);
    }
}

void add_snapshot(h5::RunFile& file, const Simulation& sim) {
  std::vector<double> xyz, vel, p;
  sim.particle_positions(xyz);
  sim.particle_velocities(vel);
  sim.particle_pressures(p);
  const size_t n = sim.particle_count();
  std::vector<float> fx(xyz.begin(), xyz.end()), fv(vel.begin(), vel.end()), fp(p.begin(), p.end());
  file.add_snapshot(sim.time(), n, fx.data(), {{"pressure", fp.data()}}, {{"velocity", fv.data()}});
}
}  // namespace

RunOutcome run_scene(const Scene& scene, const SimulationOptions& options, const std::string& out_dir,
                     bool progress, const CheckpointOptions& checkpoints) {
  namespace fs = std::filesystem;
  const bool checkpointing = checkpoints.every_s > 0 || checkpoints.resume;
  if (checkpointing && scene.instruments.snapshot_rate_hz > 0)
    throw InputError(
        scene.file, "instruments.snapshot_rate_hz",
        "a checkpointed or resumed run cannot keep snapshots yet (those before the checkpoint would "
        "be lost): set it to 0 or run without --checkpoint-every/--resume");
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) throw InputError(out_dir, "--out", "cannot create the output directory: " + ec.message());
  auto sim = make_simulation(scene, options);
  const std::string ckpt_path = (fs::path(out_dir) / "checkpoint.bin").string();
  const std::string scene_key = checkpointing ? checkpoint_scene_key(scene.source_json) : std::string();
  double wall_before = 0;  // wall time of the segments before a resume
  if (checkpoints.resume) {
    StateArchive ar(read_checkpoint_file(ckpt_path, scene_key), ckpt_path);
    ar.section("run");
    ar(wall_before);
    sim->checkpoint(ar);
    ar.finish();
    if (progress)
      std::fprintf(stderr, "resumed from %s at t = %.3f s, step %ld\n", ckpt_path.c_str(), sim->time(), sim->steps());
  }
  h5::RunFile file((fs::path(out_dir) / "result.h5").string());
  file.set_attribute("/", "status", "running");

  const double snap_period = scene.instruments.snapshot_rate_hz > 0 ? 1.0 / scene.instruments.snapshot_rate_hz : 0;
  double next_snap = 0;
  double next_report = 0;
  if (checkpoints.resume)  // the next tenth of the run after the checkpoint
    while (next_report <= sim->time()) next_report += scene.solver.end_time / 10;
  const auto t0 = std::chrono::steady_clock::now();
  auto last_ckpt = t0;
  const auto save = [&] {
    StateArchive ar;
    ar.section("run");
    double wall = wall_before + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ar(wall);
    sim->checkpoint(ar);
    // A checkpoint that cannot be written (disk full) costs the run nothing but its protection: say so and run on
    // (the previous checkpoint, if any, is intact).
    try {
      write_checkpoint_file(ckpt_path, scene_key, ar.bytes());
    } catch (const InputError& e) {
      std::fprintf(stderr, "flume run: warning: %s (at t = %.3f s; the run goes on)\n", e.what(), sim->time());
    }
    last_ckpt = std::chrono::steady_clock::now();
  };
  RunStatus status = RunStatus::kRunning;
  while (true) {
    if (snap_period > 0 && sim->time() + 1e-12 >= next_snap) {
      add_snapshot(file, *sim);
      while (next_snap <= sim->time() + 1e-12) next_snap += snap_period;
    }
    if (status != RunStatus::kRunning) break;
    status = sim->step();
    if (progress && sim->time() >= next_report) {
      std::fprintf(stderr, "t = %.3f s / %.3f s, step %ld, dt = %.3g s\n", sim->time(), scene.solver.end_time,
                   sim->steps(), sim->last_dt());
      while (next_report <= sim->time()) next_report += scene.solver.end_time / 10;
    }
    if (checkpoints.every_s > 0 &&
        (status == RunStatus::kOk ||
         (status == RunStatus::kRunning &&
          std::chrono::duration<double>(std::chrono::steady_clock::now() - last_ckpt).count() >= checkpoints.every_s)))
      save();
  }
  RunOutcome out;
  out.status = status;
  out.message = status == RunStatus::kOk ? "completed" : sim->message();
  out.cost.wall_s = wall_before + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.cost.steps = sim->steps();
  out.cost.particles = sim->particle_count();
  out.cost.particle_steps_per_s =
      out.cost.wall_s > 0 ? double(out.cost.steps) * double(out.cost.particles) / out.cost.wall_s : 0;
  out.cost.peak_rss_mb = peak_rss_mb();
  out.metrics = compute_metrics(scene, sim->record());
  write_record(file, scene, sim->record());
  if (DebrisCoupling* debris = sim->debris()) {
    debris->finish();
    write_debris(file, debris->recorder());
    // Touching a column: within a tenth of a cell or 2 mm, whichever is larger (the grid resolves no finer).
    for (const auto& [k, v] : debris_metrics(scene, debris->recorder(), std::max(0.002, 0.1 * scene.solver.dx)))
      out.metrics[k] = v;
  }
  file.set_attribute("/", "status", status_name(status));
  file.set_attribute("/", "message", out.message);
  file.finalize();
  write_run_json((fs::path(out_dir) / "run.json").string(), status, out.message, out.metrics, out.cost, scene);
  return out;
}

}  // namespace flume
