#include "solver/run.h"

#include <sys/resource.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>

#include "common/errors.h"
#include "common/version.h"
#include "solver/checkpoint.h"
#include "solver/debris_coupling.h"
#include "solver/debris_metrics.h"
#include "solver/progress.h"
#include "solver/run_output.h"
#include "store/h5/run_file.h"

namespace flume {

namespace {
volatile std::sig_atomic_t g_stop_signal = 0;
void on_run_stop_signal(int sig) { g_stop_signal = sig; }
std::string killed_message(int sig, double t) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "killed by signal %d (%s) at t = %.4g s, before the end time", sig,
                sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "a signal", t);
  return buf;
}
}  // namespace

void install_stop_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_run_stop_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);
}

int stop_signal() { return g_stop_signal; }

double peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;  // Linux reports kilobytes
}

void write_record(h5::RunFile& file, const Scene& scene, const Record& record) {
  for (const auto& [name, ts] : record.gauges) {
    file.append_series("/gauges/" + name, "time", ts.time);
    file.append_series("/gauges/" + name, "elevation", ts.values);
  }
  for (const auto& [name, ts] : record.probes) {
    file.append_series("/probes/" + name, "time", ts.time);
    file.append_matrix("/probes/" + name, "velocity", ts.values, ts.components);
  }
  for (const auto& [name, ts] : record.loads) {
    file.append_series("/loads/" + name, "time", ts.time);
    file.append_matrix("/loads/" + name, "force", ts.values, ts.components);
  }
  // /pressure_probes/<name>: time (n), pressure (n, Pa: each sample the mean over the interval before it).
  for (const auto& [name, ts] : record.pressures) {
    const std::string g = "/pressure_probes/" + name;
    file.append_series(g, "time", ts.time);
    file.append_series(g, "pressure", ts.values);
    for (const auto& p : scene.instruments.pressure_probes)
      if (p.name == name)
        for (int d = 0; d < scene.dimension; ++d) {
          const std::string axis = d == scene.dimension - 1 ? "z" : (d == 0 ? "x" : "y");
          file.set_attribute(g, "position_" + axis, p.position[d]);
          file.set_attribute(g, "normal_" + axis, p.normal[d]);
        }
    file.set_attribute(g, "units", "time s; pressure Pa (the water's on the face, the mean over each sampling "
                                   "interval; 0 when dry)");
  }
  // /sections/<name>: time (n), depth and velocity (n in 2D; n x bins in 3D, with the bin centres y).
  for (const auto& [name, sr] : record.sections) {
    const std::string g = "/sections/" + name;
    file.append_series(g, "time", sr.time);
    if (sr.y.empty()) {
      file.append_series(g, "depth", sr.depth);
      file.append_series(g, "velocity", sr.velocity);
    } else {
      file.append_series(g, "y", sr.y);
      file.append_matrix(g, "depth", sr.depth, sr.bins());
      file.append_matrix(g, "velocity", sr.velocity, sr.bins());
    }
    file.append_series(g, "z", sr.z);
    file.append_matrix(g, "velocity_profile", sr.profile, sr.z.size());  // (time x bins) x layers
    file.set_attribute(g, "x_m", sr.x_m);
    file.set_attribute(g, "floor_m", sr.floor_m);
    file.set_attribute(g, "bin_width_m", sr.bin_width_m);
    file.set_attribute(g, "dimension", scene.dimension);
    file.set_attribute(g, "units", "time s; y m (bin centres, bins bin_width_m wide); depth m (water volume per "
                                   "unit area, mass / density); velocity m/s (depth-averaged streamwise, 0 where dry); "
                                   "z m (layer centres, layers dx thick from floor_m); velocity_profile m/s "
                                   "(time x bins rows, z columns; a layer without water holds the bin's velocity)");
  }
  for (const auto& [name, v] : record.diagnostics) file.append_series("/diagnostics", name, v);
  file.set_attribute("/", "scene", scene.name);
  file.set_attribute("/", "scene_file", scene.file);
  file.set_attribute("/", "scene_json", scene.source_json);
  file.set_attribute("/", "dimension", scene.dimension);
  file.set_attribute("/", "method", to_string(scene.solver.method));
  file.set_attribute("/", "dx", scene.solver.dx);
  file.set_attribute("/", "flume_version", build_info::version_and_commit());
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

// The boxes' poses for ParaView (result.xmf's `debris` grid): one frame per resampled sample, each body a
// hexahedron of its size about its centre of mass, rotated by its orientation.
void write_debris_frames(h5::RunFile& file, const Scene& scene, const DebrisRecorder& rec) {
  const int bodies = rec.body_count();
  if (bodies == 0) return;
  std::vector<Eigen::Vector3d> half(static_cast<std::size_t>(bodies), Eigen::Vector3d::Zero());
  std::size_t frames = rec.resampled(0).size();
  for (int b = 0; b < bodies; ++b) {
    for (const DebrisBody& body : scene.debris.bodies)
      if (body.name == rec.name(b)) half[static_cast<std::size_t>(b)] = 0.5 * Eigen::Vector3d(body.size.data());
    frames = std::min(frames, rec.resampled(b).size());
  }
  static const double kCorner[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                       {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
  std::vector<float> corners(static_cast<std::size_t>(bodies) * 24);
  for (std::size_t i = 0; i < frames; ++i) {
    for (int b = 0; b < bodies; ++b) {
      const DebrisSeries& s = rec.resampled(b);
      const auto& q = s.orientation[i];
      const Eigen::Quaterniond rot(q[0], q[1], q[2], q[3]);
      const Eigen::Vector3d centre(s.position[i].data());
      for (int c = 0; c < 8; ++c) {
        const Eigen::Vector3d local(kCorner[c][0], kCorner[c][1], kCorner[c][2]);
        const Eigen::Vector3d p = centre + rot * local.cwiseProduct(half[static_cast<std::size_t>(b)]);
        for (int k = 0; k < 3; ++k) corners[static_cast<std::size_t>((b * 8 + c) * 3 + k)] = static_cast<float>(p[k]);
      }
    }
    file.add_box_frame(rec.resampled(0).time[i], static_cast<std::size_t>(bodies), corners.data());
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
                     bool progress, const CheckpointOptions& checkpoints, double flush_every_s) {
  namespace fs = std::filesystem;
  const bool checkpointing = checkpoints.every_s > 0 || checkpoints.resume;
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
  // A resumed run keeps the snapshots the stopped one took before its checkpoint (in result.h5.part).
  const std::string h5_path = (fs::path(out_dir) / "result.h5").string();
  h5::RunFile file = checkpoints.resume ? h5::RunFile(h5_path, sim->time()) : h5::RunFile(h5_path);
  file.set_attribute("/", "status", "running");
  // Between two flushes nothing is written to the file but snapshots, each flushed too: a run killed outright
  // leaves the file as of its last flush, which every HDF5 reader opens (docs/reliability.md).
  const auto flush_record = [&] {
    write_record(file, scene, sim->record());
    file.set_attribute("/", "flushed_at_s", sim->time());
    file.flush();
  };
  flush_record();

  const double snap_period = scene.instruments.snapshot_rate_hz > 0 ? 1.0 / scene.instruments.snapshot_rate_hz : 0;
  double next_snap = 0;
  for (const double t : file.snapshot_times())  // the times a run without a stop would have had next
    while (next_snap <= t + 1e-12) next_snap += snap_period;
  if (checkpoints.resume && progress && snap_period > 0)
    std::fprintf(stderr, "kept %zu snapshot(s) taken before the checkpoint\n", file.snapshot_count());
  Progress report(scene.solver.end_time, sim->time(), sim->particle_count());
  const auto t0 = std::chrono::steady_clock::now();
  auto last_ckpt = t0, last_flush = t0;
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
    if (snap_period > 0 && sim->time() + 1e-12 >= next_snap && status != RunStatus::kKilled) {
      add_snapshot(file, *sim);
      file.flush();
      while (next_snap <= sim->time() + 1e-12) next_snap += snap_period;
    }
    if (status != RunStatus::kRunning) break;
    status = sim->step();
    if (status == RunStatus::kRunning && stop_signal() != 0) status = RunStatus::kKilled;
    if (status == RunStatus::kRunning &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - last_flush).count() >= flush_every_s) {
      flush_record();
      last_flush = std::chrono::steady_clock::now();
    }
    if (progress) report.step(sim->time(), sim->steps(), sim->last_dt());
    if (checkpoints.every_s > 0 &&
        (status == RunStatus::kOk || status == RunStatus::kKilled ||
         (status == RunStatus::kRunning &&
          std::chrono::duration<double>(std::chrono::steady_clock::now() - last_ckpt).count() >= checkpoints.every_s)))
      save();
  }
  RunOutcome out;
  out.status = status;
  out.message = status == RunStatus::kOk       ? "completed"
                : status == RunStatus::kKilled ? killed_message(stop_signal(), sim->time())
                                               : sim->message();
  out.cost.wall_s = wall_before + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.cost.steps = sim->steps();
  out.cost.particles = sim->particle_count();
  out.cost.particle_steps_per_s =
      out.cost.wall_s > 0 ? double(out.cost.steps) * double(out.cost.particles) / out.cost.wall_s : 0;
  out.cost.peak_rss_mb = peak_rss_mb();
  out.metrics = compute_metrics(scene, sim->record());
  flush_record();
  if (DebrisCoupling* debris = sim->debris()) {
    debris->finish();
    write_debris(file, debris->recorder());
    write_debris_frames(file, scene, debris->recorder());
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
