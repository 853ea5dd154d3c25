// `flume run`, `flume bench`, `flume check`: their options, and what they run over run_scene().
#include "solver/commands.h"

#include <omp.h>
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common/command.h"
#include "common/errors.h"
#include "common/version.h"
#include "solver/cpu_kernels.h"
#include "solver/run.h"
#include "solver/run_output.h"
#include "solver/scene.h"
#include "solver/simulation.h"

namespace flume {
namespace {

// User + system CPU time of the process so far (every thread).
double process_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct Args {
  std::string scene;
  std::string out;
  std::vector<std::string> sets;
  SimulationOptions options;
  std::string backend = "cpu";
  long steps = 0;
  bool quiet = false;
  CheckpointOptions checkpoints;
  double flush_every_s = kDefaultFlushEvery_s;

  std::vector<Override> overrides() const {
    std::vector<Override> o;
    for (const auto& s : sets) o.push_back(parse_override(s));
    return o;
  }
  SimulationOptions simulation_options() const {
    SimulationOptions o = options;
    o.backend = backend == "cuda" ? Backend::kCuda : Backend::kCpu;
    return o;
  }
};

// The options every solver command takes: the scene, its overrides and the thread count.
std::shared_ptr<Args> add_scene_options(CLI::App& app) {
  auto a = std::make_shared<Args>();
  app.add_option("SCENE", a->scene, "the scene file (docs/scene.md)")->required();
  cli::add_set_option(app, a->sets, "override a scene field, e.g. --set solver.dx=0.01 (repeatable)");
  app.add_option("--threads", a->options.threads, "OpenMP threads (default: all)")->check(CLI::Range(1, 1024));
  app.add_option("--backend", a->backend, "cpu, or cuda when built with it")
      ->check(CLI::IsMember({"cpu", "cuda"}))
      ->default_str("cpu");
  return a;
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto a = add_scene_options(app);
  app.add_option("--out", a->out, "the run's folder: result.h5, run.json (docs/results.md)")->required();
  app.add_option("--checkpoint-every", a->checkpoints.every_s,
                 "write DIR/checkpoint.bin every S wall-clock seconds (docs/checkpoints.md)")
      ->check(CLI::Range(1.0, 1e7))
      ->type_name("S");
  app.add_flag("--resume", a->checkpoints.resume, "continue from DIR/checkpoint.bin");
  app.add_option("--flush-every", a->flush_every_s,
                 "flush the records to DIR/result.h5 every S wall-clock seconds, so a killed run keeps them "
                 "(docs/reliability.md)")
      ->check(CLI::Range(0.1, 1e7))
      ->type_name("S");
  app.add_flag("-q,--quiet", a->quiet, "no progress lines");
  cli::on_parse(app, [a] {
    const Scene scene = load_scene(a->scene, a->overrides());
    install_stop_handlers();
    const RunOutcome r = run_scene(scene, a->simulation_options(), a->out, !a->quiet, a->checkpoints, a->flush_every_s);
    std::fprintf(stderr, "flume run: %s: %s (%ld steps, %zu particles, %.1f s, %.3g particle-steps/s)\n",
                 status_name(r.status).c_str(), r.message.c_str(), r.cost.steps, r.cost.particles, r.cost.wall_s,
                 r.cost.particle_steps_per_s);
    if (r.status == RunStatus::kKilled) return 128 + stop_signal();
    return static_cast<int>(r.status == RunStatus::kOk ? kExitOk : kExitUnstable);
  });
}

void add_bench_command(CLI::App& app) {
  auto a = add_scene_options(app);
  app.add_option("--steps", a->steps, "time steps to time, after one warm-up step")
      ->required()
      ->check(CLI::Range(1L, 1000000000L));
  cli::on_parse(app, [a] {
    const Scene scene = load_scene(a->scene, a->overrides());
    const SimulationOptions options = a->simulation_options();
    auto sim = make_simulation(scene, options);
    // One warm-up step builds the block lists and touches the memory; the measured steps follow.
    sim->step();
    const long steps0 = sim->steps();
    const long pairs0 = sim->neighbour_interactions();
    const auto stages0 = sim->stage_seconds();
    const double cpu0 = process_cpu_s();
    const auto t0 = std::chrono::steady_clock::now();
    RunStatus st = RunStatus::kRunning;
    for (long i = 0; i < a->steps && st == RunStatus::kRunning; ++i) st = sim->step();
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double cpu = process_cpu_s() - cpu0;
    const long steps = sim->steps() - steps0;
    const long pairs = sim->neighbour_interactions() - pairs0;
    // Wall seconds per stage of the measured steps, and the memory traffic of a step (the solver's count of
    // what its loops read and write) per particle: with the rate, how far a run is from the memory bandwidth.
    nlohmann::json stages = nlohmann::json::object();
    const auto stages1 = sim->stage_seconds();
    for (size_t k = 0; k < stages1.size() && k < stages0.size(); ++k)
      stages[stages1[k].first] = stages1[k].second - stages0[k].second;
    const double bytes = sim->bytes_per_step();
    nlohmann::json j = {
        {"scene", scene.file},
        {"dimension", scene.dimension},
        {"precision", to_string(scene.solver.precision)},
        {"backend", options.backend == Backend::kCuda ? "cuda" : "cpu"},
        {"build", build_info::kind()},
        {"cpu_kernels", cpu_kernels_name(cpu_kernels())},
        {"threads", options.threads > 0 ? options.threads : omp_get_max_threads()},
        {"dx", scene.solver.dx},
        {"status", st == RunStatus::kUnstable ? "unstable" : "ok"},
        {"wall_s", wall},
        {"steps", steps},
        {"particles", sim->particle_count()},
        {"particle_steps_per_s", wall > 0 ? double(steps) * double(sim->particle_count()) / wall : 0},
        // CPU seconds of the measured steps (all threads): on a shared machine, where the wall
        // time counts the waits for a core, particle-steps per CPU-second compare builds.
        {"cpu_s", cpu},
        {"particle_steps_per_cpu_s", cpu > 0 ? double(steps) * double(sim->particle_count()) / cpu : 0},
        {"peak_rss_mb", peak_rss_mb()},
        {"method", to_string(scene.solver.method)},
        {"neighbour_interactions_per_s", wall > 0 ? double(pairs) / wall : 0},
        {"grid_mb", sim->grid_bytes() / 1048576.0},
        {"active_blocks", sim->active_blocks()},
        {"stage_s", stages},
        {"bytes_per_particle_step", sim->particle_count() ? bytes / double(sim->particle_count()) : 0},
        {"memory_gb_per_s", wall > 0 ? bytes * double(steps) / wall / 1e9 : 0}};
    std::printf("%s\n", j.dump(2).c_str());
    return st == RunStatus::kUnstable ? kExitUnstable : kExitOk;
  });
}

void add_check_command(CLI::App& app) {
  auto a = add_scene_options(app);
  cli::on_parse(app, [a] {
    const Scene s = load_scene(a->scene, a->overrides());
    std::printf("%s: scene '%s', %dD, %s, dx = %g m, ppc = %d, %s, end_time = %g s, %zu water boxes, %zu boundaries\n",
                s.file.c_str(), s.name.c_str(), s.dimension, to_string(s.solver.method), s.solver.dx, s.solver.ppc,
                to_string(s.solver.precision), s.solver.end_time, s.water.size(), s.boundaries.size());
    return kExitOk;
  });
}

}  // namespace flume
